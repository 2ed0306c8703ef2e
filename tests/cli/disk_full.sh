#!/usr/bin/env bash
# A full disk (a small tmpfs): exit 3, meta.json says what could not be written, no partial or
# empty file is left; once there is room, --resume completes the run with the same results.
# Points whose own files did not fit fail with the reason; --resume --retry-failed computes them
# again. Needs root to mount a tmpfs: otherwise the test is skipped (exit 77).
# Usage: disk_full.sh CHATTERLAB WORK_DIR SOURCE_DIR
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2 src=$3
mnt=$work/disk
umount "$mnt" 2>/dev/null
rm -rf "$work" && mkdir -p "$mnt"
if ! mount -t tmpfs -o size=96k tmpfs "$mnt" 2>"$work/mount.err"; then
  echo "SKIP: cannot mount a tmpfs here (needs root): $(cat "$work/mount.err")"
  exit 77
fi
trap 'umount "$mnt" 2>/dev/null' EXIT
resize() { mount -o "remount,size=$1" "$mnt" || fail "cannot resize the tmpfs to $1"; }
# Every image left behind is whole: a PNG ends with its IEND chunk, an SVG with </svg>.
whole_images() {
  local f
  for f in $(find "$1" -name '*.png'); do
    [ "$(tail -c 8 "$f" | od -An -tx1 | tr -d ' \n')" = "49454e44ae426082" ] || fail "partial PNG $f"
  done
  for f in $(find "$1" -name '*.svg'); do
    tail -c 16 "$f" | grep -q "</svg>" || fail "partial SVG $f"
  done
}
study=$CLI_TESTS_DIR/studies/plunge_2d.toml
expect_exit 0 "$work/ref" "$bin" run "$study" --out "$work/ref"

# 96 KiB: results.csv does not fit (after the journal and meta.json).
out=$mnt/out
expect_exit 3 "$work/full_results" "$bin" run "$study" --out "$out"
grep -q "output could not be written: cannot write $out/results.csv: No space left on device" \
  "$work/full_results.err" || fail "message: $(cat "$work/full_results.err")"
grep -q '"state": "output_failed"' "$out/meta.json" || fail "meta.json does not say output_failed"
grep -q '"output_error": "cannot write .*results.csv: No space left on device"' "$out/meta.json" ||
  fail "meta.json does not name results.csv"
[ ! -e "$out/results.csv" ] || fail "a partial results.csv was left"
no_partial_files "$out"
whole_images "$out"
# Room again: --resume writes the same results (from the journal, nothing recomputed).
resize 16m
expect_exit 0 "$work/resumed" "$bin" run "$study" --out "$out" --resume
cmp "$work/ref/results.csv" "$out/results.csv" || fail "resumed results.csv differs"
[ "$(json_number "$out/meta.json" points_computed)" = 0 ] || fail "the journal was not used"
whole_images "$out"

# 160 KiB: results.csv fits, the plots do not: exit 3, no partial image.
rm -rf "$out" && resize 160k
expect_exit 3 "$work/full_plots" "$bin" run "$study" --out "$out"
grep -q "output could not be written: plots: .*No space left on device" "$work/full_plots.err" ||
  fail "message: $(cat "$work/full_plots.err")"
grep -q '"state": "output_failed"' "$out/meta.json" || fail "meta.json does not say output_failed (plots)"
cmp "$work/ref/results.csv" "$out/results.csv" || fail "results.csv of the plot failure differs"
no_partial_files "$out"
whole_images "$out"
resize 16m
expect_exit 0 "$work/plots_resumed" "$bin" run "$study" --out "$out" --resume
for stem in growth_rate_map chatter_frequency_map; do
  cmp "$work/ref/$stem.dat" "$out/$stem.dat" || fail "$stem.dat differs after the resume"
done
expect_plots "$out" growth_rate_map chatter_frequency_map
whole_images "$out"

# Points that write their own files (a surface study, ~2.1 MB a point): 7 MiB holds a few. The
# others fail with the reason, the run exits 3; --resume keeps them failed (exit 1);
# --resume --retry-failed computes them again.
rm -rf "$out" && resize 7m
cp "$src/studies/data/surface_g8_roundness.csv" "$work/profile.csv"
{
  printf '[study]\nkind = "surface"\n[input]\nfile = "profile.csv"\ncolumn = "radius_um"\n'
  printf 'closed = true\nsamples_per_rev = 7200\nunit = "um"\n[filter]\ntype = "gaussian"\n'
  printf '[grid]\n"filter.cutoff_upr" = [15, 50, 150, 500]\n'
} >"$work/surface.toml"
expect_exit 0 "$work/surface_ref" "$bin" run "$work/surface.toml" --out "$work/surface_ref" --threads 1
expect_exit 3 "$work/surface_full" "$bin" run "$work/surface.toml" --out "$out" --threads 1
failed=$(grep -c 'No space left on device\|could not be written' "$out/results.csv" 2>/dev/null || echo 0)
[ "$failed" -ge 1 ] || fail "no point failed for lack of space: $(cat "$work/surface_full.err")"
grep -q "point(s) could not write their files" "$out/meta.json" || fail "meta.json does not say which outputs failed"
no_partial_files "$out"
whole_images "$out"
resize 64m
expect_exit 1 "$work/surface_resume" "$bin" run "$work/surface.toml" --out "$out" --resume
expect_exit 0 "$work/surface_retry" "$bin" run "$work/surface.toml" --out "$out" --resume --retry-failed
cmp "$work/surface_ref/results.csv" "$out/results.csv" || fail "retried results.csv differs"
[ "$(json_number "$out/meta.json" points_computed)" = "$failed" ] ||
  fail "--retry-failed computed $(json_number "$out/meta.json" points_computed) points, not the $failed failed ones"
finish
