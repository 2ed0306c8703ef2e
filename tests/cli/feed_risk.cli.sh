#!/usr/bin/env bash
# feed_risk end to end (docs/feed_risk.md): at constant conditions every segment's growth rate is
# stability_map's at the same model, the amplification is the integral of the growth rate, the
# simulation along the plan grows at the root's rate; the files and plots exist; bad input exits 2
# with the reason and writes nothing.
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2 src=$3
rm -rf "$work" && mkdir -p "$work"

# ---- constant conditions against stability_map
out="$work/constant"
expect_exit 0 "$work/constant" "$bin" run "$src/studies/feed_risk_constant.toml" --out "$out"
map="$work/map.toml"
{ echo '[study]'; echo 'kind = "stability_map"'; sed -n '/^\[model\]/,/^wheel_regeneration/p' "$src/studies/feed_risk_constant.toml"; } >"$map"
expect_exit 0 "$work/map" "$bin" run "$map" --out "$work/map_out"
root=$(csv_column "$work/map_out/results.csv" growth_rate_per_s)
frequency=$(csv_column "$work/map_out/results.csv" chatter_frequency_hz)
[ "$(csv_column "$out/segments.csv" growth_rate_per_s | sort -u | wc -l)" = "1" ] || fail "constant plan: more than one growth rate"
seg=$(csv_column "$out/segments.csv" growth_rate_per_s | head -n 1)
awk -v a="$seg" -v b="$root" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(b > 0 && d <= 1e-12 * b) }' ||
  fail "segment growth $seg vs stability_map $root"
seg_f=$(csv_column "$out/segments.csv" chatter_frequency_hz | head -n 1)
close_to "$seg_f" "$frequency" 1e-9 || fail "segment chatter frequency $seg_f vs $frequency"
# ln A = root x total time
total=$(csv_column "$out/results.csv" total_time_s)
log_a=$(csv_column "$out/results.csv" final_log_amplification)
awk -v l="$log_a" -v r="$root" -v t="$total" 'BEGIN { d = l - r * t; if (d < 0) d = -d; exit !(d <= 1e-9 * r * t) }' ||
  fail "ln A $log_a vs root x time $root x $total"
[ "$(csv_column "$out/results.csv" worst_risk)" = "chatter" ] || fail "constant plan should be chatter"
[ "$(csv_column "$out/results.csv" simulation_status)" = "completed" ] || fail "simulation status"
# The simulation's rolling growth rate over the second half agrees with the root within 6 % (the work lattice's neighbouring roots grow almost as fast, so the envelope approaches the rightmost root's rate slowly: 0.34 vs 0.356 /s after 30 s).
fitted=$(awk -F, -v t="$total" 'NR > 1 && $1 > t / 2 && $6 != "nan" { s += $6; n++ } END { if (n) print s / n }' "$out/along_x.csv")
awk -v f="$fitted" -v r="$root" 'BEGIN { d = f - r; if (d < 0) d = -d; exit !(f != "" && d <= 0.06 * r) }' ||
  fail "simulated growth $fitted vs root $root"
expect_plots "$out" growth_along_x waviness_along_x amplification_over_time
for f in segments.csv along_x.csv summary.json; do [ -s "$out/$f" ] || fail "$f missing"; done

