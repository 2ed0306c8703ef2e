#!/usr/bin/env bash
# The SDK commands of the built `chatterlab` (CTest sdk.commands): check-plugin on a conforming
# and on a broken library, init for every study kind (validate accepts what it writes, wherever
# the file is), --plugin on validate and run, and new-plugin's refusals.
# Usage: commands.sh CHATTERLAB SOURCE_DIR EXAMPLE_PLUGIN BROKEN_PLUGIN WORK_DIR
source "$(dirname "${BASH_SOURCE[0]}")/../cli/lib.sh"
chatterlab=$1 source_dir=$2 example=$3 broken=$4 work=$5
rm -rf "$work"
mkdir -p "$work"

# ---- check-plugin
expect_exit 0 "$work/check_example" "$chatterlab" check-plugin "$example"
grep -q "^ok   model 'example_delay_model': specs" "$work/check_example.out" || fail "check-plugin: no specs line"
grep -q "^ok   model 'example_delay_model': threads: 4 threads, shareable" "$work/check_example.out" ||
  fail "check-plugin: the thread-safety check did not run"
grep -q "built for chatterlab [0-9.]* (plugin API [0-9]*) with GCC" "$work/check_example.out" ||
  fail "check-plugin: no build record line"
grep -q "^1 plugin checked: [0-9]* checks passed, 0 failed" "$work/check_example.out" || fail "check-plugin: no summary"

expect_exit 1 "$work/check_broken" "$chatterlab" check-plugin "$broken"
grep -q "^FAIL model 'broken_model': model: E'(s) disagrees with a difference of E" "$work/check_broken.out" ||
  fail "check-plugin did not report the wrong derivative"
grep -q "^FAIL model 'broken_model': threads: .*declared shareable" "$work/check_broken.out" ||
  fail "check-plugin did not report the broken thread-safety declaration"

expect_exit 2 "$work/check_text" "$chatterlab" check-plugin "$source_dir/README.md"
grep -q "chatterlab: error: cannot load plugin library '$source_dir/README.md'" "$work/check_text.err" ||
  fail "check-plugin on a text file: $(cat "$work/check_text.err")"

# ---- init: every registered study kind gets a study that validates, written anywhere: a kind
# that needs a data file starts from a shipped study and names its files by absolute path.
"$chatterlab" list | awk -F '  +' '$1 == "study kind" { print $2 }' > "$work/kinds"
[ "$(wc -l < "$work/kinds")" -ge 5 ] || fail "fewer than 5 study kinds listed"
mkdir -p "$work/elsewhere"
while read -r kind; do
  expect_exit 0 "$work/init_$kind" "$chatterlab" init "$kind" -o "$work/$kind.toml"
  grep -q "^kind = \"$kind\"" "$work/$kind.toml" || fail "init $kind: no [study] kind line"
  ! grep -q "not valid yet" "$work/init_$kind.err" || fail "init $kind: $(cat "$work/init_$kind.err")"
  ! grep -q "NOT YET VALID" "$work/$kind.toml" || fail "init $kind wrote a study marked NOT YET VALID"
  cp "$work/$kind.toml" "$work/elsewhere/$kind.toml"
  expect_exit 0 "$work/validate_$kind" "$chatterlab" validate "$work/elsewhere/$kind.toml"
done < "$work/kinds"
echo "init: all $(wc -l < "$work/kinds") study kinds valid as written"
grep -q "^# .*\[Hz\]" "$work/stability_map.toml" || fail "init stability_map: keys are not commented with units"
grep -q "started from signal_analysis_" "$work/init_signal_analysis.err" || fail "init signal_analysis: no shipped study named"
data_file=$(sed -n 's/^file = "\(.*\)"$/\1/p' "$work/signal_analysis.toml" | head -1)
case "$data_file" in /*) [ -f "$data_file" ] || fail "init signal_analysis: $data_file does not exist" ;;
  *) fail "init signal_analysis: data file '$data_file' is not an absolute path" ;; esac
grep -q "^# Its data files are named by absolute path" "$work/signal_analysis.toml" || fail "init: no note on data files"
expect_exit 0 "$work/init_example_study" "$chatterlab" init feed_plan --example feed_plan_problem2 -o "$work/problem2.toml"
grep -q "^# Started from the shipped study .*feed_plan_problem2.toml" "$work/problem2.toml" || fail "init --example: not based on it"
expect_exit 0 "$work/validate_problem2" "$chatterlab" validate "$work/problem2.toml"
expect_exit 2 "$work/init_bad_example" "$chatterlab" init feed_plan --example nothing_like_it
grep -q "no shipped study of kind 'feed_plan' has that name; shipped: feed_plan_fillet, feed_plan_measured, feed_plan_problem1" \
  "$work/init_bad_example.err" || fail "init --example with an unknown name: $(cat "$work/init_bad_example.err")"
expect_exit 2 "$work/init_again" "$chatterlab" init stability_map -o "$work/stability_map.toml"
grep -q "exists; give --force" "$work/init_again.err" || fail "init overwrote a file without --force"

# An out-of-tree model in an initialised study: the library is named under `plugins`.
expect_exit 0 "$work/init_example" "$chatterlab" init stability_map --model example_delay_model \
  --plugin "$example" -o "$work/example.toml"
grep -q "^plugins = \[\"$(readlink -f "$example")\"\]" "$work/example.toml" || fail "init: plugins line missing"
expect_exit 0 "$work/validate_example" "$chatterlab" validate "$work/example.toml"

# ---- --plugin on validate and run
sed '/^plugins = /d' "$work/example.toml" > "$work/no_plugins.toml"
expect_exit 2 "$work/validate_no_plugin" "$chatterlab" validate "$work/no_plugins.toml"
expect_exit 0 "$work/validate_plugin" "$chatterlab" validate "$work/no_plugins.toml" --plugin "$example"
grep -q "plugin      $(readlink -f "$example")" "$work/validate_plugin.out" || fail "validate --plugin: library not listed"
expect_exit 0 "$work/run_plugin" "$chatterlab" run "$work/no_plugins.toml" --plugin "$example" --out "$work/run_plugin_out"
grep -q "$(readlink -f "$example")" "$work/run_plugin_out/meta.json" || fail "run --plugin: meta.json does not record the library"

# ---- new-plugin refuses, writing nothing
expect_exit 2 "$work/bad_name" "$chatterlab" new-plugin --kind model My-Model "$work/bad_name_dir"
grep -q "must be snake_case" "$work/bad_name.err" || fail "new-plugin: bad name not explained"
[ ! -e "$work/bad_name_dir" ] || fail "new-plugin wrote into a refused project"
expect_exit 2 "$work/clash" "$chatterlab" new-plugin --kind model plunge_regenerative "$work/clash_dir"
grep -q "already the name of a built-in" "$work/clash.err" || fail "new-plugin: name clash not explained"
mkdir -p "$work/full" && touch "$work/full/keep"
expect_exit 2 "$work/full_dir" "$chatterlab" new-plugin --kind analysis my_analysis "$work/full"
grep -q "exists and is not an empty directory; nothing written" "$work/full_dir.err" || fail "new-plugin: non-empty directory"
expect_exit 2 "$work/bad_kind" "$chatterlab" new-plugin --kind solver my_solver "$work/solver"
finish
