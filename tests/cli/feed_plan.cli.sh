#!/usr/bin/env bash
# feed_plan end to end (docs/planner.md): problem 1 of MODELS.md P3 gives the contract files
# (pulses.csv columns, summary.json keys), the seed-000 first-segment rates -54, 12, 14, 3000 s,
# a certified plan with replayed error <= 0.005 mm, the plots; bad input exits 2 writing nothing.
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2 src=$3
rm -rf "$work" && mkdir -p "$work"

out="$work/p1"
expect_exit 0 "$work/p1" "$bin" run "$src/studies/feed_plan_problem1.toml" --out "$out"
[ "$(csv_header "$out/pulses.csv")" = "segment,start_s,duration_s,lower_pulses,middle_pulses,upper_pulses" ] ||
  fail "pulses.csv header: $(csv_header "$out/pulses.csv")"
[ "$(csv_column "$out/pulses.csv" lower_pulses | head -n 1)" = "-54" ] || fail "first lower rate"
[ "$(csv_column "$out/pulses.csv" middle_pulses | head -n 1)" = "12" ] || fail "first middle rate"
[ "$(csv_column "$out/pulses.csv" upper_pulses | head -n 1)" = "14" ] || fail "first upper rate"
close_to "$(json_number "$out/summary.json" total_time_s)" 3000 1e-6 || fail "total time"
close_to "$(json_number "$out/summary.json" spindle_speed_rpm)" 300 0 || fail "spindle speed"
error=$(json_number "$out/summary.json" max_profile_error_mm)
awk -v e="$error" 'BEGIN { exit !(e > 0 && e <= 0.005) }' || fail "max profile error $error"
for key in lower_mm middle_mm upper_nut_mm rms_profile_error_mm max_edge_radius_mm certificate; do
  grep -q "\"$key\"" "$out/summary.json" || fail "summary.json lacks $key"
done
grep -q '"ok": true' "$out/summary.json" || fail "plan not certified"
# Problem 1 is convex: no part limits the edge radius; the number is the wheel's own limit
# (20 mm face, 180 deg arc: r <= 10 mm) and says so. The wheel clears the part at every state.
close_to "$(json_number "$out/summary.json" max_edge_radius_mm)" 10 1e-9 || fail "problem 1 edge radius"
grep -q '"max_edge_radius_limited_by": "wheel_geometry"' "$out/summary.json" || fail "edge radius limit reason"
close_to "$(json_number "$out/summary.json" max_depth_mm)" 0 0 || fail "problem 1 interference"
states=$(json_number "$out/summary.json" states_checked)
awk -v n="$states" 'BEGIN { exit !(n > 100000) }' || fail "interference checked only $states states"
# Sum of pulses = displacement: the lower table ends within a step of P4's position at x = 600.
sum=$(csv_column "$out/pulses.csv" upper_pulses | awk '{ s += $1 } END { print s }')
# z_g(600) - z_g(0) = -R (f'(600) - f'(0)) = 300 * (0.45 + 1/60) mm = 140 mm = 42000 pulses.
[ "$sum" = "42000" ] || fail "upper pulses sum $sum (expected 42000)"
expect_plots "$out" profile error_along_x pulse_rates

# Problem 2: seed 000's first rates -27, 40, 55; the edge-radius limit of the concave part.
out2="$work/p2"
expect_exit 0 "$work/p2" "$bin" run "$src/studies/feed_plan_problem2.toml" --out "$out2"
[ "$(sed -n 2p "$out2/pulses.csv" | cut -d, -f4-)" = "-27,40,55" ] || fail "problem 2 first row $(sed -n 2p "$out2/pulses.csv")"
close_to "$(json_number "$out2/summary.json" total_time_s)" 3000 1e-6 || fail "problem 2 total time"
close_to "$(json_number "$out2/summary.json" max_edge_radius_mm)" 722.7 0.5 || fail "problem 2 edge radius"
grep -q '"max_edge_radius_limited_by": "concave_part"' "$out2/summary.json" || fail "problem 2 edge radius reason"
error=$(json_number "$out2/summary.json" max_profile_error_mm)
awk -v e="$error" 'BEGIN { exit !(e > 0 && e <= 0.005) }' || fail "problem 2 max profile error $error"

# Problem 3: the sweep laws on a grid. Triangle spreads the wear evenly (uniformity > 0.9) but
# brakes at each turn; the sine sweep is smoother (less time) and piles wear at the face's edges.
out3="$work/p3"
expect_exit 0 "$work/p3" "$bin" run "$src/studies/feed_plan_problem3.toml" --out "$out3"
[ "$(csv_column "$out3/results.csv" status | sort -u)" = "ok" ] || fail "problem 3 points failed"
tri_time=$(csv_column "$out3/results.csv" total_time_s | sed -n 1p)
sine_time=$(csv_column "$out3/results.csv" total_time_s | sed -n 2p)
awk -v t="$tri_time" -v s="$sine_time" 'BEGIN { exit !(s < t && t > 3000) }' || fail "sweep times $tri_time $sine_time"
tri_u=$(json_number "$out3/points/000000/summary.json" uniformity)
sine_u=$(json_number "$out3/points/000001/summary.json" uniformity)
awk -v a="$tri_u" -v b="$sine_u" 'BEGIN { exit !(a > 0.9 && b < 0.5) }' || fail "uniformity $tri_u $sine_u"
expect_plots "$out3/points/000000" wear_histogram

# Bad input: exit 2, message with key and reason, nothing written.
sed 's/^max_pulse_rate_hz = 100.0/max_pulse_rate_hz = 0.0/' "$src/studies/feed_plan_problem1.toml" > "$work/bad.toml"
expect_exit 2 "$work/bad" "$bin" run "$work/bad.toml" --out "$work/bad_out"
grep -q "machine.max_pulse_rate_hz = 0" "$work/bad.err" || fail "bad input message: $(cat "$work/bad.err")"
[ ! -e "$work/bad_out" ] || fail "bad input wrote $work/bad_out"
finish
