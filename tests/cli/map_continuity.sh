#!/usr/bin/env bash
# Continuity of the stability map across grid neighbours (MODELS.md G1): the growth rate is the
# largest real part over the roots, a continuous function of the parameters, but it turns sharply
# where the rightmost root switches branch (a new wheel lobe takes over). A missed root would show
# as a jump that does not shrink under refinement. So: sweep the wheel speed, take the steepest
# step, refine that interval tenfold, twice; a continuous map's jump shrinks with the step, a
# discontinuity's would not. Also: refined grids reproduce the coarse grid's values bit for bit
# at shared points (a point depends on its parameters only, not on its neighbours).
# Usage: map_continuity.sh CHATTERLAB WORK_DIR
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2
rm -rf "$work" && mkdir -p "$work"
template=$CLI_TESTS_DIR/studies/plunge_1d.toml

# sweep NAME FROM TO STEPS: runs the plunge_1d study over wheel_speed_rpm = FROM..TO and sets
# a, b, jump: the grid step with the largest change of growth_rate_per_s. (Not in a subshell: the
# checks inside must count.)
sweep() {
  sed -e "/^\[grid\]/,\$ s/^wheel_speed_rpm = .*/wheel_speed_rpm = { from = $2, to = $3, steps = $4 }/" \
    "$template" >"$work/$1.toml"
  expect_exit 0 "$work/$1" "$bin" run "$work/$1.toml" --out "$work/$1" --threads 2
  local csv=$work/$1/results.csv
  [ "$(csv_column "$csv" wheel_speed_rpm | wc -l)" = "$4" ] || fail "$1: not $4 grid points"
  [ -z "$(csv_column "$csv" certified | grep -v '^true$')" ] || fail "$1: uncertified points"
  paste -d' ' <(csv_column "$csv" wheel_speed_rpm) <(csv_column "$csv" growth_rate_per_s) |
    awk 'NR > 1 { d = $2 - p; if (d < 0) d = -d; if (d > m) { m = d; a = x; b = $1 } }
         { x = $1; p = $2 } END { printf "%s %s %.17g\n", a, b, m }' >"$work/$1.steepest"
  read -r a b jump <"$work/$1.steepest"
}

growth_at() {  # NAME SPEED: growth_rate_per_s of that row, as written
  paste -d' ' <(csv_column "$work/$1/results.csv" wheel_speed_rpm) <(csv_column "$work/$1/results.csv" growth_rate_per_s) |
    awk -v s="$2" '$1 == s { print $2 }'
}

sweep level0 1400 1500 51 && a0=$a b0=$b jump0=$jump
sweep level1 "$a0" "$b0" 11 && a1=$a b1=$b jump1=$jump
sweep level2 "$a1" "$b1" 11 && a2=$a b2=$b jump2=$jump
echo "steepest steps: $jump0 on [$a0, $b0], $jump1 on [$a1, $b1], $jump2 on [$a2, $b2] (1/s)"

awk -v j0="$jump0" -v j2="$jump2" 'BEGIN { exit !(j0 > 0 && j2 <= 0.25 * j0) }' ||
  fail "the largest jump of the growth rate does not shrink under refinement ($jump0 -> $jump2): a discontinuity"
for speed in "$a0" "$b0"; do
  [ -n "$(growth_at level0 "$speed")" ] && [ "$(growth_at level0 "$speed")" = "$(growth_at level1 "$speed")" ] ||
    fail "wheel speed $speed: growth rate differs between the coarse and the refined grid"
done
finish
