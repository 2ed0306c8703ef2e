#!/usr/bin/env bash
# The exit-code table (docs/studies.md, "Exit codes"), one meaning each:
#   0 every point ok; 1 some points failed or timed out; 2 rejected, nothing run and nothing
#   written (or stopped because an input file changed); 3 an output could not be written,
#   meta.json says so and no partial file is left.
# (Time-outs: point_timeout.sh; an input changing mid-run: input_files.cli.sh; a full disk:
# disk_full.sh; a plugin calling exit(): isolate.sh.)
# Usage: exit_codes.cli.sh CHATTERLAB WORK_DIR SOURCE_DIR
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2
rm -rf "$work" && mkdir -p "$work"
studies=$CLI_TESTS_DIR/studies

# 0
expect_exit 0 "$work/ok" "$bin" run "$studies/dde_1d.toml" --out "$work/ok"
grep -q '"state": "complete"' "$work/ok/meta.json" || fail "0: meta.json not complete"
# 1
expect_exit 1 "$work/failed" "$bin" run "$studies/budget_failure.toml" --out "$work/failed"
grep -q '"state": "complete"' "$work/failed/meta.json" || fail "1: meta.json not complete"
# 2: bad input, a usage error, a refused --resume; nothing written.
expect_exit 2 "$work/bad" "$bin" run "$studies/bad_damping.toml" --out "$work/bad"
[ ! -e "$work/bad" ] || fail "2: output directory created for bad input"
expect_exit 2 "$work/usage" "$bin" run "$studies/dde_1d.toml" --threads=-1 --out "$work/usage"
[ ! -e "$work/usage" ] || fail "2: output directory created for a usage error"
cp -r "$work/ok" "$work/other_study"
expect_exit 2 "$work/refused" "$bin" run "$studies/dde_2d.toml" --out "$work/other_study" --resume
grep -q "cannot resume from" "$work/refused.err" || fail "2: $(cat "$work/refused.err")"
diff -r -x .chatterlab-lock "$work/ok" "$work/other_study" >/dev/null ||
  fail "2: a refused --resume changed the directory (other than the lock file's holder details)"
# 3: results.csv cannot be replaced (a directory took its name): meta.json says so, no partial
# file, and --resume completes once the obstacle is gone.
rm "$work/ok/results.csv" && mkdir -p "$work/ok/results.csv/blocked"
expect_exit 3 "$work/output" "$bin" run "$studies/dde_1d.toml" --out "$work/ok" --resume
grep -q "output could not be written: cannot replace $work/ok/results.csv" "$work/output.err" ||
  fail "3: message: $(cat "$work/output.err")"
grep -q '"state": "output_failed"' "$work/ok/meta.json" || fail "3: meta.json state is not output_failed"
grep -q '"output_error": "cannot replace' "$work/ok/meta.json" || fail "3: meta.json lacks the error"
no_partial_files "$work/ok"
[ ! -e "$work/ok/.chatterlab-reserve" ] || fail "3: the space reserve was left behind"
rm -r "$work/ok/results.csv"
expect_exit 0 "$work/fixed" "$bin" run "$studies/dde_1d.toml" --out "$work/ok" --resume
cmp "$work/ok/results.csv" "$work/other_study/results.csv" || fail "3: --resume after the fix differs"
finish
