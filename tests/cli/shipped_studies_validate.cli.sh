#!/usr/bin/env bash
# Every ready-to-run study in studies/ passes `chatterlab validate` (exit 0, writes nothing), so a
# change to a study kind's keys cannot silently break a shipped study that no other test runs.
# `validate` also reads and checks each study's input data files (studies/data/).
# Usage: shipped_studies_validate.cli.sh CHATTERLAB WORK_DIR SOURCE_DIR
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2 src=$3
rm -rf "$work" && mkdir -p "$work"

count=0
for study in "$src"/studies/*.toml; do
  name=$(basename "$study" .toml)
  expect_exit 0 "$work/$name" "$bin" validate "$study" --allow-large
  count=$((count + 1))
done
[ "$count" -ge 30 ] || fail "only $count studies found in $src/studies"
[ -z "$(ls -A "$src/studies" | grep -v '\.toml$' | grep -v '^data$')" ] ||
  fail "validate wrote into studies/: $(ls -A "$src/studies" | grep -v '\.toml$' | grep -v '^data$')"
finish
