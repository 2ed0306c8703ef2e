#!/usr/bin/env bash
# The `simulate` study kind end to end (dynamics engine, MODELS.md G1, G7):
# - studies/simulate_g8_chatter.toml: exit 0, every output file and plot, numbers in range
#   (finite growth, chatter frequency near the G8 map's 72-75 Hz, bounded displacement);
# - studies/simulate_g7_sidebands.toml: the three largest spectral peaks are spaced by the wheel
#   rotation frequency 1450/60 = 24.17 Hz within 0.1 Hz;
# - studies/simulate_regeneration_dominance.toml: growth and frequency with both chains and with
#   the wheel chain alone equal the rightmost roots of eq 2-16 (1 % / 0.5 %);
# - the same with integrator = "adams" (CVODE instead of the default fixed-step engine): the same
#   roots;
# - the G7 study with timeseries_format = "npy" and timeseries_decimation = 7: timeseries.npy is a
#   NumPy 1.0 structured array (magic, header naming every column and the row count, float64
#   records) holding every 7th row of the CSV the same run writes without the keys;
# - bad input exits 2 with the limit named and nothing written: an unknown integrator, a run too
#   long for its output rate, a model without a time-domain form.
# Usage: simulate.cli.sh CHATTERLAB WORK_DIR SOURCE_DIR
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2 src=$3
rm -rf "$work" && mkdir -p "$work"

# ---- G8 chatter
out=$work/g8
expect_exit 0 "$work/g8" "$bin" run "$src/studies/simulate_g8_chatter.toml" --out "$out"
for f in timeseries.csv spectrum.csv surfaces_00.csv surfaces_01.csv summary.json results.csv; do
  [ -s "$out/$f" ] || fail "g8: $f missing"
done
expect_plots "$out" timeseries force envelope_fit spectrum work_surface wheel_surface
[ "$(csv_column "$out/results.csv" status)" = "ok" ] || fail "g8: status not ok"
f=$(csv_column "$out/results.csv" dominant_frequency_hz)
close_to "$f" 73 5 || fail "g8: dominant frequency $f Hz, expected ~73 Hz (the map's chatter mode)"
x=$(csv_column "$out/results.csv" max_displacement_m)
close_to "$x" 1.5e-5 1e-5 || fail "g8: max displacement $x m out of range"
head -n 1 "$out/timeseries.csv" | grep -q "^t_s,displacement_m,force_n,depth_of_cut_m" || fail "g8: timeseries header"
grep -q '"fitted_growth_rate_per_s": -\?[0-9]' "$out/summary.json" || fail "g8: no fitted growth rate"
grep -q '"dominant_frequency_hz": [0-9]' "$out/summary.json" || fail "g8: no dominant frequency"
if tail -n +2 "$out/timeseries.csv" | grep -qiE '(^|,)-?(nan|inf)'; then fail "g8: non-finite values in timeseries.csv"; fi

# ---- G7 sidebands
out=$work/g7
expect_exit 0 "$work/g7" "$bin" run "$src/studies/simulate_g7_sidebands.toml" --out "$out"
peaks=$(grep -A1 '"frequency_hz"' "$out/summary.json" | grep -o '"frequency_hz": [0-9.e+-]*' | head -n 3 |
        sed 's/.*: //' | sort -g | tr '\n' ' ')
set -- $peaks
close_to "$(awk -v a="$1" -v b="$2" 'BEGIN { print b - a }')" 24.1667 0.1 || fail "g7: sideband spacing $1 $2"
close_to "$(awk -v a="$2" -v b="$3" 'BEGIN { print b - a }')" 24.1667 0.1 || fail "g7: sideband spacing $2 $3"

# ---- wheel vs work regeneration: growth and frequency of both rows against the roots of eq 2-16
# (4.790137 /s at 361.7148 Hz with both chains; 9.1746 /s at 409.281 Hz with the wheel alone)
# run_dominance NAME STUDY: runs STUDY into $work/NAME and checks its first row (both chains) to
# 1 % / 0.5 %; leaves the columns in the arrays growth and freq.
run_dominance() {
  out=$work/$1
  expect_exit 0 "$work/$1" "$bin" run "$2" --out "$out"
  growth=($(csv_column "$out/results.csv" fitted_growth_rate_per_s))
  freq=($(csv_column "$out/results.csv" dominant_frequency_hz))
  close_to "${growth[0]:-x}" 4.790137 0.048 || fail "$1: both chains growth ${growth[0]:-none}"
  close_to "${freq[0]:-x}" 361.7148 1.8 || fail "$1: both chains frequency ${freq[0]:-none}"
}
run_dominance dominance "$src/studies/simulate_regeneration_dominance.toml"
close_to "${growth[1]}" 9.1746 0.092 || fail "dominance: wheel only growth ${growth[1]}"
close_to "${freq[1]}" 409.281 2.0 || fail "dominance: wheel only frequency ${freq[1]}"