# ---- a second model with the process-conditions capability: plunge_with_penetration_damping
# (roots only: it has no time-domain form). kd = 0 is G1 (the same growth rate and ln A to 1e-9);
# kd = 2000 N s/m damps the work chain (slower growth).
pd() {  # pd NAME KD
  sed -e 's/^type = "plunge_regenerative"/type = "plunge_with_penetration_damping"/' \
      -e "s/^wheel_regeneration = false/wheel_regeneration = false\npenetration_damping_n_s_per_m = $2/" \
      "$src/studies/feed_risk_constant.toml" >"$work/$1.toml"
  printf '[feed_risk.simulation]\nenabled = false\n' >>"$work/$1.toml"
  expect_exit 0 "$work/$1" "$bin" run "$work/$1.toml" --out "$work/$1_out"
}
pd pd0 0.0
close_to "$(csv_column "$work/pd0_out/results.csv" max_growth_rate_per_s)" "$root" 1e-9 || fail "kd = 0: growth vs G1 $root"
close_to "$(csv_column "$work/pd0_out/results.csv" final_log_amplification)" "$log_a" 1e-9 || fail "kd = 0: ln A vs G1"
pd pd2000 2000.0
awk -v g="$(csv_column "$work/pd2000_out/results.csv" max_growth_rate_per_s)" -v r="$root" 'BEGIN { exit !(g < r - 1e-3) }' ||
  fail "kd = 2000: growth not below G1's $root"

# ---- saved plan (plan_dir) gives the same risk as the plan made in the study
expect_exit 0 "$work/plan" "$bin" run <(sed -e 's/kind = "feed_risk"/kind = "feed_plan"/' -e '/^\[model\]/,/^wheel_regeneration/d' -e '/^\[feed_risk\]/,$d' "$src/studies/feed_risk_constant.toml") --out "$work/saved_plan"
saved="$work/saved.toml"
sed -e '/^\[machine\]/,/^thickness_mm/d' "$src/studies/feed_risk_constant.toml" >"$saved"
printf 'plan_dir = "%s"\n[feed_risk.simulation]\nenabled = false\n' "$work/saved_plan" >>"$saved"
expect_exit 0 "$work/saved" "$bin" run "$saved" --out "$work/saved_out"
close_to "$(csv_column "$work/saved_out/results.csv" final_log_amplification)" "$log_a" 1e-9 || fail "saved plan ln A"

# ---- chatter-aware planning on the constant study: 250-300 rpm, time at most 1.2 x
opt="$work/optimise.toml"
{ sed 's/^spindle_speed_rpm = 300.0/spindle_speed_rpm = { from = 250.0, to = 300.0 }/' "$src/studies/feed_risk_constant.toml"
  printf '[feed_risk.optimise]\nspeed_steps = 6\nmodulation_amplitude_ratios = [0.0, 0.05]\n'; } >"$opt"
expect_exit 0 "$work/optimise" "$bin" run "$opt" --out "$work/optimise_out"
o="$work/optimise_out"
base_t=$(csv_column "$o/results.csv" total_time_s)
opt_t=$(csv_column "$o/results.csv" optimised_total_time_s)
awk -v a="$opt_t" -v b="$base_t" 'BEGIN { exit !(a >= b - 1e-9 && a <= 1.2 * b + 1e-9) }' || fail "optimised time $opt_t vs $base_t"
base_w=$(csv_column "$o/results.csv" max_predicted_waviness_um)
opt_w=$(csv_column "$o/results.csv" optimised_max_predicted_waviness_um)
awk -v a="$opt_w" -v b="$base_w" 'BEGIN { exit !(a <= b) }' || fail "optimised waviness $opt_w above $base_w"
[ "$(csv_column "$o/optimisation.csv" spindle_speed_rpm | wc -l)" = "12" ] || fail "optimisation.csv: not 12 candidates"
# The chatter-aware pulses cover the same path: every motor's pulse sum equals the baseline plan's.
for motor in lower_pulses middle_pulses upper_pulses; do
  a=$(csv_column "$o/optimised_pulses.csv" $motor | awk '{ s += $1 } END { print s }')
  b=$(csv_column "$work/saved_plan/pulses.csv" $motor | awk '{ s += $1 } END { print s }')
  [ "$a" = "$b" ] || fail "optimised $motor sum $a vs baseline $b"
