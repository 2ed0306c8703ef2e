#!/usr/bin/env bash
# The journal is on disk within its flush interval (0.1 s) whatever the other points do: with one
# point that never ends and no time limit, every other point's record is in the journal while
# the run hangs; killed then, the run resumes with all of them.
# Usage: journal_flush.sh CHATTERLAB WORK_DIR MISBEHAVING_PLUGIN THROWING_ENTRY_PLUGIN
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2 plugin=$3
rm -rf "$work" && mkdir -p "$work"

# Point 0 hangs; the 44 after it are ok.
study=$work/hang.toml
behaviours='["hang"'
for _ in $(seq 44); do behaviours+=', "ok"'; done
DECAYS='[1]' misbehaving_study "$study" "$plugin" "$behaviours]"
out=$work/out
"$bin" run "$study" --out "$out" --threads 2 >"$work/run.out" 2>"$work/run.err" &
pid=$!
all_others() { [ "$(journal_records "$out")" -ge 44 ]; }
# Each ok point takes well under a millisecond: all 44 are done at once; the journal must have
# them a tenth of a second later (20 s is the allowance for a loaded machine).
wait_for 20 all_others || fail "after 20 s the journal holds $(journal_records "$out") of the 44 finished points"
kill -0 "$pid" 2>/dev/null || fail "the run ended although point 0 never ends"
[ ! -e "$out/results.csv" ] || fail "results.csv written while a point still runs"
grep -q '"i":0,' "$out"/journal/points-*.jsonl && fail "the hanging point has a journal record"
kill -KILL "$pid" 2>/dev/null
wait "$pid" 2>/dev/null

# Resumed with a time limit: the 44 are taken over, the hanging point times out.
expect_exit 1 "$work/resume" timeout 120 "$bin" run "$study" --out "$out" --resume --point-timeout 1
[ "$(json_number "$out/meta.json" points_resumed)" = 44 ] || fail "resume took $(json_number "$out/meta.json" points_resumed) points over, not 44"
[ "$(json_number "$out/meta.json" points_timed_out)" = 1 ] || fail "the hanging point did not time out"
finish
