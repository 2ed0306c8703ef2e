#!/usr/bin/env bash
# Bad input through the command: exit 2, a message naming the file, key and value, and nothing
# written to the output directory; unusable output directories are bad input too.
# Usage: bad_input.sh CHATTERLAB WORK_DIR
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2
rm -rf "$work" && mkdir -p "$work"
studies=$CLI_TESTS_DIR/studies

expect_message() {  # LOG TEXT...: every TEXT appears in LOG.err
  local log=$1
  shift
  for text in "$@"; do
    grep -qF -- "$text" "$log.err" || fail "message lacks '$text': $(cat "$log.err")"
  done
}

# A bad model value: nothing created.
expect_exit 2 "$work/damping" "$bin" run "$studies/bad_damping.toml" --out "$work/damping_out"
expect_message "$work/damping" "bad_damping.toml:" "model.modes.0.damping_ratio = 1.5" "< 1"
[ ! -e "$work/damping_out" ] || fail "output directory created for a bad study"

# A misspelt [stability] key: named with the valid keys; an existing empty directory stays empty.
mkdir -p "$work/key_out"
expect_exit 2 "$work/key" "$bin" run "$studies/bad_stability_key.toml" --out "$work/key_out"
expect_message "$work/key" "bad_stability_key.toml:" "stability.max_frequency" \
  "max_frequency_hz, max_function_evaluations, max_newton_iterations, newton_relative_tolerance"
[ -z "$(ls -A "$work/key_out")" ] || fail "files written for a bad study: $(ls -A "$work/key_out")"

# Unusable output directories, with a valid study.
good=$studies/dde_1d.toml
expect_exit 2 "$work/proc" "$bin" run "$good" --out /proc/chatterlab_cli_test/out
expect_message "$work/proc" "/proc/chatterlab_cli_test/out"
echo "not a directory" >"$work/a_file"
expect_exit 2 "$work/file" "$bin" run "$good" --out "$work/a_file"
expect_message "$work/file" "$work/a_file" "not a directory"
expect_exit 2 "$work/under_file" "$bin" run "$good" --out "$work/a_file/out"
[ "$(cat "$work/a_file")" = "not a directory" ] || fail "the file given as --out was changed"

# A directory with someone else's files is never cleared.
mkdir -p "$work/foreign" && echo "keep me" >"$work/foreign/notes.txt"
expect_exit 2 "$work/foreign_run" "$bin" run "$good" --out "$work/foreign"
expect_message "$work/foreign_run" "not written by chatterlab"
[ "$(ls -A "$work/foreign")" = "notes.txt" ] || fail "files added to a foreign directory: $(ls -A "$work/foreign")"
finish
