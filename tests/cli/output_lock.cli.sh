#!/usr/bin/env bash
# One run at a time per output directory: a run holds an OS lock (flock) on its --out; a second
# run into it, started later or at the same instant, with the same study or another, with or
# without --resume, exits 2 naming the holder's PID and host and changes nothing. The lock dies
# with its holder (kill -9): the directory can be resumed at once.
# Usage: output_lock.cli.sh CHATTERLAB WORK_DIR SOURCE_DIR
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2
rm -rf "$work" && mkdir -p "$work"
studies=$CLI_TESTS_DIR/studies
study=$studies/resume_grid.toml
other=$studies/plunge_2d.toml

# Everything in a directory, with checksums: "changes nothing" is compared on this.
fingerprint_dir() { (cd "$1" && find . -type f -print0 | sort -z | xargs -0 sha256sum); }

expect_exit 0 "$work/ref" "$bin" run "$study" --out "$work/ref" --threads 1

# Staggered: A runs (held still with SIGSTOP once it has journaled points), B comes later.
out=$work/shared
"$bin" run "$study" --out "$out" --threads 1 >"$work/a.out" 2>"$work/a.err" &
a=$!
started() { [ "$(journal_records "$out")" -ge 5 ]; }
wait_for 60 started || fail "run A did not start"
kill -STOP "$a"
fingerprint_dir "$out" >"$work/before"
host=$(hostname)
for case in "other:$other:" "same:$study:" "resume:$study:--resume"; do
  IFS=: read -r name file flag <<<"$case"
  expect_exit 2 "$work/b_$name" "$bin" run "$file" --out "$out" $flag
  grep -qF "output directory $out is in use by another chatterlab run (PID $a on host $host, running $study since" \
    "$work/b_$name.err" || fail "B ($name) does not name A: $(cat "$work/b_$name.err")"
  grep -q "nothing was changed" "$work/b_$name.err" || fail "B ($name): $(cat "$work/b_$name.err")"
  grep -q "points: " "$work/b_$name.out" && fail "B ($name) printed a summary: $(cat "$work/b_$name.out")"
done
fingerprint_dir "$out" >"$work/after"
cmp -s "$work/before" "$work/after" || fail "refused runs changed the directory: $(diff "$work/before" "$work/after")"
kill -CONT "$a"
wait "$a" || fail "run A failed after the refused runs"
cmp "$work/ref/results.csv" "$out/results.csv" || fail "run A's results.csv is not the undisturbed one"

# The lock dies with its holder: kill -9 mid-run, then --resume at once.
"$bin" run "$study" --out "$work/killed" --threads 1 >/dev/null 2>&1 &
k=$!
killed_started() { [ "$(journal_records "$work/killed")" -ge 5 ]; }
wait_for 60 killed_started || fail "the run to kill did not start"
kill -KILL "$k"
wait "$k" 2>/dev/null
expect_exit 0 "$work/after_kill" "$bin" run "$study" --out "$work/killed" --resume --threads 2
cmp "$work/ref/results.csv" "$work/killed/results.csv" || fail "resumed after kill -9: results differ"

# Simultaneous: two runs started at the same instant into a new directory, ten times. One may
# finish before the other starts (then both succeed, one after the other); otherwise the loser
# must name the winner, never call the directory foreign. The end is always a complete run.
for i in 1 2 3 4 5 6 7 8 9 10; do
  dir=$work/race$i
  "$bin" run "$study" --out "$dir" --threads 1 >"$work/race$i.1.out" 2>"$work/race$i.1.err" &
  p1=$!
  "$bin" run "$other" --out "$dir" --threads 1 >"$work/race$i.2.out" 2>"$work/race$i.2.err" &
  p2=$!
  wait "$p1"
  r1=$?
  wait "$p2"
  r2=$?
  for n in 1 2; do
    rc=$([ "$n" = 1 ] && echo "$r1" || echo "$r2")
    if [ "$rc" = 2 ]; then
      grep -q "is in use by another chatterlab run (PID [0-9]* on host $host" "$work/race$i.$n.err" ||
        fail "race $i: run $n refused without naming the holder: $(cat "$work/race$i.$n.err")"
    elif [ "$rc" != 0 ]; then
      fail "race $i: run $n exited $rc: $(cat "$work/race$i.$n.err")"
    fi
    grep -q "not written by chatterlab" "$work/race$i.$n.err" && fail "race $i: run $n called the directory foreign"
  done
  [ "$r1" = 0 ] || [ "$r2" = 0 ] || fail "race $i: neither run succeeded"
  grep -q '"state": "complete"' "$dir/meta.json" || fail "race $i: meta.json is not complete"
  no_partial_files "$dir"
done
finish
