#!/usr/bin/env bash
# --isolate: points run in worker processes, so a plugin that segfaults, aborts, calls exit(0)
# or throws an int at one grid point fails that point (with the signal or exit status) and the
# run goes on; results stay byte-identical to an in-process run. Without --isolate a crash names
# the point and the way out, and exit(0) can no longer end the run with exit code 0.
# Usage: isolate.sh CHATTERLAB WORK_DIR MISBEHAVING_PLUGIN THROWING_ENTRY_PLUGIN
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2 plugin=$3
rm -rf "$work" && mkdir -p "$work"

study=$work/faults.toml
misbehaving_study "$study" "$plugin" '["ok", "segfault", "exit0", "abort", "throw_int"]'
expect_exit 1 "$work/isolated" "$bin" run "$study" --out "$work/isolated" --isolate --threads 2
csv=$work/isolated/results.csv
[ "$(tail -n +2 "$csv" | wc -l)" = 15 ] || fail "results.csv does not have 15 rows"
# Grid order: decay (1, 2, 3) slowest, behaviour fastest. The ok points are right.
for decay in 1 2 3; do
  row=$(grep "^$decay,ok," "$csv") || { fail "no ok row for decay $decay"; continue; }
  growth=$(echo "$row" | cut -d, -f3)
  close_to "$growth" "-$decay" 1e-9 || fail "decay $decay: growth rate $growth, expected -$decay"
  case $row in *",ok") ;; *) fail "ok point not ok: $row" ;; esac
done
expect_status() {  # BEHAVIOUR TEXT...: every row of BEHAVIOUR has a status holding every TEXT
  local behaviour=$1 rows
  shift
  rows=$(grep ",$behaviour," "$csv")
  [ "$(echo "$rows" | wc -l)" = 3 ] || fail "$behaviour: not 3 rows"
  for text in "$@"; do
    [ "$(echo "$rows" | grep -cF -- "$text")" = 3 ] || fail "$behaviour rows lack '$text': $rows"
  done
}
# Under ASan the sanitizer reports a SIGSEGV itself and then ends the worker its own way.
if grep -q "AddressSanitizer" "$work/isolated.err"; then
  expect_status segfault "failed: the point's worker process"
else
  expect_status segfault "failed: the point's worker process killed by signal 11 (SIGSEGV"
fi
expect_status segfault "misbehaving_model" "$plugin" "$study" "the rest of the run goes on"
expect_status exit0 "failed: the point's worker process exited with status 0"
expect_status abort "failed: the point's worker process killed by signal 6 (SIGABRT"
expect_status throw_int "failed: an exception of type 'int' (not derived from std::exception)" \
  "model plugin 'misbehaving_model' (library $plugin)" "study $study"
[ "$(json_number "$work/isolated/meta.json" points_failed)" = 12 ] || fail "meta.json: points_failed != 12"
grep -q '"worker_processes": true' "$work/isolated/meta.json" || fail "meta.json does not say worker processes"
grep -q "15 points: 3 ok, 12 failed" "$work/isolated.out" || fail "summary: $(cat "$work/isolated.out")"

# [run] isolate = true does the same without the flag.
misbehaving_study "$work/faults_run_table.toml" "$plugin" '["ok", "segfault", "exit0", "abort", "throw_int"]' \
  'isolate = true'
expect_exit 1 "$work/run_table" "$bin" run "$work/faults_run_table.toml" --out "$work/run_table" --threads 2
# (the failure statuses name the study file, which differs)
sed "s|faults_run_table.toml|faults.toml|g" "$work/run_table/results.csv" | cmp - "$csv" ||
  fail "[run] isolate = true differs from --isolate"