done
expect_plots "$o" optimisation before_after
# A stable choice (over the +-0.5 % speed band) is written, with the stable window around it.
[ "$(csv_column "$o/results.csv" replan_verdict)" = "stable" ] || fail "constant: replan verdict"
grep -q '"plan_written": true' "$o/summary.json" || fail "constant: plan_written"
chosen=$(csv_column "$o/results.csv" optimised_spindle_speed_rpm)
sed -n '/"stable_window_rpm"/,/}/p' "$o/summary.json" | tr -d ' ,' |
  awk -F: -v n="$chosen" '/"from"/ { f = $2 } /"to"/ { t = $2 } END { exit !(f != "" && f <= n && n <= t) }' ||
  fail "constant: stable window does not hold the chosen $chosen rpm"

# ---- the simulation reaching the depth of cut: recorded, root results kept, prediction capped
shallow="$work/shallow.toml"
sed 's/^depth_of_cut_mm = 0.01/depth_of_cut_mm = 0.001/' "$src/studies/feed_risk_constant.toml" >"$shallow"
expect_exit 0 "$work/shallow" "$bin" run "$shallow" --out "$work/shallow_out"
[ "$(csv_column "$work/shallow_out/results.csv" simulation_status)" = "reached_depth_of_cut" ] || fail "shallow: simulation status"
close_to "$(csv_column "$work/shallow_out/results.csv" max_growth_rate_per_s)" "$root" 1e-12 || fail "shallow: root kept"
close_to "$(csv_column "$work/shallow_out/results.csv" max_predicted_waviness_um)" 1 1e-12 || fail "shallow: prediction not capped at 1 um"
grep -q '"diverged": true' "$work/shallow_out/summary.json" || fail "shallow: summary lacks diverged"

# ---- P3 problem 2 (roots and re-planning; the simulations are left to the shipped study, 75 s):
# chatter at the planner's 300 rpm. Rated over the +-0.5 % spindle-speed band (issue 19), no
# speed in 250..300 rpm is stable: 290 rpm (1450/290 = 5 exactly) is at -0.32 /s only at the
# exact ratio, its band reaches ~0 /s. The re-plan says so on the terminal and in results.csv,
# writes no optimised plan, and lists the levers with the growth rate each change actually gives.
p2="$work/p2.toml"
{ cat "$src/studies/feed_risk_problem2.toml"; printf '[feed_risk.simulation]\nenabled = false\n'; } |
  sed 's/^modulation_amplitude_ratios = .*/modulation_amplitude_ratios = [0.0]/' >"$p2"
expect_exit 0 "$work/p2" "$bin" run "$p2" --out "$work/p2_out"
r="$work/p2_out/results.csv"
s="$work/p2_out/summary.json"
[ "$(csv_column "$r" worst_risk)" = "chatter" ] || fail "problem 2: not chatter at 300 rpm"
awk -v g="$(csv_column "$r" max_growth_rate_per_s)" 'BEGIN { exit !(g > 0.1 && g < 0.2) }' || fail "problem 2: max growth"
[ "$(csv_column "$r" replan_verdict)" = "no stable candidate" ] || fail "problem 2: verdict $(csv_column "$r" replan_verdict)"
[ -z "$(csv_column "$r" optimised_spindle_speed_rpm)" ] || fail "problem 2: an optimised speed without a stable plan"
[ ! -e "$work/p2_out/optimised_pulses.csv" ] && [ ! -e "$work/p2_out/optimised_segments.csv" ] ||
  fail "problem 2: an optimised plan was written"
grep -q '^notice: no stable candidate: every spindle speed in \[250, 300\] rpm' "$work/p2.out" ||
  fail "problem 2: no notice on the terminal: $(cat "$work/p2.out")"
grep -q '"exact_speed_ratio": "5/1"' "$s" || fail "problem 2: 290 rpm's exact ratio not reported"
grep -q '"plan_written": false' "$s" || fail "problem 2: plan_written"
[ "$(grep -c '"lever":' "$s")" = 4 ] || fail "problem 2: not four levers (width, work speed, wheel speed, depth of cut)"
grep -q 'Levers at the worst segment: width of cut' "$work/p2.out" || fail "problem 2: levers not on the terminal"
grep -q '"speed_tolerance": 0.005' "$s" || fail "problem 2: speed tolerance not reported"
expect_plots "$work/p2_out" growth_along_x waviness_along_x amplification_over_time optimisation before_after

