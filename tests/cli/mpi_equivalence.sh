#!/usr/bin/env bash
# `mpirun -np 2 chatterlab run` writes a results.csv byte-identical to a single-process run (and
# exits the same way), whichever rank computes which point (ranks claim blocks of points from a
# shared counter, runner/mpi_scheduler.hpp). Usage: mpi_equivalence.sh CHATTERLAB MPIEXEC WORK_DIR
source "$(dirname "$0")/lib.sh"
bin=$1 mpiexec=$2 work=$3
rm -rf "$work" && mkdir -p "$work"

# cost_varying: the cost per point grows 30x along the last axis, so the ranks take blocks of
# different sizes in an order that depends on timing; the bytes must not.
for study in plunge_2d dde_2d budget_failure cost_varying; do
  file=$CLI_TESTS_DIR/studies/$study.toml
  want=0
  [ "$study" = budget_failure ] && want=1
  expect_exit "$want" "$work/$study.single" "$bin" run "$file" --out "$work/$study.single" --threads 2
  expect_exit "$want" "$work/$study.mpi" "$mpiexec" --oversubscribe -np 2 "$bin" run "$file" \
    --out "$work/$study.mpi" --threads 1
  cmp "$work/$study.single/results.csv" "$work/$study.mpi/results.csv" ||
    fail "$study: results.csv differs between 1 process and 2 MPI ranks"
  # Both ranks really took part (an MPI that silently failed to start would run two
  # independent single processes into the same directory).
  [ "$(json_number "$work/$study.mpi/meta.json" ranks)" = 2 ] || fail "$study: meta.json does not report 2 ranks"
  [ -s "$work/$study.mpi/journal/points-1-1.jsonl" ] || fail "$study: rank 1 wrote no journal"
  # meta.json accounts for each rank's share (timings.ranks), and the shares add up.
  [ "$(grep -c '"loop_s"' "$work/$study.mpi/meta.json")" = 2 ] || fail "$study: meta.json timings.ranks lacks a rank"
  shares=$(awk '/"ranks": \[/ { in_ranks = 1 } in_ranks && /"points": / { gsub(/[^0-9]/, ""); s += $0 }
                in_ranks && /^    \]/ { in_ranks = 0 } END { print s }' "$work/$study.mpi/meta.json")
  [ "$shares" = "$(json_number "$work/$study.mpi/meta.json" points_computed)" ] ||
    fail "$study: the ranks' points ($shares) do not add up to points_computed"
  points=$(json_number "$work/$study.mpi/meta.json" points)
  [ "$(json_number "$work/$study.mpi/meta.json" points_computed)" = "$points" ] ||
    fail "$study: not every point computed exactly once"
  # Worker processes under every rank (--isolate): still the same bytes.
  expect_exit "$want" "$work/$study.mpi_isolated" "$mpiexec" --oversubscribe -np 2 "$bin" run "$file" \
    --out "$work/$study.mpi_isolated" --threads 1 --isolate
  cmp "$work/$study.single/results.csv" "$work/$study.mpi_isolated/results.csv" ||
    fail "$study: results.csv differs between 1 process and 2 MPI ranks with --isolate"
  # Only rank 0 prints the summary.
  [ "$(grep -c "^[0-9]* points: " "$work/$study.mpi.out")" = 1 ] || fail "$study: summary printed $(grep -c "^[0-9]* points: " "$work/$study.mpi.out") times"
done
finish