# Byte-identical to in-process runs: built-in stability maps, a data-file kind (its bytes travel
# to the workers with the setup) and 1 and 2 threads.
for case in "plunge_2d 2" "dde_2d 1" "budget_failure 2"; do
  set -- $case
  file=$CLI_TESTS_DIR/studies/$1.toml
  want=0
  [ "$1" = budget_failure ] && want=1
  expect_exit "$want" "$work/$1.in" "$bin" run "$file" --out "$work/$1.in" --threads "$2"
  expect_exit "$want" "$work/$1.iso" "$bin" run "$file" --out "$work/$1.iso" --threads "$2" --isolate
  cmp "$work/$1.in/results.csv" "$work/$1.iso/results.csv" || fail "$1: --isolate changed results.csv"
done
src=$(cd "$CLI_TESTS_DIR/../.." && pwd)
expect_exit 0 "$work/surface.in" "$bin" run "$src/studies/surface_roundness.toml" --out "$work/surface.in" --threads 2
expect_exit 0 "$work/surface.iso" "$bin" run "$src/studies/surface_roundness.toml" --out "$work/surface.iso" --threads 2 --isolate
cmp "$work/surface.in/results.csv" "$work/surface.iso/results.csv" || fail "surface: --isolate changed results.csv"
cmp "$work/surface.in/summary.json" "$work/surface.iso/summary.json" || fail "surface: --isolate changed summary.json"

# A library given as `--plugin` instead of `plugins = [...]`: hashed like a listed one (meta.json,
# the workers' check before they load it), and the workers load it too.
misbehaving_study "$work/cmdline.toml" "$plugin" '["ok"]'
sed -i '/^plugins = /d' "$work/cmdline.toml"
expect_exit 0 "$work/cmdline" "$bin" run "$work/cmdline.toml" --plugin "$plugin" --out "$work/cmdline" --isolate --threads 2
[ "$(grep -c ',ok$' "$work/cmdline/results.csv")" = 3 ] || fail "--plugin --isolate: not 3 ok rows"
plugin_sha=$(sha256sum "$plugin" | cut -d' ' -f1)
grep -q "\"sha256\": \"$plugin_sha\"" "$work/cmdline/meta.json" ||
  fail "--plugin: meta.json lacks the library's sha256 $plugin_sha"

# In-process, a crash says which point and how to go on, and dies by its signal.
misbehaving_study "$work/segv.toml" "$plugin" '["ok", "segfault"]'
# (in a subshell: the test's own shell would report the crash on stderr)
("$bin" run "$work/segv.toml" --out "$work/segv" --threads 1 >"$work/segv.out" 2>"$work/segv.err") 2>/dev/null
rc=$?
[ "$rc" -ne 0 ] && [ "$rc" -ne 1 ] && [ "$rc" -ne 2 ] || fail "in-process segfault: exit code $rc"
grep -q "fatal: signal 11 (SEGV) while computing grid point(s) 1 in this process" "$work/segv.err" ||
  fail "in-process segfault: no message naming the point: $(cat "$work/segv.err")"
grep -q -- "--resume --isolate" "$work/segv.err" || fail "in-process segfault: the way out is not named"
expect_exit 1 "$work/segv_resume" "$bin" run "$work/segv.toml" --out "$work/segv" --threads 1 --resume --isolate
[ "$(json_number "$work/segv/meta.json" points_resumed)" -ge 1 ] || fail "resume after a crash took nothing over"

# In-process exit(0) is exit code 3 with meta.json saying so, never 0.
misbehaving_study "$work/exit.toml" "$plugin" '["ok", "exit0"]'
expect_exit 3 "$work/exit" "$bin" run "$work/exit.toml" --out "$work/exit" --threads 1
grep -q "a plugin ended the process (exit()) while grid point(s) 1 were computed" "$work/exit.err" ||
  fail "exit(0) in-process: no message: $(cat "$work/exit.err")"
grep -q '"state": "ended_by_plugin"' "$work/exit/meta.json" || fail "meta.json does not say ended_by_plugin"
[ ! -e "$work/exit/results.csv" ] || fail "results.csv written by a run that a plugin ended"
ls "$work/exit"/results.csv.tmp* >/dev/null 2>&1 && fail "a half results.csv (temporary file) was left behind"
finish
