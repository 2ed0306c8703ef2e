#!/usr/bin/env bash
# The error_separation study kind through the `chatterlab` command (MODELS.md E1-E6):
# - the shipped three-probe study: exit 0, profile.csv equals the true profile stated in the
#   study header (awk evaluates r(theta) independently), summary.json lists no suppressed
#   harmonic, the plots exist;
# - probe angles sharing a factor with N (0, 30, 100 deg at N = 360): exit 0 with a warning on
#   stderr and the suppressed harmonics 35, 37, ... in summary.json; with
#   on_suppressed = "error": exit 2, the harmonics named, nothing written;
# - the cylindricity study: sections.csv holds the stated section radii;
# - bad input (missing column, unequal lengths): exit 2, message text, no output directory.
# Usage: error_separation.cli.sh CHATTERLAB WORK_DIR SOURCE_DIR
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2 src=$3
rm -rf "$work" && mkdir -p "$work"

# An error_separation study at $1: its [input] source line $2 (file or files), columns $3 and probe
# angles $4, one key a line (line 5: columns, line 7: angles_deg).
write_probe_study() {
  printf '[study]\nkind = "error_separation"\n[input]\n%s\ncolumns = %s\n[probes]\nangles_deg = %s\n' "$2" "$3" "$4" > "$1"
}

# ---- shipped three-probe study
out=$work/three
expect_exit 0 "$work/three" "$bin" run "$src/studies/error_separation_three_probe.toml" --out "$out"
[ "$(csv_header "$out/profile.csv")" = "angle_deg,deviation_um" ] || fail "profile.csv header"
[ "$(csv_header "$out/spindle.csv")" = "angle_deg,dx_um,dy_um" ] || fail "spindle.csv header"
paste -d, <(csv_column "$out/profile.csv" angle_deg) <(csv_column "$out/profile.csv" deviation_um) |
  awk -F, '{ t = $1 * atan2(0, -1) / 180
             r = 2.0 * cos(3 * t + 0.5) + cos(5 * t) + 0.5 * sin(18 * t) + 0.3 * cos(40 * t + 1)
             d = $2 - r; if (d < 0) d = -d; if (d > worst) worst = d; n++ }
           END { if (n != 360 || worst > 1e-9) { print "rows " n ", worst deviation " worst; exit 1 } }' ||
  fail "three_probe: profile.csv is not the true profile"
grep -q '"suppressed_harmonics": \[\]' "$out/summary.json" || fail "three_probe: suppressed_harmonics not empty"
grep -A4 '"first_harmonic_check"' "$out/summary.json" | grep -q '"valid": true' || fail "three_probe: validity check"
expect_plots "$out" profile_polar profile_linear spindle_motion transfer_g transfer_q suppression_map

# ---- suppressed harmonics: warning (exit 0) or error (exit 2)
mkdir -p "$work/supp"
awk 'BEGIN { pi = atan2(0, -1); print "A,B,C"
  for (i = 0; i < 360; i++) { t = 2 * pi * i / 360; line = ""
    for (q = 0; q < 3; q++) { p = (q == 0 ? 0 : (q == 1 ? 30 : 100)) * pi / 180
      y = cos(3 * (t + p)) + 0.5 * sin(7 * (t + p)) + 0.3 * cos(2 * t) * cos(p) + 0.2 * sin(t) * sin(p)
      line = line (q ? "," : "") sprintf("%.15g", y) }
    print line } }' > "$work/supp/probes.csv"
write_probe_study "$work/supp/warn.toml" 'file = "probes.csv"' '["A", "B", "C"]' '[0, 30, 100]'
expect_exit 0 "$work/supp/warn" "$bin" run "$work/supp/warn.toml" --out "$work/supp/warn_out"
grep -q "warning: .*harmonics 35, 37, 71, 73" "$work/supp/warn.err" || fail "no suppression warning on stderr"
tr -d ' \n' < "$work/supp/warn_out/summary.json" | grep -q '"suppressed_harmonics":\[35,37,71,73,107,109,143,145,179\]' ||
  fail "summary.json suppressed_harmonics is not [35, 37, 71, 73, 107, 109, 143, 145, 179]"
