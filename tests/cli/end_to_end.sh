#!/usr/bin/env bash
# End-to-end runs of the stability_map studies in tests/cli/studies through the `chatterlab`
# command: exit code 0, the files (results.csv, meta.json, PNG + SVG plots), the exact header,
# and the numbers (linear_dde against independent reference roots, plunge_regenerative against
# eq 2-16 itself). Usage: end_to_end.sh CHATTERLAB WORK_DIR
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2
studies=$CLI_TESTS_DIR/studies
reference=$CLI_TESTS_DIR/reference/dde_rightmost_roots.csv
rm -rf "$work" && mkdir -p "$work"

common_columns="growth_rate_per_s,chatter_frequency_hz,stable,certified,certified_real_part_per_s,certificate,route,status"
# Models with process conditions (G1) also carry the speed-tolerance band verdict (issue 19).
wheel_columns="growth_rate_per_s,chatter_frequency_hz,growth_rate_per_wheel_rev,stable,certified,certified_real_part_per_s,certificate,route,band_worst_growth_rate_per_s,band_worst_chatter_frequency_hz,stable_over_speed_band,exact_speed_ratio,g3_growth_rate_per_s,g3_growth_rate_per_wheel_rev,g3_chatter_frequency_hz,g3_max_growth_rate_per_wheel_rev,status"
plunge_model=(-v kc=1.0e8 -v kg=5.0e9 -v kw=5.0e7 -v modes="184.08:0.05:5.0e7 305.6:0.04:8.0e7")

run_study() {  # NAME [OPTION...]: runs studies/NAME.toml into $work/NAME, expecting exit 0 and the base files
  expect_exit 0 "$work/$1" "$bin" run "$studies/$1.toml" --out "$work/$1" "${@:2}"
  [ -s "$work/$1/results.csv" ] || fail "$1: no results.csv"
  [ -s "$work/$1/meta.json" ] || fail "$1: no meta.json"
  grep -q '"state": "complete"' "$work/$1/meta.json" || fail "$1: meta.json does not say complete"
  grep -q '"git_revision": "' "$work/$1/meta.json" || fail "$1: meta.json has no git revision"
  grep -q '"sundials": "' "$work/$1/meta.json" || fail "$1: meta.json has no dependency versions"
  grep -q "\"points_failed\": 0" "$work/$1/meta.json" || fail "$1: meta.json reports failed points"
}

expect_header() {  # NAME HEADER
  [ "$(csv_header "$work/$1/results.csv")" = "$2" ] ||
    fail "$1: header '$(csv_header "$work/$1/results.csv")', expected '$2'"
}

# ---- linear_dde, 1-D: the DDE-BIFTOOL oscillator over three delays
run_study dde_1d
expect_header dde_1d "model.delayed.0.delay_s,$common_columns"
awk -v b=0.3 -v delay_column=model.delayed.0.delay_s -v expected_rows=3 "$CSV_AWK$(cat "$CLI_TESTS_DIR/check_dde.awk")" \
  "$reference" "$work/dde_1d/results.csv" || fail "dde_1d: numbers differ from the reference"
# The headline value, spelled out: tau = 10 -> 0.038562247054131913 + 1.1222499565638465i.
row=$(grep -n '^10,' "$work/dde_1d/results.csv" | cut -d: -f1)
growth=$(csv_column "$work/dde_1d/results.csv" growth_rate_per_s | sed -n "$((row - 1))p")
close_to "$growth" 0.038562247054131913 1e-9 || fail "dde_1d: tau = 10 growth rate $growth"
expect_plots "$work/dde_1d" growth_rate chatter_frequency
# stderr is not a terminal here: no progress bar, no output at all.
[ ! -s "$work/dde_1d.err" ] || fail "dde_1d: stderr not silent: $(cat "$work/dde_1d.err")"

# ---- linear_dde, 2-D: gain x delay, every cell against the reference (progress bar forced on)
run_study dde_2d --progress
grep -q "20/20 points .* elapsed  ETA" "$work/dde_2d.err" || fail "dde_2d: no progress bar with --progress"
expect_header dde_2d "model.delayed.0.matrix.1.0,model.delayed.0.delay_s,$common_columns"
awk -v b_column=model.delayed.0.matrix.1.0 -v delay_column=model.delayed.0.delay_s -v expected_rows=20 \
  "$CSV_AWK$(cat "$CLI_TESTS_DIR/check_dde.awk")" "$reference" "$work/dde_2d/results.csv" ||
  fail "dde_2d: numbers differ from the reference"
# Grid order: the last key varies fastest.
[ "$(cut -d, -f1,2 "$work/dde_2d/results.csv" | sed -n '2,7p' | tr '\n' ' ')" = "0.1,2 0.1,4 0.1,6 0.1,8 0.1,10 0.2,2 " ] ||
  fail "dde_2d: rows not in grid order"
expect_plots "$work/dde_2d" growth_rate_map chatter_frequency_map

# ---- plunge_regenerative (G1), 1-D wheel-speed sweep and 2-D work x wheel speed
run_study plunge_1d
expect_header plunge_1d "wheel_speed_rpm,$wheel_columns"
awk "${plunge_model[@]}" -v work_rpm=55 -v expected_rows=7 "$CSV_AWK$(cat "$CLI_TESTS_DIR/check_plunge.awk")" \
  "$work/plunge_1d/results.csv" || fail "plunge_1d: reported roots do not solve eq 2-16"
expect_plots "$work/plunge_1d" growth_rate chatter_frequency

run_study plunge_2d
expect_header plunge_2d "work_speed_rpm,wheel_speed_rpm,$wheel_columns"
awk "${plunge_model[@]}" -v expected_rows=20 "$CSV_AWK$(cat "$CLI_TESTS_DIR/check_plunge.awk")" \
  "$work/plunge_2d/results.csv" || fail "plunge_2d: reported roots do not solve eq 2-16"
expect_plots "$work/plunge_2d" growth_rate_map chatter_frequency_map
# The log-spaced work-speed axis is drawn on a log scale.
grep -q "logscale y" "$work/plunge_2d/growth_rate_map.gp" || fail "plunge_2d: y axis not logarithmic"

finish
