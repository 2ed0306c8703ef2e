#!/usr/bin/env bash
# Strong scaling and load balance of `mpirun -np R chatterlab run` (docs/performance.md, "MPI and
# shards") on tests/bench/studies/cost_varying_100x.toml, one thread per rank. Runs R = 1, 2, 4
# in turn, REPEATS times, alternating with BASELINE (another chatterlab, e.g. one with the
# static split) when given, so both see the same load; prints one line per run and the medians.
# Efficiency = summed point time / (ranks x wall time of the run), from meta.json.
# Usage: mpi_scaling.sh CHATTERLAB WORK_DIR [REPEATS [BASELINE]]
set -u
bin=$1 work=$2 repeats=${3:-3} baseline=${4:-}
study=$(cd "$(dirname "$0")" && pwd)/studies/cost_varying_100x.toml
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
mkdir -p "$work" && : > "$work/runs.txt"
builds=(new) && [ -n "$baseline" ] && builds+=(baseline)
for ((rep = 1; rep <= repeats; rep++)); do
  for np in 1 2 4; do
    for build in "${builds[@]}"; do
      exe=$bin && [ "$build" = baseline ] && exe=$baseline
      out=$work/$build-np$np-$rep
      rm -rf "$out"
      load=$(cut -d' ' -f1 /proc/loadavg)
      mpirun --oversubscribe -np "$np" "$exe" run "$study" --out "$out" --threads 1 --no-progress \
        >"$out.log" 2>&1 || { echo "failed: $out.log" >&2; exit 1; }
      /usr/bin/python3 - "$out/meta.json" "$build" "$np" "$load" >>"$work/runs.txt" <<'PY'
import json, sys
meta, build, np, load = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
t = json.load(open(meta))["timings"]
print(build, np, t["wall_s"], t["compute_s"], t["compute_s"] / (np * t["wall_s"]),
      t.get("load_balance", float("nan")), load)
PY
      cmp -s "$out/results.csv" "$work/${builds[0]}-np1-1/results.csv" || echo "results.csv differs: $out" >&2
    done
  done
done
/usr/bin/python3 - "$work/runs.txt" <<'PY'
import collections, statistics, sys
runs = collections.defaultdict(list)
for line in open(sys.argv[1]):
    b, np, wall, busy, eff, lb, load = line.split()
    runs[(b, int(np))].append((float(wall), float(eff), float(lb), float(load)))
print("build  ranks  wall_s(median)  speedup  efficiency(median)  load_balance(median)  load")
for (b, np), v in sorted(runs.items()):
    wall = statistics.median(x[0] for x in v)
    base = statistics.median(x[0] for x in runs[(b, 1)])
    print(f"{b:9} {np}  {wall:8.2f}  {base / wall:5.2f}  {statistics.median(x[1] for x in v):5.2f}"
          f"  {statistics.median(x[2] for x in v):5.2f}  {min(x[3] for x in v):.1f}-{max(x[3] for x in v):.1f}")
PY
