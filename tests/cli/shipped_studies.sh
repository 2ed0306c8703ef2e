#!/usr/bin/env bash
# The ready-to-run studies in studies/ (the README's default study first) through the `chatterlab`
# command: exit 0, every point ok and certified, plots present, and numbers checked against what
# is known independently of chatterlab's solver:
# - default.toml (lobe diagram of the G8 grinder from its tap test): a limit at each of the 200
#   work speeds, all below the 35 mm the G8 grinder chattered at, the lobe diagram and the fit's
#   plots written (the limit's known answers are stability_lobes' unit tests).
# - g8_speed_map.toml (G8 experiment): every reported root solves eq 2-16 (check_plunge.awk writes
#   D(s) out in plain complex arithmetic); the centre point chatters, as the G8 grinder did; growth
#   rises with work speed at every wheel speed (workpiece regeneration: the chain's growth scales
#   with the regeneration rate 1/Tw).
# - contact_stiffness.toml (fig 2-3): kc -> 0 decouples the process from the structure, so the
#   softest contact is stable at every damping; the stiffest contact chatters at every damping;
#   so the map holds a stability boundary.
# Usage: shipped_studies.sh CHATTERLAB STUDIES_DIR WORK_DIR
source "$(dirname "$0")/lib.sh"
bin=$1 studies=$2 work=$3
rm -rf "$work" && mkdir -p "$work"

run_shipped() {  # NAME EXPECTED_ROWS
  expect_exit 0 "$work/$1" "$bin" run "$studies/$1.toml" --out "$work/$1"
  local csv=$work/$1/results.csv
  [ "$(csv_column "$csv" status | grep -c '^ok$')" -eq "$2" ] || fail "$1: not $2 points with status ok"
  [ "$(csv_column "$csv" certified | grep -c '^true$')" -eq "$2" ] || fail "$1: not every point certified"
  expect_plots "$work/$1" growth_rate_map chatter_frequency_map
}

# ---- default.toml
expect_exit 0 "$work/default" "$bin" run "$studies/default.toml" --out "$work/default"
expect_plots "$work/default" lobe_diagram time_to_chatter_map stabilisation_diagram frf_fit
[ "$(csv_column "$work/default/results.csv" speeds_with_limit)" = 200 ] || fail "default: not 200 speeds with a limit"
awk -F, 'NR > 1 { n++; if (!($2 > 0 && $2 < 35)) { print "work " $1 " rpm: critical width " $2; bad = 1 } }
         END { exit bad || n != 200 }' "$work/default/limit.csv" || fail "default: limits not all in (0, 35) mm"

# ---- g8_speed_map.toml
run_shipped g8_speed_map 247
csv=$work/g8_speed_map/results.csv
awk -v kc=2.0e8 -v kg=6.3e10 -v kw=2.0e7 -v expected_rows=247 \
  -v modes="67.56:0.03:5.53e7 102.44:0.03:1.27e8 184.08:0.03:4.11e8 221.11:0.03:5.93e8 255.01:0.03:7.88e8 275.05:0.03:9.17e8 305.60:0.03:1.132e9" \
  "$CSV_AWK$(cat "$CLI_TESTS_DIR/check_plunge.awk")" "$csv" || fail "g8_speed_map: reported roots do not solve eq 2-16"
centre=$(awk -F, '$1 == 1450 && $2 == 55 { print $3 }' "$csv")
awk -v g="$centre" 'BEGIN { exit !(g > 0) }' || fail "g8_speed_map: centre point (1450, 55 rpm) growth '$centre' is not > 0"
awk -F, 'NR > 1 { if ($1 == wheel && $3 + 0 < last + 0) { print "wheel " $1 ": growth falls at work " $2; bad = 1 }
                  wheel = $1; last = $3 } END { exit bad }' "$csv" ||
  fail "g8_speed_map: growth rate does not rise with work speed"

# ---- contact_stiffness.toml
run_shipped contact_stiffness 620
csv=$work/contact_stiffness/results.csv
awk -F, 'NR > 1 { kc[NR] = $1; g[NR] = $3; if (NR == 2 || $1 < lo) lo = $1; if ($1 > hi) hi = $1 }
         END { for (r in kc) {
                 if (kc[r] == lo && g[r] >= 0) { print "softest contact chatters: row " r; bad = 1 }
                 if (kc[r] == hi && g[r] <= 0) { print "stiffest contact stable: row " r; bad = 1 } }
               exit bad }' "$csv" || fail "contact_stiffness: limits of kc violated"

finish
