#!/usr/bin/env bash
# Kill a run mid-way (SIGKILL: no chance to clean up), then `--resume`: the results.csv must be
# byte-identical to an uninterrupted run, and the points the journal had finished must not be
# computed again. Usage: resume.sh CHATTERLAB WORK_DIR
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2
rm -rf "$work" && mkdir -p "$work"
study=$CLI_TESTS_DIR/studies/resume_grid.toml
points=300

expect_exit 0 "$work/full" "$bin" run "$study" --out "$work/full" --threads 2

cut=$work/cut
"$bin" run "$study" --out "$cut" --threads 1 >"$work/cut.out" 2>"$work/cut.err" &
pid=$!
for _ in $(seq 1 1200); do  # up to 60 s for the first 10 points
  [ "$(journal_records "$cut")" -ge 10 ] && break
  kill -0 "$pid" 2>/dev/null || break
  sleep 0.05
done
kill -KILL "$pid" 2>/dev/null
wait "$pid" 2>/dev/null

if [ -e "$cut/results.csv" ]; then
  fail "the run finished before it could be interrupted (make resume_grid.toml larger)"
  finish
fi
grep -q '"state": "running' "$cut/meta.json" || fail "meta.json of the killed run does not say running"
done_before=$(journal_records "$cut")
[ "$done_before" -ge 10 ] && [ "$done_before" -lt "$points" ] ||
  fail "journal of the killed run has $done_before points (expected 10..$((points - 1)))"
# A line cut in the middle of a write, as a kill during write(2) would leave it.
journal=$(ls "$cut"/journal/points-*.jsonl | head -n 1)
printf '{"i":299,"out":[-1.5e-3,12' >>"$journal"

expect_exit 0 "$work/resume" "$bin" run "$study" --out "$cut" --resume --threads 2
cmp "$work/full/results.csv" "$cut/results.csv" || fail "resumed results.csv differs from an uninterrupted run"
[ "$(json_number "$cut/meta.json" points_resumed)" = "$done_before" ] ||
  fail "meta.json: points_resumed = $(json_number "$cut/meta.json" points_resumed), the journal had $done_before"
[ "$(json_number "$cut/meta.json" points_computed)" = "$((points - done_before))" ] ||
  fail "meta.json: points_computed = $(json_number "$cut/meta.json" points_computed), expected $((points - done_before))"
[ "$(json_number "$cut/meta.json" truncated)" -ge 1 ] || fail "meta.json: the cut journal line was not noticed"
grep -q "($done_before taken over from the earlier run)" "$work/resume.out" ||
  fail "summary does not report the resumed points: $(cat "$work/resume.out")"
grep -q '"state": "complete"' "$cut/meta.json" || fail "meta.json not complete after --resume"
finish
