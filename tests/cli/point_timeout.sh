#!/usr/bin/env bash
# A per-point time limit: a point that never ends is killed at --point-timeout (or [run]
# point_timeout_s), recorded as `timeout` with its time, and the run goes on and exits 1;
# --resume does not hang on it; --resume --retry-failed computes it again (under the limit).
# Usage: point_timeout.sh CHATTERLAB WORK_DIR MISBEHAVING_PLUGIN THROWING_ENTRY_PLUGIN
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2 plugin=$3
rm -rf "$work" && mkdir -p "$work"

# 3 decay rates x (ok, hang, sleep 1 s): the hanging points time out, the 1 s sleepers do not.
study=$work/hang.toml
misbehaving_study "$study" "$plugin" '["ok", "hang", "sleep"]'
out=$work/limited
start=$(date +%s)
expect_exit 1 "$work/limited" timeout 120 "$bin" run "$study" --out "$out" --threads 2 --point-timeout 3
wall=$(($(date +%s) - start))
csv=$out/results.csv
[ "$(grep -c ',hang,.*,"\?timeout: still running after the time limit of 3 s (point_timeout_s); its worker process was killed' "$csv")" = 3 ] ||
  fail "hanging points not recorded as timeout: $(grep ,hang, "$csv")"
[ "$(grep -c ',sleep,.*,ok$' "$csv")" = 3 ] || fail "points under the limit not ok: $(grep ,sleep, "$csv")"
[ "$(grep -c ',ok,.*,ok$' "$csv")" = 3 ] || fail "ok points not ok"
# 3 timeouts of 3 s on 2 workers, the rest a few seconds: well under a minute.
[ "$wall" -lt 60 ] || fail "the limited run took $wall s"
[ "$(json_number "$out/meta.json" points_timed_out)" = 3 ] || fail "meta.json: points_timed_out != 3"
for elapsed in $(grep -o '"elapsed_s": [0-9.e+-]*' "$out/meta.json" | sed 's/.*: //'); do
  awk -v e="$elapsed" 'BEGIN { exit !(e >= 3 && e < 10) }' || fail "timeout recorded with elapsed_s = $elapsed"
done
[ "$(grep -c '"status": "timeout"' "$out/meta.json")" = 3 ] || fail "meta.json: failed_points lack status timeout"
grep -q "9 points: 6 ok, 3 failed (3 of them timed out)" "$work/limited.out" ||
  fail "summary: $(cat "$work/limited.out")"
cp "$csv" "$work/first.csv"

# --resume does not hang: the timed-out points are taken over as they are.
expect_exit 1 "$work/resume" timeout 60 "$bin" run "$study" --out "$out" --resume
cmp "$work/first.csv" "$csv" || fail "--resume changed results.csv"
[ "$(json_number "$out/meta.json" points_computed)" = 0 ] || fail "--resume recomputed points"

# results.h5 does not keep a timeout's elapsed time; --resume of a completed hdf5 run takes it
# from the run's meta.json, so the resumed meta.json still says how long each timeout ran.
misbehaving_study "$work/hang_hdf5.toml" "$plugin" '["ok", "hang", "sleep"]'
printf '[output]\nformat = "hdf5"\n' >>"$work/hang_hdf5.toml"
out_h5=$work/limited_hdf5
expect_exit 1 "$work/limited_hdf5" timeout 120 "$bin" run "$work/hang_hdf5.toml" --out "$out_h5" --threads 2 --point-timeout 3
expect_exit 1 "$work/resume_hdf5" timeout 60 "$bin" run "$work/hang_hdf5.toml" --out "$out_h5" --resume
[ "$(json_number "$out_h5/meta.json" points_computed)" = 0 ] || fail "hdf5 --resume recomputed points"
[ "$(grep -c '"elapsed_s"' "$out_h5/meta.json")" = 3 ] || fail "hdf5 --resume: timeouts lost elapsed_s"
for elapsed in $(grep -o '"elapsed_s": [0-9.e+-]*' "$out_h5/meta.json" | sed 's/.*: //'); do
  awk -v e="$elapsed" 'BEGIN { exit !(e >= 3 && e < 10) }' || fail "hdf5 --resume: a timeout's elapsed_s = $elapsed"
done

# --resume --retry-failed computes exactly the timed-out points again, under the limit.
expect_exit 1 "$work/retry" timeout 120 "$bin" run "$study" --out "$out" --resume --retry-failed --point-timeout 2
[ "$(json_number "$out/meta.json" points_computed)" = 3 ] || fail "--retry-failed did not compute the 3 timed-out points"
[ "$(grep -c 'time limit of 2 s' "$csv")" = 3 ] || fail "--retry-failed: the new limit is not in the statuses"

# The limit from the study's [run] table, no flag.
misbehaving_study "$work/hang_run_table.toml" "$plugin" '["ok", "hang", "sleep"]' 'point_timeout_s = 3'
expect_exit 1 "$work/run_table" timeout 120 "$bin" run "$work/hang_run_table.toml" --out "$work/run_table" --threads 2
cmp "$work/first.csv" "$work/run_table/results.csv" || fail "[run] point_timeout_s differs from --point-timeout"

# --retry-failed needs --resume; a limit must be positive.
expect_exit 2 "$work/retry_alone" "$bin" run "$study" --out "$work/x" --retry-failed
grep -q "requires --resume" "$work/retry_alone.err" || fail "--retry-failed alone: $(cat "$work/retry_alone.err")"
expect_exit 2 "$work/zero" "$bin" run "$study" --out "$work/x" --point-timeout 0
misbehaving_study "$work/bad_limit.toml" "$plugin" '["ok"]' 'point_timeout_s = -1'
expect_exit 2 "$work/bad_limit" "$bin" run "$work/bad_limit.toml" --out "$work/x"
grep -q "bad_limit.toml:.*run.point_timeout_s = -1" "$work/bad_limit.err" || fail "bad [run] limit: $(cat "$work/bad_limit.err")"
[ ! -e "$work/x" ] || fail "a rejected run created its output directory"
finish
