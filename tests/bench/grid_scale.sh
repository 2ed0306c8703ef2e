#!/usr/bin/env bash
# The grid-scale table of docs/performance.md ("Study runner at grid scale"): a two-parameter
# linear_dde stability_map (tests/cli/studies/dde_2d.toml, b 0.01..0.6 x tau 1..60 s, STEPS x STEPS
# points) run with plots in one process; prints the peak RSS, points/s (meta.json), and the sizes
# of the results file, journal/ and the plots.
# Usage: grid_scale.sh CHATTERLAB WORK_DIR STEPS FORMAT(csv|hdf5) [THREADS]
set -euo pipefail
bin=$1 work=$2 steps=$3 format=$4 threads=${5:-2}
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$work"
study=$work/map_${steps}_${format}.toml
out=$work/out_${steps}_${format}
sed '/^\[grid\]/,$d' "$here/../cli/studies/dde_2d.toml" >"$study"
cat >>"$study" <<TOML
[grid]
"model.delayed.0.matrix.1.0" = { from = 0.01, to = 0.6, steps = $steps }
"model.delayed.0.delay_s" = { from = 1.0, to = 60.0, steps = $steps }

[output]
format = "$format"
TOML
rm -rf "$out"
load=$(cut -d' ' -f1 /proc/loadavg)
/usr/bin/time -v "$bin" run "$study" --out "$out" --allow-large --threads "$threads" --no-progress \
  >"$out.log" 2>"$out.time" || { cat "$out.log" "$out.time" >&2; exit 1; }
rss_kb=$(awk -F': ' '/Maximum resident set size/ {print $2}' "$out.time")
size() { { du -sb "$@" 2>/dev/null || true; } | awk '{s += $1} END {printf "%.1f", s / 1e6}'; }
results=$(size "$out"/results.*)
journal=$(size "$out"/journal)
plots=$(size "$out"/*.png "$out"/*.svg "$out"/*.dat "$out"/*.gp)
total=$(size "$out")
rate=$(/usr/bin/python3 -c 'import json,sys; print(round(json.load(open(sys.argv[1]))["timings"].get("points_per_s", 0)))' "$out/meta.json")
echo "points=$((steps * steps)) format=$format rss_MB=$(awk "BEGIN {printf \"%.1f\", $rss_kb / 1024}") points_per_s=$rate results_MB=$results journal_MB=${journal:-0} plots_MB=$plots total_MB=$total load=$load"
