#!/usr/bin/env bash
# [output] format = "hdf5" from the command line (docs/studies.md, "[output]"): results.h5 instead
# of results.csv, plots as for CSV, the journal removed once the run is complete and a --resume
# of it recomputing nothing; h5dump/h5ls (Debian's hdf5-tools, when installed) read the file and
# its values equal results.csv's; shards of an hdf5 study merge into the single run's results.h5;
# a bad [output] value is exit 2 naming file, line, key and value, with nothing written.
# Usage: hdf5_output.cli.sh CHATTERLAB WORK_DIR SOURCE_DIR
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2 src=$3
rm -rf "$work" && mkdir -p "$work"
{ cat "$src/tests/cli/studies/dde_2d.toml"; printf '\n[output]\nformat = "hdf5"\n'; } >"$work/h5.toml"
{ cat "$src/tests/cli/studies/dde_2d.toml"; printf '\n[output]\nformat = "hdf"\n'; } >"$work/bad.toml"

expect_exit 0 "$work/csv" "$bin" run "$src/tests/cli/studies/dde_2d.toml" --out "$work/csv" --threads 2
expect_exit 0 "$work/h5" "$bin" run "$work/h5.toml" --out "$work/h5" --threads 2
grep -qF "20 points: 20 ok, 0 failed; results in $work/h5/results.h5" "$work/h5.out" ||
  fail "summary does not name results.h5: $(cat "$work/h5.out")"
[ -s "$work/h5/results.h5" ] || fail "no results.h5"
[ -e "$work/h5/results.csv" ] && fail "an hdf5 run wrote results.csv"
[ -e "$work/h5/journal" ] && fail "the journal of a complete hdf5 run was kept"
grep -q '"journal": "removed' "$work/h5/meta.json" || fail "meta.json does not say the journal was removed"
[ "$(cd "$work/csv" && ls ./*.png ./*.svg)" = "$(cd "$work/h5" && ls ./*.png ./*.svg)" ] ||
  fail "the hdf5 run's plots differ from the csv run's"
ls "$work/h5"/*.tmp* >/dev/null 2>&1 && fail "temporary files left behind"

# --resume of the complete run takes every point from results.h5.
expect_exit 0 "$work/again" "$bin" run "$work/h5.toml" --out "$work/h5" --threads 2 --resume
grep -q "(20 taken over from the earlier run)" "$work/again.out" || fail "resume: $(cat "$work/again.out")"
[ "$(json_number "$work/h5/meta.json" points_computed)" = 0 ] || fail "resume of a complete hdf5 run recomputed points"

# Shards of an hdf5 study merge into the single run's numbers.
for i in 1 2; do
  expect_exit 0 "$work/s$i" "$bin" run "$work/h5.toml" --out "$work/s$i" --threads 1 --shard "$i/2"
done
expect_exit 0 "$work/merged" "$bin" merge "$work/merged" "$work/s1" "$work/s2"
[ -s "$work/merged/results.h5" ] || fail "the merge wrote no results.h5"

if command -v h5dump >/dev/null && command -v h5ls >/dev/null; then
  h5ls -r "$work/h5/results.h5" >"$work/h5ls.txt" || fail "h5ls cannot read results.h5"
  for name in "/growth_rate_per_s +Dataset \{4, 5\}" "/status +Dataset \{4, 5\}" \
              "/grid/model.delayed.0.delay_s +Dataset \{5\}"; do
    grep -qE "^$name" "$work/h5ls.txt" || fail "h5ls lacks '$name': $(cat "$work/h5ls.txt")"
  done
  # Every number of a column, printed with 17 digits, equals the CSV's (awk reads both as doubles).
  for column in growth_rate_per_s chatter_frequency_hz certified_real_part_per_s; do
    h5dump -m '%.17g' -w 0 -y -d "/$column" "$work/h5/results.h5" |
      awk '/DATA \{/ && !seen {on = seen = 1; next} on && /\}/ {on = 0} on' | tr ',' '\n' |
      awk 'NF {printf "%.17g\n", $1}' \
      >"$work/$column.h5.txt"
    csv_column "$work/csv/results.csv" "$column" | awk '{printf "%.17g\n", $1}' >"$work/$column.csv.txt"
    [ "$(wc -l <"$work/$column.csv.txt")" = 20 ] || fail "$column: not 20 CSV values"
    cmp -s "$work/$column.h5.txt" "$work/$column.csv.txt" ||
      fail "$column: h5dump's values differ from results.csv's: $(paste "$work/$column.h5.txt" "$work/$column.csv.txt" | head -3)"
    h5dump -m '%.17g' -w 0 -y -d "/$column" "$work/merged/results.h5" |
      awk '/DATA \{/ && !seen {on = seen = 1; next} on && /\}/ {on = 0} on' | tr ',' '\n' |
      awk 'NF {printf "%.17g\n", $1}' \
      >"$work/$column.merged.txt"
    cmp -s "$work/$column.h5.txt" "$work/$column.merged.txt" || fail "$column: merged shards differ from the single run"
  done
  # Two MPI ranks (rank 0 writes results.h5, the other rank's points arrive at the end): the
  # same datasets as one process.
  if command -v mpirun >/dev/null; then
    export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
    expect_exit 0 "$work/mpi" mpirun --oversubscribe -np 2 "$bin" run "$work/h5.toml" --out "$work/mpi" --threads 1
    for dataset in growth_rate_per_s stable certificate status; do
      cmp -s <(h5dump -m '%.17g' -d "/$dataset" "$work/mpi/results.h5" | sed 1d) \
             <(h5dump -m '%.17g' -d "/$dataset" "$work/h5/results.h5" | sed 1d) ||
        fail "$dataset: 2 MPI ranks wrote other values than one process"
    done
  fi
  h5dump -a /study_text "$work/h5/results.h5" | grep -q 'DDE-BIFTOOL test' ||
    fail "results.h5 lacks the study file text"
else
  echo "h5dump/h5ls not installed (Debian: hdf5-tools): the checks with them are skipped"
fi

expect_exit 2 "$work/bad" "$bin" run "$work/bad.toml" --out "$work/bad_out"
grep -qF "$work/bad.toml:21: output.format = \"hdf\": not one of: auto, csv, hdf5" "$work/bad.err" ||
  fail "bad [output] message: $(cat "$work/bad.err")"
[ -e "$work/bad_out" ] && fail "a rejected study wrote $work/bad_out"
finish
