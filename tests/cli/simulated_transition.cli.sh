#!/usr/bin/env bash
# The dynamics engine feeding the metrology and the monitors (issues 6 and 7):
# - studies/simulate_transition.toml (G1 time domain, growth 4.79 /s at 361.7 Hz out of 0.1 um
#   rms sensor noise): exit 0; growth and chatter frequency equal the rightmost root of eq 2-16
#   (5 % / 0.5 %); timeseries.csv carries measured_displacement_m = x + noise (noise rms checked);
#   summary.json reports the final work surface's waviness and roundness, results.csv its columns,
#   and the polar roundness plot is drawn;
# - the chain simulate -> chatter_monitor on that run's own timeseries.csv: the onset is taken
#   from the noise-free displacement (first 25 ms window whose detrended rms reaches the noise
#   rms); each detector's first alarm comes after it, never before, and before the chatter is
#   5 x the noise;
# - studies/chatter_monitor_simulated.toml on the committed copy studies/data/
#   simulated_transition.csv: the copy equals this run's columns (to 1e-12 m), so the shipped
#   study is reproducible with the command in its header;
# - bad [surface] input exits 2 naming the key and the limit, nothing written.
# Usage: simulated_transition.cli.sh CHATTERLAB WORK_DIR SOURCE_DIR
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2 src=$3
rm -rf "$work" && mkdir -p "$work"

# ---- the simulation
sim=$work/sim
expect_exit 0 "$work/sim" "$bin" run "$src/studies/simulate_transition.toml" --out "$sim"
csv=$sim/results.csv
g=$(csv_column "$csv" fitted_growth_rate_per_s)
close_to "$g" 4.790137 0.24 || fail "simulate: growth $g /s, expected the root's 4.790 /s"
f=$(csv_column "$csv" dominant_frequency_hz)
close_to "$f" 361.7148 1.8 || fail "simulate: frequency $f Hz, expected the root's 361.71 Hz"
[ "$(head -n 1 "$sim/timeseries.csv" | awk -F, '{ print $11 }')" = measured_displacement_m ] ||
  fail "timeseries.csv: no measured_displacement_m column"
noise=$(awk -F, 'NR > 1 { d = $11 - $2; s += d * d; n++ } END { printf "%.4g", sqrt(s / n) }' "$sim/timeseries.csv")
close_to "$noise" 1e-7 3e-9 || fail "measured - clean displacement rms $noise m, expected 1e-7"
for c in work_waviness_wt_um work_waviness_wz_um work_roundness_ront_um; do
  v=$(csv_column "$csv" "$c")
  awk -v v="$v" 'BEGIN { exit !(v > 0) }' || fail "results.csv: $c = '$v'"
done
grep -q '"work_surface_quality"' "$sim/summary.json" || fail "summary.json: no work_surface_quality"
ront=$(json_number "$sim/summary.json" RONt_um)
[ "$ront" = "$(csv_column "$csv" work_roundness_ront_um)" ] || fail "RONt in summary.json ($ront) != results.csv"
grep -q '"cutoff_upr": 150' "$sim/summary.json" || fail "summary.json: [surface] cutoff_upr not applied"
expect_plots "$sim" timeseries envelope_fit spectrum work_surface surface_profile_polar surface_profile_wz_f_bands

# ---- onset from the noise-free displacement: detrended rms per 200-sample (25 ms) window
read -r onset five < <(awk -F, -v sigma=1e-7 '
  NR == 1 { next }
  { i = (NR - 2) % 200; t[i] = $1; x[i] = $2
    if (i == 199) {
      st = sx = stt = stx = 0
      for (k = 0; k < 200; k++) { st += t[k]; sx += x[k]; stt += t[k] * t[k]; stx += t[k] * x[k] }
      b = (200 * stx - st * sx) / (200 * stt - st * st); a = (sx - b * st) / 200
      s = 0; for (k = 0; k < 200; k++) { r = x[k] - a - b * t[k]; s += r * r }
      rms = sqrt(s / 200)
      if (onset == "" && t[0] > 0.1 && rms >= sigma) onset = t[0]
      if (five == "" && t[0] > 0.1 && rms >= 5 * sigma) five = t[199]
    } }
  END { print onset, five }' "$sim/timeseries.csv")
[ -n "$onset" ] && [ -n "$five" ] || fail "no onset found in the noise-free displacement"
echo "onset (chatter rms = noise rms) at $onset s; 5 x noise by $five s"

# ---- chain: chatter_monitor on the simulation's own output
mon=$work/monitor
sed "s|^file = .*|file = \"$sim/timeseries.csv\"|" "$src/studies/chatter_monitor_simulated.toml" > "$work/monitor.toml"
expect_exit 0 "$work/monitor" "$bin" run "$work/monitor.toml" --out "$mon"
for detector in bp_network rbf_density; do
  first=$(csv_column "$mon/results.csv" "${detector}_first_alarm_s")
  echo "$detector: first alarm at $first s"
  awk -v t="$first" -v on="$onset" -v five="$five" 'BEGIN { exit !(t != "" && t >= on && t <= five) }' ||
    fail "$detector: first alarm '$first' s not between the onset $onset s and 5 x noise at $five s"
  awk -F, -v d="$detector" -v on="$onset" 'NR > 1 && $2 == d && $1 < on && $4 == 1 { bad = 1 } END { exit bad }' \
    "$mon/alarms.csv" || fail "$detector: alarm on before the onset"
done
grep -q '"converged": true' "$mon/summary.json" || fail "monitor: network training did not converge"

# ---- the shipped monitor study on the committed copy
cut -d, -f1,11 "$sim/timeseries.csv" > "$work/regenerated.csv"
paste -d, "$work/regenerated.csv" "$src/studies/data/simulated_transition.csv" | awk -F, '
  NR == 1 { if ($1 != $3 || $2 != $4) bad = 1; next }
  { d = $2 - $4; if (d < 0) d = -d; if ($1 != $3 || d > 1e-12) bad = 1; n++ }
  END { exit bad || n < 1000 }' ||
  fail "studies/data/simulated_transition.csv differs from the simulation's columns"
[ "$(wc -l < "$work/regenerated.csv")" = "$(wc -l < "$src/studies/data/simulated_transition.csv")" ] ||
  fail "studies/data/simulated_transition.csv: row count differs"
shipped=$work/shipped
expect_exit 0 "$work/shipped" "$bin" run "$src/studies/chatter_monitor_simulated.toml" --out "$shipped"
for detector in bp_network rbf_density; do
  [ "$(csv_column "$shipped/results.csv" "${detector}_first_alarm_s")" = \
    "$(csv_column "$mon/results.csv" "${detector}_first_alarm_s")" ] || fail "shipped $detector: alarm differs from the chain's"
done

# ---- bad [surface] input: exit 2, key and limit named, nothing written
printf '\n[surface]\ncutoff_mm = 0.8\n' | cat <(sed '/^\[surface\]/,$d' "$src/studies/simulate_transition.toml") - > "$work/bad_surface.toml"
expect_exit 2 "$work/bad_surface" "$bin" run "$work/bad_surface.toml" --out "$work/bad_surface_out"
grep -q "surface.cutoff_mm = 0.8: a simulated work surface is a closed profile" "$work/bad_surface.err" ||
  fail "bad surface: message $(cat "$work/bad_surface.err")"
[ ! -e "$work/bad_surface_out/results.csv" ] || fail "bad surface: results written"

finish
