#!/usr/bin/env bash
# Study kind signal_analysis through the command: the shipped Lorenz and Henon studies (exit 0,
# intervals covering the known answers for 10,000 / 5,000 samples, the verdict, summary.json and
# every plot), a study without a sample rate (rates per sample), and bad input (missing column,
# constant signal, 150 samples, too short for the requested dimension, a Theiler window leaving
# too few neighbours): exit 2, the reason in the message, nothing written.
# Usage: signal_analysis.cli.sh CHATTERLAB WORK_DIR SOURCE_DIR
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2 src=$3
rm -rf "$work" && mkdir -p "$work"

# ---- the shipped study
out=$work/lorenz
expect_exit 0 "$work/lorenz" "$bin" run "$src/studies/signal_analysis_lorenz.toml" --out "$out"
csv=$out/results.csv
[ "$(csv_column "$csv" status)" = ok ] || fail "lorenz: point not ok"
# covers VALUE LOW HIGH: LOW <= VALUE <= HIGH (all numbers).
covers() {
  awk -v v="$1" -v lo="$2" -v hi="$3" 'BEGIN { exit !(lo != "" && hi != "" && lo <= v && v <= hi) }'
}
lo=$(csv_column "$csv" lyapunov_max_per_s_ci_low) hi=$(csv_column "$csv" lyapunov_max_per_s_ci_high)
covers 0.906 "$lo" "$hi" || fail "lorenz: lyapunov_max_per_s interval [$lo, $hi] misses 0.906"
lo=$(csv_column "$csv" correlation_dimension_ci_low) hi=$(csv_column "$csv" correlation_dimension_ci_high)
covers 2.05 "$lo" "$hi" || fail "lorenz: correlation_dimension interval [$lo, $hi] misses 2.05"
[ "$(csv_column "$csv" verdict)" = "deterministic chaos" ] || fail "lorenz: verdict $(csv_column "$csv" verdict)"
[ "$(csv_column "$csv" embedding_dimension)" = 3 ] || fail "lorenz: embedding dimension not 3"
grep -q '"lyapunov_max_per_s"' "$out/summary.json" || fail "summary.json lacks lyapunov_max_per_s"
grep -q '"ci_low"' "$out/summary.json" || fail "summary.json lacks confidence intervals"
expect_plots "$out" embedding_ami embedding_fnn correlation_dimension_sums \
  correlation_dimension_slopes correlation_dimension_saturation lyapunov_divergence \
  lyapunov_spectrum surrogates phase_portrait

# ---- the shipped Henon study (one iteration per sample: per second = per iteration)
out=$work/henon
expect_exit 0 "$work/henon" "$bin" run "$src/studies/signal_analysis_henon.toml" --out "$out"
csv=$out/results.csv
lambda=$(csv_column "$csv" lyapunov_max_per_s)
close_to "$lambda" 0.419 0.015 || fail "henon: lyapunov_max_per_s = $lambda (known 0.419)"
[ "$(csv_column "$csv" lyapunov_max_per_s_quality)" = good ] || fail "henon: exponent not good"
lo=$(csv_column "$csv" lyapunov_max_per_s_ci_low) hi=$(csv_column "$csv" lyapunov_max_per_s_ci_high)
covers 0.419 "$lo" "$hi" || fail "henon: lyapunov_max_per_s interval [$lo, $hi] misses 0.419"
d2=$(csv_column "$csv" correlation_dimension)
close_to "$d2" 1.21 0.05 || fail "henon: correlation_dimension = $d2 (known 1.21-1.22)"
[ "$(csv_column "$csv" delay_samples),$(csv_column "$csv" embedding_dimension)" = 1,2 ] ||
  fail "henon: delay/dimension not 1/2"

# ---- no sample rate: time in samples, the exponent per sample (Henon: per iteration)
head -n 3001 "$src/studies/data/henon_x.csv" >"$work/henon3000.csv"
printf '[study]\nkind = "signal_analysis"\n\n[input]\nfile = "henon3000.csv"\ncolumn = "x"\n[analysis]\nmethods = ["embedding", "lyapunov"]\n' >"$work/per_sample.toml"
expect_exit 0 "$work/per_sample" "$bin" run "$work/per_sample.toml" --out "$work/per_sample_out"
header=$(csv_header "$work/per_sample_out/results.csv")
case "$header" in *lyapunov_max_per_sample,*) ;; *) fail "no lyapunov_max_per_sample column: $header" ;; esac
case "$header" in *per_s,* | *per_s_*) fail "a per-second column without a sample rate: $header" ;; esac
lambda=$(csv_column "$work/per_sample_out/results.csv" lyapunov_max_per_sample)
close_to "$lambda" 0.419 0.03 || fail "per sample: lyapunov_max_per_sample = $lambda (known 0.419)"

# ---- bad input
printf 't_s,x\n' >"$work/short.csv"
for i in $(seq 1 300); do printf '%s,%s\n' "$i" "$(( (i * 37) % 101 ))"; done >>"$work/short.csv"
printf 't_s,x\n' >"$work/constant.csv"
for i in $(seq 1 300); do printf '%s,1.5\n' "$i"; done >>"$work/constant.csv"

bad_study() {  # NAME BODY EXPECTED_TEXT...
  local name=$1 body=$2
  shift 2
  printf '[study]\nkind = "signal_analysis"\n\n%b\n' "$body" >"$work/$name.toml"
  expect_exit 2 "$work/$name" "$bin" run "$work/$name.toml" --out "$work/${name}_out"
  for text in "$@"; do
    grep -qF -- "$text" "$work/$name.err" || fail "$name: message lacks '$text': $(cat "$work/$name.err")"
  done
  [ ! -e "$work/${name}_out" ] || fail "$name: output directory created for a bad study"
}
bad_study missing_column '[input]\nfile = "short.csv"\ncolumn = "y"\nsample_rate_hz = 100' \
  'input.column = "y"' "no column 'y'" "t_s, x"
printf 't_s,x\n' >"$work/tiny.csv"
for i in $(seq 1 150); do printf '%s,%s\n' "$i" "$(( (i * 37) % 101 ))"; done >>"$work/tiny.csv"
bad_study tiny '[input]\nfile = "tiny.csv"\ncolumn = "x"\nsample_rate_hz = 100' \
  "150 samples are too short" "at least 300 samples"
bad_study constant '[input]\nfile = "constant.csv"\ncolumn = "x"\nsample_rate_hz = 100' \
  "the signal is constant"
bad_study too_short '[input]\nfile = "short.csv"\ncolumn = "x"\nsample_rate_hz = 100\n[analysis]\nmethods = ["correlation_dimension"]\n[analysis.correlation_dimension]\nembedding_dimension = 5\ndelay_samples = 60' \
  "300 samples are too short for embedding dimension 5 with delay 60" "at least 340 samples"
bad_study theiler '[input]\nfile = "short.csv"\ncolumn = "x"\nsample_rate_hz = 100\n[analysis]\nmethods = ["embedding", "lyapunov"]\n[analysis.lyapunov]\ntheiler_window_samples = 100' \
  "analysis.lyapunov.theiler_window_samples = 100: too few neighbours" "at most 99 samples"

finish
