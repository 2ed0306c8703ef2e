#!/usr/bin/env bash
# A grid point whose root search fails (work budget exhausted) is recorded with its reason, the
# other points are computed, and the run exits 1. Usage: point_failure.sh CHATTERLAB WORK_DIR
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2
rm -rf "$work" && mkdir -p "$work"
out=$work/budget_failure

expect_exit 1 "$work/run" "$bin" run "$CLI_TESTS_DIR/studies/budget_failure.toml" --out "$out"
csv=$out/results.csv
[ -s "$csv" ] || fail "no results.csv"

# Rows 1-2 (budget 3e6) ok, rows 3-4 (budget 3) failed with empty outputs and the reason.
statuses=$(csv_column "$csv" status)
[ "$(echo "$statuses" | sed -n 1,2p | tr '\n' ' ')" = "ok ok " ] || fail "points 0-1 not ok: $statuses"
for row in 3 4; do
  status=$(echo "$statuses" | sed -n "${row}p")
  case $status in
    "failed: "*budget*3*) ;;
    *) fail "point $((row - 1)) status '$status' (expected the exhausted budget)" ;;
  esac
  line=$(sed -n "$((row + 1))p" "$csv")
  case $line in
    3,*,,,,,,,failed:* | 3,*,,,,,,,\"failed:*) ;;  # budget, delay, six empty outputs, status
    *) fail "failed row not empty: $line" ;;
  esac
done
# The successful points are still right.
head -n 3 "$csv" | awk -v b=0.3 -v delay_column=model.delayed.0.delay_s -v expected_rows=2 \
  "$CSV_AWK$(cat "$CLI_TESTS_DIR/check_dde.awk")" "$CLI_TESTS_DIR/reference/dde_rightmost_roots.csv" - ||
  fail "the ok points' numbers are wrong"

[ "$(json_number "$out/meta.json" points_failed)" = 2 ] || fail "meta.json: points_failed is not 2"
grep -q '"reason": "root search: evaluation budget (3) exhausted' "$out/meta.json" ||
  fail "meta.json: no reason for the failed points"
grep -q "4 points: 2 ok, 2 failed" "$work/run.out" || fail "summary line missing: $(cat "$work/run.out")"
# The map is still drawn (failed cells grey).
expect_plots "$out" growth_rate_map chatter_frequency_map
finish
