#!/usr/bin/env bash
# studies/thompson_band.toml (MODELS.md G2) through the `chatterlab` command: every point ok and
# certified, both verdicts present (stable islands and chatter), Thompson's closed-form verdict
# (closed_form_chatter_margin > 0) equal to the rightmost root's (growth_rate_per_s > 0) at every
# point, c_m equal to the 2-65 damping, and the plots drawn.
# Usage: thompson_band.cli.sh CHATTERLAB WORK_DIR SOURCE_DIR
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2 src=$3
rm -rf "$work" && mkdir -p "$work"

expect_exit 0 "$work/run" "$bin" run "$src/studies/thompson_band.toml" --out "$work/out" --no-progress
csv=$work/out/results.csv
rows=1517
[ "$(csv_column "$csv" status | grep -c '^ok$')" -eq "$rows" ] || fail "not $rows points ok"
[ "$(csv_column "$csv" certified | grep -c '^true$')" -eq "$rows" ] || fail "not every point certified"
paste -d' ' <(csv_column "$csv" growth_rate_per_s) <(csv_column "$csv" closed_form_chatter_margin) \
  <(csv_column "$csv" unconditional_damping_n_s_per_m) <(csv_column "$csv" absolute_stability_damping_n_s_per_m) |
  awk '{ root = ($1 > 0); closed = ($2 > 0); chatter += root; stable += !root
         if (root != closed) { print "row " NR ": root " $1 " vs closed-form margin " $2; bad = 1 }
         d = $3 - $4; if (d < 0) d = -d; if (d > 1e-9 * $3) { print "c_m " $3 " != 2-65 " $4; bad = 1 } }
       END { if (chatter == 0 || stable == 0) { print "no band: " chatter " chatter, " stable " stable"; bad = 1 }
             exit bad }' || fail "closed form and rightmost root disagree (or no band)"
expect_plots "$work/out" growth_rate_map chatter_frequency_map closed_form_chatter_margin
finish
