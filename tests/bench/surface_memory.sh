#!/usr/bin/env bash
# Peak memory of a `surface` study on one long open profile (issue 23: profiles of 10^7..10^8
# samples in at most 48 bytes per sample; docs/performance.md, "Surface metrology"). Writes a
# profile of SAMPLES samples (0.5 um spacing: a 4 mm and a 0.05 mm wave plus noise, "%.6g", one
# column) to WORK_DIR once, runs `chatterlab run` on it with the FILTER filter (lc = 0.8 mm)
# under /usr/bin/time -v, and prints the peak resident set, bytes per sample, the output
# directory's size and the wall time. Not a test: run it by hand, with a BASELINE chatterlab to
# compare (each run alternates the two). FILTER `closed` measures a closed profile instead: one
# revolution of SAMPLES radii (eccentricity, 26 and 895 lobes plus noise), 50 UPR Gaussian filter,
# so the roundness evaluation (reference circles, UPR table, Wz|f) runs on all of them. FILTER
# `monitor` measures a signal instead: a `chatter_monitor` study (both detectors, as
# studies/chatter_monitor_transition.toml) on SAMPLES samples at 8 kHz of 0.1 um noise with a
# 361.7 Hz chatter growing at 0.02 /s from 600 s, one column. FILTER `chaos` measures a
# `signal_analysis` study instead (the methods of studies/signal_analysis_lorenz.toml, each with
# its default reference-point counts) on SAMPLES samples of the Lorenz x coordinate (sigma 10,
# rho 28, beta 8/3, RK4 at dt = 0.01 as 100 Hz, after 50 time units of transient, "%.8g").
# Usage: surface_memory.sh CHATTERLAB WORK_DIR [SAMPLES [FILTER|closed|monitor|chaos [BASELINE]]]
set -eu
bin=$1 work=$2 samples=${3:-10000000} filter=${4:-gaussian} baseline=${5:-}
mkdir -p "$work"
# Writes the awk program's output (n = SAMPLES) to the file once: later runs reuse it.
generate() { [ -s "$1" ] || { awk -v n="$samples" "$2" >"$1.tmp" && mv "$1.tmp" "$1"; }; }
# Writes $study: [study] of KIND named "memory: NAME", [input] reading COLUMN of $data, then the
# mode's own lines from standard input.
write_study() {
  { printf '[study]\nkind = "%s"\nname = "memory: %s"\n\n[input]\nfile = "%s"\ncolumn = "%s"\n' \
      "$1" "$2" "$(basename "$data")" "$3"
    cat; } >"$study"
}
if [ "$filter" = monitor ]; then
  # The network trains on 100 s of noise and at 669 s (chatter at ~4 x the noise).
  [ "$samples" -ge 5400000 ] || { echo "monitor needs SAMPLES >= 5400000 (675 s at 8 kHz)" >&2; exit 2; }
  data=$work/signal_$samples.csv
  generate "$data" 'BEGIN {
      srand(7); pi = atan2(0, -1); print "displacement_m"
      for (i = 0; i < n; i++) {
        t = i / 8000; u = rand(); if (u < 1e-12) u = 1e-12
        a = t > 600 ? 1e-7 * exp(0.02 * (t - 600)) : 0; if (a > 2e-5) a = 2e-5
        printf "%.6g\n", sqrt(-2 * log(u)) * cos(2 * pi * rand()) * 1e-7 + a * sin(2 * pi * 361.7 * t)
      }
    }'
  study=$work/monitor_$samples.toml
  write_study chatter_monitor "signal of $samples samples" displacement_m <<EOF
sample_rate_hz = 8000.0

[monitor.bp_network]
window_samples = 10
stable_s = [100.0, 100.0186875]
onset_s = [669.0, 669.0186875]
seed = 1

