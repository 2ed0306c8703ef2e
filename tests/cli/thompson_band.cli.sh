#!/usr/bin/env bash
# studies/thompson_band.toml and studies/thompson_damping.toml (MODELS.md G2) through the
# `chatterlab` command: every point ok and certified, both verdicts present (stable and chatter),
# Thompson's closed-form verdict (closed_form_chatter_margin > 0) equal to the rightmost root's
# (growth_rate_per_s > 0) at every point, c_m equal to the 2-65 damping, every point with damping
# above c_m stable (unconditional stability, 2-48), and the plots drawn.
# Usage: thompson_band.cli.sh CHATTERLAB WORK_DIR SOURCE_DIR
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2 src=$3
rm -rf "$work" && mkdir -p "$work"

check_study() {  # NAME ROWS
  expect_exit 0 "$work/$1" "$bin" run "$src/studies/$1.toml" --out "$work/$1" --no-progress
  local csv=$work/$1/results.csv
  [ "$(csv_column "$csv" status | grep -c '^ok$')" -eq "$2" ] || fail "$1: not $2 points ok"
  [ "$(csv_column "$csv" certified | grep -c '^true$')" -eq "$2" ] || fail "$1: not every point certified"
  paste -d' ' <(csv_column "$csv" growth_rate_per_s) <(csv_column "$csv" closed_form_chatter_margin) \
    <(csv_column "$csv" unconditional_damping_n_s_per_m) <(csv_column "$csv" absolute_stability_damping_n_s_per_m) |
    awk '{ root = ($1 > 0); closed = ($2 > 0); chatter += root; stable += !root
           if (root != closed) { print "row " NR ": root " $1 " vs closed-form margin " $2; bad = 1 }
           d = $3 - $4; if (d < 0) d = -d; if (d > 1e-9 * $3) { print "c_m " $3 " != 2-65 " $4; bad = 1 } }
         END { if (chatter == 0 || stable == 0) { print "no band: " chatter " chatter, " stable " stable"; bad = 1 }
               exit bad }' || fail "$1: closed form and rightmost root disagree (or no band)"
  expect_plots "$work/$1" growth_rate_map chatter_frequency_map closed_form_chatter_margin
}

check_study thompson_band 1517
check_study thompson_damping 1271
# Above c_m (3001 N s/m) stable at every wheel speed.
csv=$work/thompson_damping/results.csv
paste -d' ' <(csv_column "$csv" damping_n_s_per_m) <(csv_column "$csv" unconditional_damping_n_s_per_m) \
  <(csv_column "$csv" growth_rate_per_s) |
  awk '$1 > $2 { above++; if ($3 >= 0) { print "damping " $1 " > c_m " $2 " but growth " $3; bad = 1 } }
       END { if (above == 0) { print "no point above c_m"; bad = 1 }; exit bad }' ||
  fail "thompson_damping: not stable above the unconditional damping"
finish
