#!/usr/bin/env bash
# The `surface` study kind end to end: the two shipped studies (closed G8 part with roundness and
# Wz|f; open axial profile with waviness and MOTIF) and bad input (exit 2, message text, nothing
# written). Numbers are checked against what the synthetic profiles were built from
# (studies/data/make_surface_examples.py) and the Gaussian transmission exp(-pi (alpha lc/l)^2).
# Usage: surface.cli.sh CHATTERLAB WORK_DIR SOURCE_DIR
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2 src=$3
rm -rf "$work" && mkdir -p "$work"

# json_in FILE KEY...: the number at a path of nested keys (pretty JSON, one key per line).
json_in() {
  local file=$1
  shift
  awk -v path="$*" 'BEGIN { n = split(path, want, " ") }
    { line = $0; gsub(/^ +/, "", line)
      if (match(line, /^"[^"]+":/)) {
        key = substr(line, 2, RLENGTH - 3); depth = (match($0, /[^ ]/) - 1) / 2
        got[depth] = key
        ok = (depth == n)
        for (i = 1; i <= n && ok; i++) ok = (got[i] == want[i])
        if (ok) { sub(/^"[^"]+": */, "", line); sub(/,$/, "", line); print line; exit } } }' "$file"
}

# ---- closed profile: roundness, UPR table, Wz|f
out=$work/roundness
expect_exit 0 "$work/roundness" "$bin" run "$src/studies/surface_roundness.toml" --out "$out"
[ "$(csv_header "$out/filtered.csv")" = "angle_deg,profile_um,waviness_um,roughness_um" ] ||
  fail "roundness: filtered.csv header is '$(csv_header "$out/filtered.csv")'"
[ "$(csv_column "$out/filtered.csv" angle_deg | wc -l)" -eq 7200 ] || fail "roundness: not 7200 rows"
awk -F, 'NR > 1 { d = $2 - $3 - $4; if (d < 0) d = -d; if (d > 1e-9) bad = 1 } END { exit bad }' \
  "$out/filtered.csv" || fail "roundness: roughness_um != profile_um - waviness_um"
expect_plots "$out" profile roughness polar wz_f_bands
ls_ront=$(json_in "$out/summary.json" roundness least_squares RONt_um)
mz_ront=$(json_in "$out/summary.json" roundness minimum_zone RONt_um)
mc_ront=$(json_in "$out/summary.json" roundness minimum_circumscribed RONt_um)
flat=$(json_in "$out/summary.json" RONt_um)
[ "$flat" = "$ls_ront" ] || fail "roundness: flat RONt_um $flat != least_squares $ls_ront"
awk -v mz="$mz_ront" -v ls="$ls_ront" -v mc="$mc_ront" 'BEGIN { exit !(mz > 0 && mz <= ls && mz <= mc) }' ||
  fail "roundness: minimum zone $mz_ront not <= LS $ls_ront and MC $mc_ront"
[ "$(json_in "$out/summary.json" roundness minimum_zone certified)" = "true" ] ||
  fail "roundness: minimum zone not certified"
# Wz|f: 26 forced lobes of amplitude 2.13 um -> low band Wz 4.26 um at 26 UPR = 23.8 Hz at 55 rpm;
# 895 chatter lobes of 1.56 um -> high band dominant at 895 UPR = 820.4 Hz.
close_to "$(json_in "$out/summary.json" Wz_f low Wz_um)" 4.26 0.05 || fail "roundness: low band Wz"
close_to "$(json_in "$out/summary.json" Wz_f low dominant_upr)" 26 0 || fail "roundness: low band UPR"
close_to "$(json_in "$out/summary.json" Wz_f high dominant_frequency_hz)" 820.4167 0.01 ||
  fail "roundness: high band frequency"
close_to "$(json_in "$out/summary.json" Wz_f high Wz_um)" 3.12 0.2 || fail "roundness: high band Wz"
# 50 UPR Gaussian: 26 lobes pass with exp(-pi (alpha 26/50)^2) = 0.8094, ovality (2 UPR) with
# 0.9997; 895 lobes do not. The LS RONt then lies near 2 (2.13 * 0.8094) + ovality contribution.
close_to "$(json_in "$out/summary.json" roundness_by_upr 50 least_squares_RONt_um)" "$ls_ront" 1e-9 ||
  fail "roundness: 50 UPR entry differs from the study's own 50 UPR filter"

# ---- a grid over the UPR cut-off: per-point files, and RONt grows as more lobes pass the filter
mkdir -p "$work/grid"
sed "s|file = \"data/|file = \"$src/studies/data/|" "$src/studies/surface_roundness.toml" >"$work/grid/grid.toml"
printf '\n[grid]\n"filter.cutoff_upr" = [15, 50, 150]\n' >>"$work/grid/grid.toml"
expect_exit 0 "$work/grid/run" "$bin" run "$work/grid/grid.toml" --out "$work/grid/out"
expect_plots "$work/grid/out" parameters
for i in 000000 000001 000002; do
  [ -s "$work/grid/out/points/$i/summary.json" ] || fail "grid: points/$i/summary.json missing"
done
csv_column "$work/grid/out/results.csv" RONt_um |
  awk 'NR > 1 && $1 + 0 <= last + 0 { bad = 1 } { last = $1 } END { exit bad }' ||
  fail "grid: RONt_um does not grow with cutoff_upr"

# ---- open profile: waviness parameters, MOTIF
out=$work/waviness
expect_exit 0 "$work/waviness" "$bin" run "$src/studies/surface_waviness.toml" --out "$out"
[ "$(csv_header "$out/filtered.csv")" = "x_mm,profile_um,waviness_um,roughness_um" ] ||
  fail "waviness: filtered.csv header"
expect_plots "$out" profile roughness
# 1.6 mm wave of 1.5 um under a 0.8 mm cut-off: 1.5 * 0.8409 / sqrt(2) = 0.892 um (the 0.4 mm
# wave adds 0.5 * 0.0625 and the roughness almost nothing).
close_to "$(json_number "$out/summary.json" Wq_um)" 0.892 0.01 || fail "waviness: Wq_um"
close_to "$(json_number "$out/summary.json" WSm_mm)" 1.6 0.02 || fail "waviness: WSm_mm"
for key in Wa_um Wz_um Wt_um Wp_um Wv_um Wsk Wku Wz_five_um W_um AW_mm Wx_um Wte_um; do
  [ -n "$(json_number "$out/summary.json" $key)" ] || fail "waviness: summary.json has no $key"
done
wq_csv=$(csv_column "$out/results.csv" Wq_um)
[ "$wq_csv" = "$(json_number "$out/summary.json" Wq_um)" ] || fail "waviness: results.csv Wq_um differs"

# ---- bad input: exit 2, message, nothing written
bad() {  # NAME EXPECTED_TEXT: study text on stdin
  local dir=$work/bad_$1
  mkdir -p "$dir"
  cp "$src/studies/data/surface_open_profile.csv" "$dir/p.csv"
  cat >"$dir/study.toml"
  expect_exit 2 "$dir/log" "$bin" run "$dir/study.toml" --out "$dir/out"
  grep -qF -- "$2" "$dir/log.err" || fail "$1: message lacks '$2': $(cat "$dir/log.err")"
  [ ! -e "$dir/out" ] || fail "$1: output directory written"
}
bad_open() {  # NAME EXPECTED_TEXT COLUMN CUTOFF_MM: an open-profile study of p.csv
  printf '[study]\nkind = "surface"\n[input]\nfile = "p.csv"\ncolumn = "%s"\nspacing_mm = 0.002\n[filter]\ncutoff_mm = %s\n' \
    "$3" "$4" | bad "$1" "$2"
}
bad_open few_samples "too few samples per cut-off: 2.5" height_um 0.005
bad_open too_long "cutoff_mm = 10 is longer than the profile (8 mm" height_um 10
bad_open missing_column "no column 'radius'" radius 0.8
mkdir -p "$work/bad_uneven"
awk -F, 'NR == 50 { $1 = $1 + 0.0005 } { print $1 "," $2 }' "$src/studies/data/surface_open_profile.csv" \
  >"$work/bad_uneven/uneven.csv"
cat >"$work/bad_uneven/study.toml" <<'TOML'
[study]
kind = "surface"
[input]
file = "uneven.csv"
column = "height_um"
x_column = "x_mm"
[filter]
cutoff_mm = 0.8
TOML
expect_exit 2 "$work/bad_uneven/log" "$bin" run "$work/bad_uneven/study.toml" --out "$work/bad_uneven/out"
grep -qF "non-uniform spacing" "$work/bad_uneven/log.err" || fail "uneven: $(cat "$work/bad_uneven/log.err")"
grep -qF "at line 50" "$work/bad_uneven/log.err" || fail "uneven: no line: $(cat "$work/bad_uneven/log.err")"
[ ! -e "$work/bad_uneven/out" ] || fail "uneven: output directory written"

finish