[monitor.rbf_density]
window_samples = 50
rho = 0.2
EOF
elif [ "$filter" = chaos ]; then
  data=$work/lorenz_$samples.csv
  generate "$data" 'function f(x, y, z) { dx = 10 * (y - x); dy = x * (28 - z) - y; dz = x * y - 8 / 3 * z }
    BEGIN {
      x = 1; y = 1; z = 1; h = 0.01; print "x"
      for (i = -5000; i < n; i++) {
        f(x, y, z); k1x = dx; k1y = dy; k1z = dz
        f(x + h / 2 * k1x, y + h / 2 * k1y, z + h / 2 * k1z); k2x = dx; k2y = dy; k2z = dz
        f(x + h / 2 * k2x, y + h / 2 * k2y, z + h / 2 * k2z); k3x = dx; k3y = dy; k3z = dz
        f(x + h * k3x, y + h * k3y, z + h * k3z)
        x += h / 6 * (k1x + 2 * k2x + 2 * k3x + dx)
        y += h / 6 * (k1y + 2 * k2y + 2 * k3y + dy)
        z += h / 6 * (k1z + 2 * k2z + 2 * k3z + dz)
        if (i >= 0) printf "%.8g\n", x
      }
    }'
  study=$work/chaos_$samples.toml
  write_study signal_analysis "Lorenz x, $samples samples" x <<EOF
sample_rate_hz = 100.0

[analysis]
methods = ["embedding", "correlation_dimension", "lyapunov", "lyapunov_spectrum", "surrogates"]

[analysis.surrogates]
surrogates = 19
EOF
elif [ "$filter" = closed ]; then
  data=$work/roundness_$samples.csv
  generate "$data" 'BEGIN {
      srand(1); pi = atan2(0, -1); print "radius_um"
      for (i = 0; i < n; i++) {
        t = 2 * pi * i / n
        printf "%.6g\n", 3 * cos(t - 0.4) + 0.8 * sin(26 * t) + 0.05 * sin(895 * t) + 0.02 * (rand() + rand() + rand() - 1.5)
      }
    }'
  study=$work/roundness_$samples.toml
  write_study surface "closed profile of $samples samples" radius_um <<EOF
closed = true
samples_per_rev = $samples
unit = "um"

[filter]
type = "gaussian"
cutoff_upr = 50

[process]
wheel_speed_rpm = 1450
work_speed_rpm = 55
EOF
else
data=$work/profile_$samples.csv
generate "$data" 'BEGIN {
    srand(1); pi = atan2(0, -1); print "height_um"
    for (i = 0; i < n; i++) {
      x = i * 0.0005
      printf "%.6g\n", 1.5 * sin(2 * pi * x / 4) + 0.3 * sin(2 * pi * x / 0.05) + 0.1 * (rand() + rand() + rand() - 1.5)
    }
  }'
study=$work/surface_${samples}_$filter.toml
write_study surface "$samples samples, $filter" height_um <<EOF
spacing_mm = 0.0005

[filter]
type = "$filter"
cutoff_mm = 0.8
EOF
fi
echo "input: $data ($(stat -c %s "$data") bytes, $samples samples), filter $filter, load $(cut -d' ' -f1 /proc/loadavg)"
printf '%-9s %14s %14s %14s %8s\n' build "peak RSS kB" "bytes/sample" "output bytes" "wall s"
for build in new ${baseline:+baseline}; do
  exe=$bin && [ "$build" = baseline ] && exe=$baseline
  out=$work/out_${samples}_${filter}_$build
  rm -rf "$out"
  /usr/bin/time -v "$exe" run "$study" --out "$out" --no-progress >"$out.log" 2>"$out.time" ||
    { echo "failed: $out.log $out.time" >&2; exit 1; }
  peak_kb=$(awk -F': ' '/Maximum resident set size/ {print $2}' "$out.time")
  wall=$(awk -F': ' '/Elapsed \(wall clock\)/ {print $2}' "$out.time")
  printf '%-9s %14s %14.1f %14s %8s\n' "$build" "$peak_kb" "$(echo "$peak_kb * 1024 / $samples" | bc -l)" \
    "$(du -sb "$out" | cut -f1)" "$wall"
done
[ -z "$baseline" ] || cmp -s "$work/out_${samples}_${filter}_new/results.csv" "$work/out_${samples}_${filter}_baseline/results.csv" ||
  echo "results.csv differs from the baseline's" >&2