# ---- bad input: exit 2, reason in the message, nothing written
bad() {  # bad NAME EXPECTED_TEXT: runs $work/NAME.toml
  local name=$1 text=$2
  expect_exit 2 "$work/$name" "$bin" run "$work/$name.toml" --out "$work/${name}_out"
  grep -q "$text" "$work/$name.err" || fail "$name: message lacks '$text': $(cat "$work/$name.err")"
  [ ! -e "$work/${name}_out" ] || fail "$name: output written"
}
study="$src/studies/feed_risk_constant.toml"
without_plan_tables() { sed '/^\[machine\]/,/^thickness_mm/d' "$study"; }
# A model whose parameters do not follow the process conditions (no ProcessConditionsModel).
sed -e '/^\[model\]/,/^wheel_regeneration/c\[model]\ntype = "linear_dde"\na0 = [[0.0, 1.0], [-1.3, -0.1]]' "$study" >"$work/model_mismatch.toml"
bad model_mismatch 'model.type = "linear_dde": feed_risk needs a model whose parameters follow the process conditions'
# plunge_with_penetration_damping has roots but no time-domain form: the simulation must be off.
sed -e 's/^type = "plunge_regenerative"/type = "plunge_with_penetration_damping"/' \
    -e 's/^wheel_regeneration = false/wheel_regeneration = false\npenetration_damping_n_s_per_m = 0.0/' "$study" >"$work/pd_simulated.toml"
bad pd_simulated 'the model has no time-domain form, so feed_risk cannot simulate along the plan'

{ without_plan_tables; echo "plan_dir = \"$work/no_such_plan\""; } >"$work/missing_plan.toml"
bad missing_plan "cannot open (a saved feed plan needs summary.json)"
mkdir -p "$work/half_plan" && cp "$work/saved_plan/summary.json" "$work/half_plan/"
{ without_plan_tables; echo "plan_dir = \"$work/half_plan\""; } >"$work/missing_pulses.toml"
bad missing_pulses "pulses.csv: cannot open (a saved feed plan needs pulses.csv)"
{ without_plan_tables | sed 's/^\[feed_risk\]$/[wheel]\ndiameter_mm = 500.0\n[feed_risk]/'; echo "plan_dir = \"$work/saved_plan\""; } >"$work/wheel_mismatch.toml"
bad wheel_mismatch "wheel.diameter_mm = 500.0: plan/model mismatch: the saved plan in .* has wheel.diameter_mm = 400"
range='s/^spindle_speed_rpm = 300.0/spindle_speed_rpm = { from = 250.0, to = 300.0 }/'
{ sed "$range" "$study"; printf '[feed_risk.optimise]\nmodulation_amplitude_ratios = [0.0, 1.0]\n'; } >"$work/stop_spindle.toml"
bad stop_spindle "amplitude ratio 1 would stop or reverse the spindle"
{ sed "$range" "$study"; printf '[feed_risk.optimise]\nmodulation_amplitude_ratios = [0.2]\n'; } >"$work/spindle_range.toml"
bad spindle_range "spindle range violated: with amplitude ratio 0.2 no mean speed"
# A saved plan whose spindle speed (top-level key, not the machine's range) lies outside the range.
cp -r "$work/saved_plan" "$work/fast_plan"
sed -i 's/^  "spindle_speed_rpm": 300.0/  "spindle_speed_rpm": 320.0/' "$work/fast_plan/summary.json"
{ without_plan_tables; echo "plan_dir = \"$work/fast_plan\""; } >"$work/plan_speed.toml"
bad plan_speed "spindle range violated: the plan runs the spindle at 320 rpm"
finish
