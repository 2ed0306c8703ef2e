#!/usr/bin/env bash
# Rewrites tests/regression/references/ from the current build: run it only when a change alters
# shipped results on purpose, and say in the commit message what changed and why.
# Usage: update_references.sh [BUILD_DIR]   (default build/ci)
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
build=${1:-$root/build/ci}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
bash "$root/tests/regression/run_studies.sh" "$build/framework/chatterlab" "$root/studies" "$work/out"
rm -f "$root"/tests/regression/references/*.tar.xz
for dir in "$work"/out/*/; do
  name=$(basename "$dir")
  "$build/tests/regression/compare_study_outputs" snapshot "$dir" "$work/ref/$name" "$root"
  # Sorted names and fixed metadata: the same results give the same archive bytes.
  tar --sort=name --mtime=@0 --owner=0 --group=0 --numeric-owner -C "$work/ref/$name" -cf - . |
    xz -9e >"$root/tests/regression/references/$name.tar.xz"
done
du -ch "$root"/tests/regression/references/*.tar.xz | tail -n 1
