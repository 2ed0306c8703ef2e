#!/usr/bin/env bash
# Runs every shipped study (studies/*.toml) into WORK_DIR/<study>, two threads each, no progress bar.
# Usage: run_studies.sh CHATTERLAB STUDIES_DIR WORK_DIR
set -u
bin=$1 studies=$2 work=$3
mkdir -p "$work"
status=0
for study in "$studies"/*.toml; do
  name=$(basename "$study" .toml)
  rm -rf "${work:?}/$name"
  if ! "$bin" run "$study" --out "$work/$name" --threads 2 --no-progress >"$work/$name.log" 2>&1; then
    echo "FAIL: $name: chatterlab run exited non-zero" >&2
    sed 's/^/  | /' "$work/$name.log" >&2
    status=1
  fi
done
exit $status
