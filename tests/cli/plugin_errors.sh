#!/usr/bin/env bash
# Whatever a plugin throws, of any type: exit 2 at load time (naming the library, the plugin and
# the study file and line), a failed point at run time (naming them too); never "terminate
# called" (exit 134).
# Usage: plugin_errors.sh CHATTERLAB WORK_DIR MISBEHAVING_PLUGIN THROWING_ENTRY_PLUGIN
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2 plugin=$3 throwing=$4
rm -rf "$work" && mkdir -p "$work"

expect_message() {  # LOG TEXT...
  local log=$1
  shift
  for text in "$@"; do
    grep -qF -- "$text" "$log.err" || fail "message lacks '$text': $(cat "$log.err")"
  done
  grep -q "terminate called" "$log.err" && fail "terminate called: $(cat "$log.err")"
}

# An entry point that throws an int.
{ echo "plugins = [\"$throwing\"]"; printf '[study]\nkind = "stability_map"\n[model]\ntype = "plunge_regenerative"\n'; } >"$work/entry.toml"
expect_exit 2 "$work/entry" "$bin" run "$work/entry.toml" --out "$work/entry_out"
expect_message "$work/entry" "entry.toml:1:" "$throwing" "failed to register: an exception of type 'int' (not derived from std::exception)"
expect_exit 2 "$work/entry_list" "$bin" list --plugin "$throwing"
expect_message "$work/entry_list" "$throwing" "an exception of type 'int'"
[ ! -e "$work/entry_out" ] || fail "output directory created"

# A constructor that throws an int at load time: the table's line, the plugin and library.
misbehaving_study "$work/ctor.toml" "$plugin" '["ok"]'
sed -i 's/^sleep_s = 1$/sleep_s = 1\nbehaviour = "throw_in_constructor"/' "$work/ctor.toml"
sed -i 's/^"model.behaviour" = .*$//' "$work/ctor.toml"
expect_exit 2 "$work/ctor" "$bin" run "$work/ctor.toml" --out "$work/ctor_out"
expect_message "$work/ctor" "ctor.toml:5:" "model plugin 'misbehaving_model' (library $plugin)" \
  "its constructor threw an exception of type 'int'"
[ ! -e "$work/ctor_out" ] || fail "output directory created"
# ... and when only one grid value makes it throw: the grid key's line and the value.
misbehaving_study "$work/ctor_grid.toml" "$plugin" '["ok", "throw_in_constructor"]'
expect_exit 2 "$work/ctor_grid" "$bin" validate "$work/ctor_grid.toml"
expect_message "$work/ctor_grid" "ctor_grid.toml:11:" "model.behaviour, value 2 of 2" \
  "model plugin 'misbehaving_model' (library $plugin): its constructor threw an exception of type 'int'"

# At run time, in-process: the point fails with the type, the plugin, its library and the study.
misbehaving_study "$work/run.toml" "$plugin" '["ok", "throw_int"]'
expect_exit 1 "$work/run" "$bin" run "$work/run.toml" --out "$work/run_out" --threads 2
[ "$(grep -cF "failed: an exception of type 'int' (not derived from std::exception) (out-of-tree plugins of this point: model plugin 'misbehaving_model' (library $plugin); study $work/run.toml)" "$work/run_out/results.csv")" = 3 ] ||
  fail "run-time throw not recorded with plugin and study: $(cat "$work/run_out/results.csv")"
finish
