#!/usr/bin/env bash
# The suppression_map study kind end to end (MODELS.md S1-S3):
# - a 2 x 3 x 3 grid: exit 0, 18 rows, the amplitude-0 rows exactly "no effect" (simulated and
#   predicted log10 ratio 0), reference.json, the three heatmaps per shape (PNG + SVG);
# - bad input exits 2 with file:line, key, value and limit, and writes nothing: an amplitude that
#   would stop the spindle (in the table and as a grid value), a negative frequency, an unknown
#   shape and target, feed modulation without a feed.
# Usage: suppression.cli.sh CHATTERLAB WORK_DIR SOURCE_DIR
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2 src=$3
rm -rf "$work" && mkdir -p "$work"
study=$src/tests/cli/studies/suppression_small.toml

out=$work/small
expect_exit 0 "$work/small" "$bin" run "$study" --out "$out"
[ "$(csv_column "$out/results.csv" status | grep -c '^ok$')" = 18 ] || fail "small: not 18 ok rows"
paste -d' ' <(csv_column "$out/results.csv" suppression.amplitude_ratio) \
            <(csv_column "$out/results.csv" log10_amplitude_ratio) \
            <(csv_column "$out/results.csv" s2_predicted_log10_ratio) > "$work/zero.txt"
awk '$1 == 0 && ($2 != 0 || $3 != 0) { bad = 1 } END { exit bad }' "$work/zero.txt" ||
  fail "small: amplitude 0 is not exactly the constant run"
awk '$1 == 0.1 && $2 < 0 { helps = 1 } END { exit !helps }' "$work/zero.txt" ||
  fail "small: 10 % modulation never helps"
grep -q '"growth_rate_per_s": 3.06' "$out/reference.json" || fail "small: reference growth rate"
for shape in square random; do
  expect_plots "$out" "log10_amplitude_ratio_wheel_speed_$shape" "s2_predicted_log10_ratio_wheel_speed_$shape" \
    "s3_energy_change_wheel_speed_$shape"
done

# bad_case NAME SED_EXPRESSION EXPECTED_MESSAGE: exit 2, the message, nothing written.
bad_case() {
  local name=$1 expr=$2 want=$3
  sed "$expr" "$study" > "$work/$name.toml"
  expect_exit 2 "$work/$name" "$bin" run "$work/$name.toml" --out "$work/out_$name"
  grep -qF -- "$want" "$work/$name.err" || { fail "$name: message"; sed 's/^/  | /' "$work/$name.err" >&2; }
  [ ! -e "$work/out_$name" ] || fail "$name: output written"
}
bad_case stop 's/^target = "wheel_speed"/target = "wheel_speed"\namplitude_ratio = 1.0/' \
  'stop.toml:20: suppression.amplitude_ratio = 1: out of range, must be >= 0 and < 1'
bad_case grid_stop 's/\[0.0, 0.02, 0.1\]/[0.0, 0.02, 1.2]/' 'suppression.amplitude_ratio = 1.2: out of range, must be >= 0 and < 1'
bad_case negative 's/^target = "wheel_speed"/target = "wheel_speed"\nfrequency_hz = -1.0/' \
  'negative.toml:20: suppression.frequency_hz = -1 [Hz]: out of range, must be > 0'
bad_case shape 's/^target = "wheel_speed"/target = "wheel_speed"\nshape = "sawtooth"/' \
  'shape.toml:20: suppression.shape = "sawtooth": not one of: random, sinusoidal, square, triangular'
bad_case target 's/^target = "wheel_speed"/target = "spindle"/' \
  'target.toml:19: suppression.target = "spindle": not one of: feed, wheel_speed, work_speed'
bad_case feed 's/^target = "wheel_speed"/target = "feed"/' \
  'suppression_map.infeed_rate_m_per_s = 0: feed modulation needs a mean infeed rate > 0'
finish