# ---- the same study with CVODE Adams instead of the default ERK integrator: an independent
# integrator must reach the same roots (1 % / 0.5 %)
adams=$work/dominance_adams.toml
sed 's/^fit_start_s = 1.5/fit_start_s = 1.5\nintegrator = "adams"\nrelative_tolerance = 1e-5/' \
  "$src/studies/simulate_regeneration_dominance.toml" > "$adams"
run_dominance dominance_adams "$adams"

# ---- binary, decimated time series (read with od: no NumPy needed)
out=$work/g7_csv
expect_exit 0 "$work/g7_csv" "$bin" run "$src/studies/simulate_g7_sidebands.toml" --out "$out"
sed 's/^min_frequency_hz = 100/min_frequency_hz = 100\ntimeseries_format = "npy"\ntimeseries_decimation = 7/' \
  "$src/studies/simulate_g7_sidebands.toml" > "$work/g7_npy.toml"
npy=$work/g7_npy
expect_exit 0 "$work/g7_npy" "$bin" run "$work/g7_npy.toml" --out "$npy"
[ -s "$npy/timeseries.npy" ] && [ ! -e "$npy/timeseries.csv" ] || fail "npy: timeseries.npy missing or a CSV written too"
[ "$(head -c 6 "$npy/timeseries.npy" | tail -c 5)" = "NUMPY" ] || fail "npy: no NUMPY magic"
header_length=$(od -A n -t u2 -j 8 -N 2 "$npy/timeseries.npy" | tr -d ' ')
[ $(((10 + header_length) % 64)) -eq 0 ] || fail "npy: header not padded to 64 bytes ($header_length)"
rows=$(($(wc -l < "$out/timeseries.csv") - 1))
kept=$(((rows + 6) / 7))
columns=$(head -n 1 "$out/timeseries.csv" | tr ',' '\n' | wc -l)
header=$(dd if="$npy/timeseries.npy" bs=1 skip=10 count="$header_length" 2>/dev/null)
for c in $(head -n 1 "$out/timeseries.csv" | tr ',' ' '); do
  echo "$header" | grep -q "('$c', '<f8')" || fail "npy: column $c missing from the header"
done
echo "$header" | grep -q "'shape': ($kept,)" || fail "npy: shape is not ($kept,): $header"
[ $(stat -c %s "$npy/timeseries.npy") -eq $((10 + header_length + kept * columns * 8)) ] || fail "npy: file size"
# Every value equals the CSV's row 7 i (to the 17 digits od prints).
od -A n -v -t f8 -w$((columns * 8)) -j $((10 + header_length)) "$npy/timeseries.npy" |
  awk 'NR == FNR { for (c = 1; c <= NF; c++) v[NR, c] = $c; n = NR; next }
       FNR > 1 && (FNR - 2) % 7 == 0 { r = (FNR - 2) / 7 + 1; split($0, f, ",")
         for (c = 1; c <= length(f); c++) { d = v[r, c] - f[c]; if (d < 0) d = -d; a = f[c] < 0 ? -f[c] : f[c]
           if (d > 1e-15 * a + 1e-300) bad++ }; m++ }
       END { exit bad > 0 || m != n }' - FS=, "$out/timeseries.csv" || fail "npy: values differ from the CSV's every 7th row"
grep -q '"file": "timeseries.npy"' "$npy/summary.json" || fail "npy: summary.json does not name the file"

# ---- bad input
bad=$work/bad_integrator.toml
sed 's/^fit_start_s = 1.5/fit_start_s = 1.5\nintegrator = "rk4"/' \
  "$src/studies/simulate_regeneration_dominance.toml" > "$bad"
expect_exit 2 "$work/bad_integrator" "$bin" run "$bad" --out "$work/bad_integrator_out"
grep -q 'simulation.integrator = "rk4"' "$work/bad_integrator.err" && grep -q 'explicit_runge_kutta' "$work/bad_integrator.err" ||
  fail "bad integrator: message $(cat "$work/bad_integrator.err")"
[ ! -e "$work/bad_integrator_out/results.csv" ] || fail "bad integrator: results written"
bad=$work/too_long.toml
sed 's/^duration_s = 6.0/duration_s = 6000.0/' "$src/studies/simulate_g8_chatter.toml" > "$bad"
expect_exit 2 "$work/too_long" "$bin" run "$bad" --out "$work/too_long_out"
grep -q "simulation.duration_s = 6000: duration_s \* sample_rate_hz = 6e+07 output samples exceeds the limit of 5e+07" \
  "$work/too_long.err" || fail "too long: message $(cat "$work/too_long.err")"
[ ! -e "$work/too_long_out/results.csv" ] || fail "too long: results written"
bad=$work/no_time_domain.toml
cat > "$bad" <<'TOML'
[study]
kind = "simulate"
[model]
type = "linear_dde"
a0 = [[0.0, 1.0], [-1.3, -0.1]]
[simulation]
duration_s = 1.0
TOML
expect_exit 2 "$work/no_td" "$bin" run "$bad" --out "$work/no_td_out"
grep -q 'model.type = "linear_dde": this model has no time-domain form' "$work/no_td.err" ||
  fail "no time domain: message $(cat "$work/no_td.err")"
finish
