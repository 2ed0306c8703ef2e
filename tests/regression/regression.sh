#!/usr/bin/env bash
# Regression test: every shipped study's result files equal the stored references
# (tests/regression/references/<study>.tar.xz; README.md says what is compared and how), and the
# claims its header states ("# claim:" lines) hold in the same outputs.
# Usage: regression.sh CHATTERLAB COMPARE_TOOL STUDIES_DIR WORK_DIR CLAIMS_TOOL
set -u
bin=$1 compare=$2 studies=$3 work=$4 claims=$5
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
rm -rf "$work" && mkdir -p "$work/out" "$work/ref"
bash "$here/run_studies.sh" "$bin" "$studies" "$work/out" || exit 1
failed=0
for study in "$studies"/*.toml; do
  name=$(basename "$study" .toml)
  archive=$here/references/$name.tar.xz
  if [ ! -f "$archive" ]; then
    echo "FAIL: $name: no reference (run tests/regression/update_references.sh and commit it)" >&2
    failed=$((failed + 1))
    continue
  fi
  mkdir -p "$work/ref/$name" && tar -xJf "$archive" -C "$work/ref/$name"
  if ! "$compare" compare "$work/ref/$name" "$work/out/$name" "$(dirname "$studies")" >"$work/$name.diff"; then
    echo "FAIL: $name differs from its reference:" >&2
    sed 's/^/  | /' "$work/$name.diff" >&2
    failed=$((failed + 1))
  fi
done
for archive in "$here"/references/*.tar.xz; do
  name=$(basename "$archive" .tar.xz)
  [ -f "$studies/$name.toml" ] || { echo "FAIL: reference $name.tar.xz has no study" >&2; failed=$((failed + 1)); }
done
"$claims" "$studies" "$work/out" >"$work/claims.log"
claims_status=$?
[ "$claims_status" -eq 0 ] || sed 's/^/  | /' "$work/claims.log" >&2
[ "$failed" -eq 0 ] || { echo "$failed studies differ from their references" >&2; exit 1; }
[ "$claims_status" -eq 0 ] || { echo "shipped studies' claims fail" >&2; exit 1; }
echo "all shipped studies match their references; $(tail -n 1 "$work/claims.log")"
