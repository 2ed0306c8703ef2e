#!/usr/bin/env bash
# The grid-scale table of docs/performance.md ("Study runner at grid scale"): a two-parameter
# linear_dde stability_map (tests/cli/studies/dde_2d.toml, b 0.01..0.6 x tau 1..60 s, STEPS x STEPS
# points) run with plots; prints the peak RSS (of rank 0 under MPI), points/s (meta.json), and the
# sizes of the results file, journal/ and the plots.
# Usage: grid_scale.sh CHATTERLAB WORK_DIR STEPS FORMAT(csv|hdf5) [THREADS] [MODE]
#   MODE fresh   (default) one process, a new output directory
#        resume  --resume of a complete run (made first, unmeasured, when WORK_DIR has none):
#                every point is taken over from results.h5 (hdf5) or the journal (csv)
#        mpi:N   mpirun -np N --oversubscribe, THREADS threads per rank
set -euo pipefail
bin=$1 work=$2 steps=$3 format=$4 threads=${5:-2} mode=${6:-fresh}
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$work"
study=$work/map_${steps}_${format}.toml
out=$work/out_${steps}_${format}_${mode/:/}
sed '/^\[grid\]/,$d' "$here/../cli/studies/dde_2d.toml" >"$study"
cat >>"$study" <<TOML
[grid]
"model.delayed.0.matrix.1.0" = { from = 0.01, to = 0.6, steps = $steps }
"model.delayed.0.delay_s" = { from = 1.0, to = 60.0, steps = $steps }

[output]
format = "$format"
TOML
run=("$bin" run "$study" --out "$out" --allow-large --threads "$threads" --no-progress)
case $mode in
  fresh) rm -rf "$out" ;;
  resume)
    if ! grep -q '"state": "complete"' "$out/meta.json" 2>/dev/null; then
      rm -rf "$out"
      "${run[@]}" >"$out.first.log" 2>&1 || { cat "$out.first.log" >&2; exit 1; }
    fi
    run+=(--resume) ;;
  mpi:*) rm -rf "$out" ;;
  *) echo "grid_scale.sh: MODE must be fresh, resume or mpi:N, not $mode" >&2; exit 2 ;;
esac
load=$(cut -d' ' -f1 /proc/loadavg)
start=$(date +%s.%N)
if [[ $mode == mpi:* ]]; then
  # Each rank under its own /usr/bin/time: the figure is rank 0's peak, the one that writes.
  mpirun -np "${mode#mpi:}" --oversubscribe sh -c \
    '/usr/bin/time -v -o "$0.time.$OMPI_COMM_WORLD_RANK" "$@"' "$out" "${run[@]}" \
    >"$out.log" 2>&1 || { cat "$out.log" >&2; exit 1; }
  time_file=$out.time.0
else
  /usr/bin/time -v -o "$out.time" "${run[@]}" >"$out.log" 2>&1 || { cat "$out.log" "$out.time" >&2; exit 1; }
  time_file=$out.time
fi
wall=$(awk -v s="$start" -v e="$(date +%s.%N)" 'BEGIN {printf "%.1f", e - s}')
rss_kb=$(awk -F': ' '/Maximum resident set size/ {print $2}' "$time_file")
size() { { du -sb "$@" 2>/dev/null || true; } | awk '{s += $1} END {printf "%.1f", s / 1e6}'; }
results=$(size "$out"/results.*)
journal=$(size "$out"/journal)
plots=$(size "$out"/*.png "$out"/*.svg "$out"/*.dat "$out"/*.gp)
total=$(size "$out")
rate=$(/usr/bin/python3 -c 'import json,sys; print(round(json.load(open(sys.argv[1]))["timings"].get("points_per_s", 0)))' "$out/meta.json")
echo "points=$((steps * steps)) format=$format mode=$mode threads=$threads rss_MB=$(awk "BEGIN {printf \"%.1f\", $rss_kb / 1024}") points_per_s=$rate wall_s=$wall results_MB=$results journal_MB=${journal:-0} plots_MB=$plots total_MB=$total load=$load"
