#!/usr/bin/env bash
# The tutorial of docs/tutorial_model.md exactly as printed (CTest sdk.tutorial):
#   1. every file the page prints (a code block after "<!-- file: NAME -->") is, byte for byte,
#      docs/tutorial/two_dof_model/NAME, and the model itself is at most 100 lines;
#   2. `cmake --install` into a temporary prefix; the project is copied out of the tree, configured
#      against the prefix only, built, and its tests pass (conformance suite + known answer);
#   3. the page's studies run with the installed chatterlab: the lobe diagram (stability_map) has
#      every point ok and certified, the simulation grows at the rate of the certified root.
# Usage: tutorial.sh BUILD_DIR SOURCE_DIR WORK_DIR
source "$(dirname "${BASH_SOURCE[0]}")/../cli/lib.sh"
build=$1 source_dir=$2 work=$3
page=$source_dir/docs/tutorial_model.md
project=$source_dir/docs/tutorial/two_dof_model
rm -rf "$work"
mkdir -p "$work/printed"

# ---- 1. the page prints the files
awk -v out="$work/printed" '
  /^<!-- file: .* -->$/ { name = $3; next }
  name != "" && /^```/ && !inside { inside = 1; file = out "/" name; printf "" > file; next }
  inside && /^```$/ { inside = 0; close(file); name = ""; next }
  inside { print >> file }' "$page"
for f in two_dof_model.cpp two_dof_model_test.cpp CMakeLists.txt lobes.toml simulate.toml; do
  if [ ! -f "$work/printed/$f" ]; then fail "the page prints no $f"; continue; fi
  cmp -s "$work/printed/$f" "$project/$f" || fail "the page's $f differs from $project/$f"
done
lines=$(wc -l < "$project/two_dof_model.cpp")
[ "$lines" -le 100 ] || fail "two_dof_model.cpp has $lines lines (the tutorial promises at most 100)"

# ---- 2. install, build out of tree, test
prefix=$work/prefix
expect_exit 0 "$work/install" cmake --install "$build" --prefix "$prefix"
cp -r "$work/printed" "$work/two_dof_model"
dir=$work/two_dof_model
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
expect_exit 0 "$work/configure" cmake -S "$dir" -B "$dir/build" "${generator[@]}" "${launcher[@]}" \
  -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF
expect_exit 0 "$work/build" cmake --build "$dir/build" -j 2
expect_exit 0 "$work/ctest" ctest --test-dir "$dir/build" --output-on-failure
grep -q "100% tests passed, 0 tests failed out of 2" "$work/ctest.out" || fail "the tutorial's two tests did not both pass"
[ -f "$dir/build/libtwo_dof_model.so" ] || { fail "no libtwo_dof_model.so"; finish; }

# ---- 3. the studies, from the project directory (their plugins = ["build/libtwo_dof_model.so"])
chatterlab=$prefix/bin/chatterlab
cd "$dir" || finish
expect_exit 0 "$work/lobes" "$chatterlab" run lobes.toml --out out/lobes --threads 2
results=out/lobes/results.csv
if [ -s "$results" ]; then
  points=$(csv_column "$results" status | wc -l)
  [ "$points" -ge 20 ] || fail "lobes: only $points grid points"
  [ "$(csv_column "$results" status | grep -vc '^ok$')" -eq 0 ] || fail "lobes: a point is not ok"
  [ "$(csv_column "$results" certified | grep -vc '^true$')" -eq 0 ] || fail "lobes: a root is not certified"
  stable=$(csv_column "$results" stable | grep -c '^true$')
  [ "$stable" -gt 0 ] && [ "$stable" -lt "$points" ] || fail "lobes: the diagram shows no lobes ($stable of $points stable)"
  is_png out/lobes/growth_rate_map.png || fail "lobes: no growth_rate_map.png"
else
  fail "lobes: no results.csv"
fi
expect_exit 0 "$work/simulate" "$chatterlab" run simulate.toml --out out/simulate
fitted=$(json_number out/simulate/summary.json fitted_growth_rate_per_s)
dominant=$(json_number out/simulate/summary.json dominant_frequency_hz)
# The certified root at the simulated point (60 rpm, the default contact stiffness 1e8 N/m). The
# work lattice puts many roots within 1 % of its growth rate (1 Hz apart at 60 rpm), so the
# envelope approaches that rate only slowly: it must not exceed it, and the dominant frequency
# must be the root's.
row=$(paste -d, <(csv_column "$results" work_speed_rpm) <(csv_column "$results" contact_stiffness_n_per_m) \
        <(csv_column "$results" growth_rate_per_s) <(csv_column "$results" chatter_frequency_hz) |
      awk -F, '$1 == 60 && $2 == 1e8 { print $3, $4 }')
read -r root frequency <<< "$row"
if [ -z "$fitted" ] || [ -z "$dominant" ] || [ -z "$root" ]; then
  fail "simulate: no fitted growth ('$fitted') or frequency ('$dominant'), or no root at 60 rpm, 1e8 N/m ('$row')"
else
  close_to "$dominant" "$frequency" 0.5 || fail "simulate: dominant frequency $dominant Hz is not the root's $frequency Hz"
  awk -v f="$fitted" -v r="$root" 'BEGIN { exit !(f > 0 && f <= 1.02 * r) }' ||
    fail "simulate: fitted growth $fitted 1/s is not in (0, the certified root's $root 1/s]"
  echo "simulated: growth $fitted 1/s at $dominant Hz; certified root: $root 1/s at $frequency Hz"
fi
finish
