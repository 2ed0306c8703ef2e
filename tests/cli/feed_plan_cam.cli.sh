#!/usr/bin/env bash
# cam_plan end to end (MODELS.md K, docs/planner.md "Cams"): the seed-002 cam study fits the
# 27 chosen points, inserts lift-table rows until every row is within 5e-4 mm, and writes pulses,
# fit errors, summary and plots; a chosen angle that is not a table row exits 2.
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2 src=$3
rm -rf "$work" && mkdir -p "$work"
out="$work/cam"
expect_exit 0 "$work/cam" "$bin" run "$src/studies/cam_seed002.toml" --out "$out"
fit=$(csv_column "$out/results.csv" max_fit_error_mm)
awk -v e="$fit" 'BEGIN { exit !(e > 0 && e <= 5e-4) }' || fail "adaptive fit error $fit"
seed=$(csv_column "$out/results.csv" seed_points_max_fit_error_mm)
awk -v e="$seed" 'BEGIN { exit !(e > 5e-4) }' || fail "27-point fit error $seed should exceed the target"
[ "$(csv_header "$out/pulses.csv")" = "segment,start_s,duration_s,c_axis_pulses,x_slide_pulses" ] ||
  fail "pulses.csv header"
sum=$(csv_column "$out/pulses.csv" c_axis_pulses | awk '{ s += $1 } END { print s }')
[ "$sum" = "360000" ] || fail "C axis turns $sum pulses (expected one turn, 360000)"
expect_plots "$out" fit_error profile_error x_slide
# Every machine rule, certified after integerisation; the lower bound below the plan's time.
grep -q '"ok": true' "$out/summary.json" || fail "cam plan not certified"
total=$(json_number "$out/summary.json" total_time_s)
bound=$(json_number "$out/summary.json" lower_bound_s)
awk -v t="$total" -v b="$bound" 'BEGIN { exit !(b > 0 && b <= t && t < 2) }' || fail "time $total, bound $bound"
# K3 process limits with the shipped 40 mm wheel: lift error within 15 um, per degree within 4 um.
lift=$(json_number "$out/summary.json" max_lift_error_mm)
per=$(json_number "$out/summary.json" max_per_degree_lift_error_mm)
awk -v e="$lift" -v p="$per" 'BEGIN { exit !(e > 0 && e <= 0.015 && p > 0 && p <= 0.004) }' ||
  fail "lift error $lift, per degree $per"
# Controller output read back exactly (program.ngc with C and X, steps.csv).
grep -q '^G1 C' "$out/program.ngc" || fail "program.ngc has no C moves"
grep -A3 '"round_trip"' "$out/summary.json" | grep -q '"exact": true' || fail "cam controller round trip"
# A 200 mm wheel gouges the concave flanks: beyond the limit, so the plan is not certified and
# the point fails (exit 1); its files still say how deep.
sed "s/^wheel_radius_mm = 40.0/wheel_radius_mm = 200.0/; s|\.\./tests/data|$src/tests/data|" \
  "$src/studies/cam_seed002.toml" > "$work/large.toml"
expect_exit 1 "$work/large" "$bin" run "$work/large.toml" --out "$work/large_out"
lift=$(json_number "$work/large_out/summary.json" max_lift_error_mm)
awk -v e="$lift" 'BEGIN { exit !(e > 0.05) }' || fail "200 mm wheel lift error $lift"
grep -q '"certified": false' "$work/large_out/summary.json" || fail "200 mm wheel plan certified"
grep -q 'failed: plan not certified: lift error' "$work/large_out/results.csv" || fail "200 mm wheel status"
sed 's/^chosen_angles_deg = \[360, 10, 21,/chosen_angles_deg = [360, 10, 22,/' "$src/studies/cam_seed002.toml" > "$work/bad.toml"
sed -i "s|\.\./tests/data|$src/tests/data|" "$work/bad.toml"
expect_exit 2 "$work/bad" "$bin" run "$work/bad.toml" --out "$work/bad_out"
grep -q "chosen angle 22 deg is not a row of the lift table" "$work/bad.err" || fail "message: $(cat "$work/bad.err")"
[ ! -e "$work/bad_out" ] || fail "bad input wrote files"
# The smoothness rule's delta is checked like feed_plan's.
sed "s/^max_relative_rate_change = 0.1 /max_relative_rate_change = 1.5 /; s|\.\./tests/data|$src/tests/data|" \
  "$src/studies/cam_seed002.toml" > "$work/bad_delta.toml"
expect_exit 2 "$work/bad_delta" "$bin" run "$work/bad_delta.toml" --out "$work/bad_delta_out"
grep -q "machine.max_relative_rate_change = 1.5: out of range, must be > 0 and < 1" "$work/bad_delta.err" ||
  fail "message: $(cat "$work/bad_delta.err")"
[ ! -e "$work/bad_delta_out" ] || fail "bad delta wrote files"
finish
