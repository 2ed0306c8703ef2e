#!/usr/bin/env bash
# Study kind signal_analysis through the command: the shipped Lorenz and Henon studies (exit 0,
# headline numbers near the known answers for 10,000 / 5,000 samples, summary.json and every
# plot), and bad input
# (missing column, missing sample rate, constant signal, too short for the requested dimension):
# exit 2, the reason in the message, nothing written.
# Usage: signal_analysis.cli.sh CHATTERLAB WORK_DIR SOURCE_DIR
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2 src=$3
rm -rf "$work" && mkdir -p "$work"

# ---- the shipped study
out=$work/lorenz
expect_exit 0 "$work/lorenz" "$bin" run "$src/studies/signal_analysis_lorenz.toml" --out "$out"
csv=$out/results.csv
[ "$(csv_column "$csv" status)" = ok ] || fail "lorenz: point not ok"
lambda=$(csv_column "$csv" lyapunov_max_per_s)
close_to "$lambda" 0.906 0.12 || fail "lorenz: lyapunov_max_per_s = $lambda (known 0.906)"
d2=$(csv_column "$csv" correlation_dimension)
close_to "$d2" 2.05 0.15 || fail "lorenz: correlation_dimension = $d2 (known 2.05)"
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
d2=$(csv_column "$csv" correlation_dimension)
close_to "$d2" 1.21 0.05 || fail "henon: correlation_dimension = $d2 (known 1.21-1.22)"
[ "$(csv_column "$csv" delay_samples),$(csv_column "$csv" embedding_dimension)" = 1,2 ] ||
  fail "henon: delay/dimension not 1/2"

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
bad_study missing_rate '[input]\nfile = "short.csv"\ncolumn = "x"' \
  "missing key 'input.sample_rate_hz'"
bad_study constant '[input]\nfile = "constant.csv"\ncolumn = "x"\nsample_rate_hz = 100' \
  "the signal is constant"
bad_study too_short '[input]\nfile = "short.csv"\ncolumn = "x"\nsample_rate_hz = 100\n[analysis]\nmethods = ["correlation_dimension"]\n[analysis.correlation_dimension]\nembedding_dimension = 5\ndelay_samples = 60' \
  "300 samples are too short for embedding dimension 5 with delay 60" "at least 340 samples"

finish
