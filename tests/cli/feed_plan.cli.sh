#!/usr/bin/env bash
# feed_plan end to end (docs/planner.md): problem 1 of MODELS.md P3 gives the contract files
# (pulses.csv columns, summary.json keys), the seed-000 first-segment rates -54, 12, 14, 3000 s,
# a certified plan with replayed error <= 0.005 mm, the controller output (program.ngc,
# steps.csv) read back exactly, the plots; the fillet plans to the 5 um tolerance; the measured
# table plans from its smoothed curve; kinks and near-steps and other bad input exit 2 writing
# nothing.
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
expect_plots "$out" profile error_along_x pulse_rates segment_lengths
grep -q '"certified": true' "$out/summary.json" || fail "problem 1 not certified"
# Controller output: G93 inverse time, one G1 per segment; both files read back exactly.
[ "$(grep -c '^G1 ' "$out/program.ngc")" = "3000" ] || fail "program.ngc: not 3000 moves"
grep -q '^G93$' "$out/program.ngc" || fail "program.ngc: no G93"
[ "$(csv_header "$out/steps.csv")" = "tick,motor,direction" ] || fail "steps.csv header"
pulses=$(awk -F, 'NR > 1 { s += ($4 < 0 ? -$4 : $4) + ($5 < 0 ? -$5 : $5) + ($6 < 0 ? -$6 : $6) } END { print s }' "$out/pulses.csv")
[ "$(($(wc -l < "$out/steps.csv") - 1))" = "$pulses" ] || fail "steps.csv rows differ from the pulse count $pulses"
grep -A3 '"round_trip"' "$out/summary.json" | grep -q '"exact": true' || fail "controller round trip not exact"

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

# The fillet (38.6 um at uniform 0.2 mm segments) plans within the 5 um tolerance.
out4="$work/fillet"
expect_exit 0 "$work/fillet" "$bin" run "$src/studies/feed_plan_fillet.toml" --out "$out4"
error=$(json_number "$out4/summary.json" max_profile_error_mm)
awk -v e="$error" 'BEGIN { exit !(e > 0 && e <= 0.005) }' || fail "fillet max profile error $error"
shortest=$(json_number "$out4/summary.json" shortest_segment_mm)
awk -v l="$shortest" 'BEGIN { exit !(l < 0.06) }' || fail "fillet shortest segment $shortest"
grep -q '"certified": true' "$out4/summary.json" || fail "fillet not certified"

# The measured table plans from its smoothed curve; the raw spline's plan is reported beside it.
out5="$work/measured"
expect_exit 0 "$work/measured" "$bin" run "$src/studies/feed_plan_measured.toml" --out "$out5"
close_to "$(json_number "$out5/summary.json" total_time_s)" 3000 1 || fail "measured part time"
raw_time=$(grep -A3 '"interpolating_spline"' "$out5/summary.json" | json_number /dev/stdin total_time_s)
awk -v t="$raw_time" 'BEGIN { exit !(t > 3300) }' || fail "raw spline time $raw_time"
expect_plots "$out5" table_residual table_curvature

# Kinks and near-steps are refused with their place (exit 2, nothing written).
sed 's|^generatrix = .*|generatrix = "100 + abs(x-300)*1.0"|' "$src/studies/feed_plan_problem1.toml" > "$work/kink.toml"
expect_exit 2 "$work/kink" "$bin" run "$work/kink.toml" --out "$work/kink_out"
grep -q "the slope f' jumps by 2 at x = 300 (a kink" "$work/kink.err" || fail "kink message: $(cat "$work/kink.err")"
[ ! -e "$work/kink_out" ] || fail "kink wrote $work/kink_out"
sed 's|^generatrix = .*|generatrix = "100 + 5*tanh((x-300)/0.001)"|' "$src/studies/feed_plan_problem1.toml" > "$work/step.toml"
expect_exit 2 "$work/step" "$bin" run "$work/step.toml" --out "$work/step_out"
grep -q "narrower than the resolution 0.01 mm at x = 299.99" "$work/step.err" || fail "near-step message: $(cat "$work/step.err")"

# Bad input: exit 2, message with key and reason, nothing written.
sed 's/^max_pulse_rate_hz = 100.0/max_pulse_rate_hz = 0.0/' "$src/studies/feed_plan_problem1.toml" > "$work/bad.toml"
expect_exit 2 "$work/bad" "$bin" run "$work/bad.toml" --out "$work/bad_out"
grep -q "machine.max_pulse_rate_hz = 0" "$work/bad.err" || fail "bad input message: $(cat "$work/bad.err")"
[ ! -e "$work/bad_out" ] || fail "bad input wrote $work/bad_out"
finish
