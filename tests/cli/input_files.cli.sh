#!/usr/bin/env bash
# Input files are fingerprinted and read once: meta.json holds each file's sha256 (as sha256sum
# prints it); a data file replaced while the study runs stops the run (exit 2, meta.json says
# which file, no results.csv: never a mix of old and new data); --resume after the data changed
# is refused naming the file; --resume ignores the study's name, description, comments and key
# order, but refuses a changed value, naming it.
# Usage: input_files.cli.sh CHATTERLAB WORK_DIR SOURCE_DIR
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2 src=$3
rm -rf "$work" && mkdir -p "$work"

# A surface study over 12 filter cut-offs of one profile, each point drawing its plots (slow
# enough, ~0.3 s a point, to swap the file while it runs).
data=$work/profile.csv
cp "$src/studies/data/surface_g8_roundness.csv" "$data"
write_study() {  # FILE [NAME]: the study; NAME adds [study] name, description and comments
  {
    [ -n "${2:-}" ] && echo "# a comment that changes no number"
    printf '[study]\nkind = "surface"\n'
    [ -n "${2:-}" ] && printf 'name = "%s"\ndescription = "renamed"\n' "$2"
    printf '[input]\nfile = "profile.csv"\ncolumn = "radius_um"\nclosed = true\n'
    printf 'samples_per_rev = 7200\nunit = "um"\n'
    printf '[process]\nwheel_speed_rpm = %s\nwork_speed_rpm = 55\n' "${WHEEL:-1450}"
    printf '[filter]\ntype = "gaussian"\n'
    printf '[grid]\n"filter.cutoff_upr" = [15, 20, 25, 30, 40, 50, 60, 80, 100, 120, 150, 200]\n'
  } >"$1"
}
study=$work/profile.toml
write_study "$study"

# The reference: an undisturbed run. meta.json records the data file's sha256.
expect_exit 0 "$work/ref" "$bin" run "$study" --out "$work/ref" --threads 1
sha=$(sha256sum "$data" | cut -d' ' -f1)
grep -q "\"sha256\": \"$sha\"" "$work/ref/meta.json" || fail "meta.json lacks the data file's sha256 $sha"
grep -q "\"path\": \"$data\"" "$work/ref/meta.json" || fail "meta.json lacks the data file's path"
study_sha=$(sha256sum "$study" | cut -d' ' -f1)
grep -q "\"sha256\": \"$study_sha\"" "$work/ref/meta.json" || fail "meta.json lacks the study file's sha256"

# Swapped mid-run (after the second point is in the journal): stopped, exit 2, no results.csv.
out=$work/swapped
"$bin" run "$study" --out "$out" --threads 1 >"$work/swap.out" 2>"$work/swap.err" &
pid=$!
two_done() { [ "$(journal_records "$out")" -ge 2 ]; }
wait_for 60 two_done || fail "the run did not get to its second point"
awk 'NR == 2 { $0 = $0 + 1 } { print }' "$src/studies/data/surface_g8_roundness.csv" >"$data.new"
mv "$data.new" "$data"  # replaced, as an editor or a copy would
wait "$pid"
rc=$?
[ "$rc" = 2 ] || fail "a run whose data changed mid-run exited $rc, not 2"
grep -q "an input file changed while the study ran" "$work/swap.err" || fail "message: $(cat "$work/swap.err")"
grep -qF "$data: changed since the run read it (sha256 ${sha:0:12}..." "$work/swap.err" ||
  fail "the message does not name the file and its hash: $(cat "$work/swap.err")"
grep -q '"state": "input_changed"' "$out/meta.json" || fail "meta.json state is not input_changed"
grep -qF "$data: changed since the run read it" "$out/meta.json" || fail "meta.json does not name the file"
[ ! -e "$out/results.csv" ] || fail "results.csv written from data that changed"
records=$(journal_records "$out")
[ "$records" -lt 12 ] || fail "the run was not stopped: $records points computed after the change"
no_partial_files "$out"

# --resume with the changed data is refused, naming the file; nothing changes.
cp "$out/meta.json" "$work/meta_before"
expect_exit 2 "$work/resume_changed" "$bin" run "$study" --out "$out" --resume
grep -qF "input file $data changed since that run (sha256 ${sha:0:12}... then" "$work/resume_changed.err" ||
  fail "refused resume does not name the file: $(cat "$work/resume_changed.err")"
cmp "$work/meta_before" "$out/meta.json" || fail "a refused --resume changed meta.json"

# Swapped back: --resume completes from the journal and matches the undisturbed run.
cp "$src/studies/data/surface_g8_roundness.csv" "$data"
expect_exit 0 "$work/resume_back" "$bin" run "$study" --out "$out" --resume --threads 1
cmp "$work/ref/results.csv" "$out/results.csv" || fail "resumed results.csv differs from the undisturbed run"
[ "$(json_number "$out/meta.json" points_resumed)" = "$records" ] || fail "resume did not take the $records journal points over"

# Changed before a --resume of a complete run: refused too.
awk 'NR == 3 { $0 = $0 - 1 } { print }' "$src/studies/data/surface_g8_roundness.csv" >"$data"
expect_exit 2 "$work/resume_before" "$bin" run "$study" --out "$out" --resume
grep -qF "input file $data changed since that run" "$work/resume_before.err" || fail "$(cat "$work/resume_before.err")"
cmp "$work/ref/results.csv" "$out/results.csv" || fail "a refused --resume changed results.csv"
cp "$src/studies/data/surface_g8_roundness.csv" "$data"

# Name, description, comments: --resume takes every point over.
write_study "$study" "Renamed study"
expect_exit 0 "$work/renamed" "$bin" run "$study" --out "$out" --resume
[ "$(json_number "$out/meta.json" points_computed)" = 0 ] || fail "renaming the study made --resume recompute"
cmp "$work/ref/results.csv" "$out/results.csv" || fail "renamed resume changed results.csv"
grep -q '"name": "Renamed study"' "$out/meta.json" || fail "meta.json does not have the new name"
# A value that changes results: refused, naming it.
WHEEL=1500 write_study "$study" "Renamed study"
expect_exit 2 "$work/changed_value" "$bin" run "$study" --out "$out" --resume
grep -qF "the study changed since that run (process.wheel_speed_rpm: 1450 then, 1500 now)" \
  "$work/changed_value.err" || fail "changed value not named: $(cat "$work/changed_value.err")"
finish