sed 's/^angles_deg.*/&\non_suppressed = "error"/' "$work/supp/warn.toml" > "$work/supp/error.toml"
expect_exit 2 "$work/supp/error" "$bin" run "$work/supp/error.toml" --out "$work/supp/error_out"
grep -q 'error.toml:7: .*harmonics 35, 37, 71, 73' "$work/supp/error.err" || fail "suppression error message"
[ ! -e "$work/supp/error_out" ] || fail "output written despite exit 2"

# ---- a layout that loses harmonics: degraded, said in summary, results, stderr and plots
out=$work/degraded
expect_exit 0 "$work/degraded" "$bin" run "$src/studies/error_separation_degraded.toml" --out "$out"
[ "$(csv_column "$out/results.csv" separation_status)" = "degraded" ] || fail "degraded: separation_status"
[ "$(csv_column "$out/results.csv" worst_error_transfer_q)" = "inf" ] || fail "degraded: worst Q not inf"
[ "$(csv_column "$out/results.csv" suppressed_harmonic_count)" = "89" ] || fail "degraded: not 89 lost harmonics"
grep -q '"status": "degraded"' "$out/summary.json" || fail "degraded: summary status"
grep -q "warning: .*degraded: harmonics 3, 5, 7, .* hold 69.4 % of the probe signals' power" "$work/degraded.err" ||
  fail "degraded: warning: $(cat "$work/degraded.err")"
grep -q '^3,.*,inf,inf,1$' "$out/transfer.csv" || fail "degraded: transfer.csv row of harmonic 3"
grep -q 'DEGRADED' "$out/profile_polar.gp" || fail "degraded: polar plot does not say so"
expect_plots "$out" profile_polar transfer_q transfer_g probe_spectrum

# ---- cylindricity
out=$work/cyl
expect_exit 0 "$work/cyl" "$bin" run "$src/studies/error_separation_cylinder.toml" --out "$out"
paste -d, <(csv_column "$out/sections.csv" z_mm) <(csv_column "$out/sections.csv" mean_radius_difference_um) |
  awk -F, '{ d = $2 - (3 + 0.01 * $1); if (d < 0) d = -d; if (d > 1e-8) bad = 1; n++ } END { exit bad || n != 5 }' ||
  fail "cylinder: section radii are not 3 + 0.01 z"
expect_plots "$out" cylinder_sections cylinder_form

# ---- bad input
mkdir -p "$work/bad"
printf 'A,B\n1,2\n3,4\n' > "$work/bad/two.csv"
printf 'X\n1\n2\n3\n4\n5\n6\n7\n8\n' > "$work/bad/eight.csv"
printf 'X\n1\n2\n3\n4\n5\n6\n7\n8\n9\n' > "$work/bad/nine.csv"
write_probe_study "$work/bad/missing.toml" 'file = "two.csv"' '["A", "B", "C"]' '[0, 99, 202]'
expect_exit 2 "$work/bad/missing" "$bin" run "$work/bad/missing.toml" --out "$work/bad/out1"
grep -q 'missing.toml:5: input.columns: no column "C" in .*two.csv (columns: A, B)' "$work/bad/missing.err" ||
  fail "missing column message"
[ ! -e "$work/bad/out1" ] || fail "output written for a missing column"
write_probe_study "$work/bad/lengths.toml" 'files = ["eight.csv", "eight.csv", "nine.csv"]' '["X", "X", "X"]' '[0, 99, 202]'
expect_exit 2 "$work/bad/lengths" "$bin" run "$work/bad/lengths.toml" --out "$work/bad/out2"
grep -q 'input.files: probe signals differ in length: .*has 8 rows, .*nine.csv has 9 rows' "$work/bad/lengths.err" ||
  fail "length mismatch message"
[ ! -e "$work/bad/out2" ] || fail "output written for unequal lengths"

finish
