#!/usr/bin/env bash
# The chatter_monitor study kind through the command (MODELS.md C1-C3): the shipped transition
# study (noise, then from 0.5 s a growing 360 Hz chatter sine that passes the noise level at
# 0.625 s) raises each detector's alarm once, between 0.625 s and 0.8 s, and never before the
# onset; files and plots are written; bad input exits 2 with the reason and writes nothing.
# Usage: chatter_monitor.cli.sh CHATTERLAB WORK_DIR SOURCE_DIR
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2 src=$3
rm -rf "$work" && mkdir -p "$work"

out=$work/transition
expect_exit 0 "$work/transition" "$bin" run "$src/studies/chatter_monitor_transition.toml" --out "$out"
csv=$out/results.csv
for detector in bp_network rbf_density; do
  first=$(csv_column "$csv" "${detector}_first_alarm_s")
  awk -v t="$first" 'BEGIN { exit !(t > 0.625 && t < 0.8) }' ||
    fail "$detector: first alarm '$first' s not between 0.625 s and 0.8 s"
  [ "$(csv_column "$csv" "${detector}_alarm_intervals")" = 1 ] || fail "$detector: not one alarm interval"
  # alarms.csv: no evaluation before the onset has the alarm on.
  awk -F, -v d="$detector" 'NR > 1 && $2 == d && $1 < 0.5 && $4 == 1 { bad = 1 } END { exit bad }' \
    "$out/alarms.csv" || fail "$detector: alarm on before the chatter onset"
  expect_plots "$out" "signal_alarms_$detector" "scores_$detector"
done
expect_plots "$out" density_snapshots
[ "$(head -n 1 "$out/alarms.csv")" = "t_s,detector,score,alarm" ] || fail "alarms.csv header"
[ "$(head -n 1 "$out/features.csv")" = "t_s,variance,rho1,residual_variance" ] || fail "features.csv header"
grep -q '"converged": true' "$out/summary.json" || fail "summary.json: network training did not converge"
[ -s "$out/network_weights.json" ] || fail "network_weights.json missing"

# Bad input: a missing column, labels outside the signal. Exit 2, reason given, nothing written.
study_with() {  # NAME SED_EXPRESSION: a copy of the shipped study, edited, next to its data
  mkdir -p "$work/studies"
  cp -r "$src/studies/data" "$work/studies/" 2>/dev/null
  sed "$2" "$src/studies/chatter_monitor_transition.toml" >"$work/studies/$1.toml"
}
study_with bad_column 's/^column = "displacement_m"/column = "force_n"/'
expect_exit 2 "$work/bad_column" "$bin" run "$work/studies/bad_column.toml" --out "$work/bad_column_out"
grep -qF "input.column = \"force_n\"" "$work/bad_column.err" || fail "bad column: $(cat "$work/bad_column.err")"
grep -qF "no column 'force_n' (columns: t_s, displacement_m" "$work/bad_column.err" || fail "bad column lists: $(cat "$work/bad_column.err")"
[ ! -e "$work/bad_column_out" ] || fail "output written for a bad column"

study_with bad_labels 's/^onset_s = .*/onset_s = [0.9, 1.2]/'
expect_exit 2 "$work/bad_labels" "$bin" run "$work/studies/bad_labels.toml" --out "$work/bad_labels_out"
grep -qF "bp_network.onset_s = [0.9, 1.2]: outside the signal, which ends at t = 0.999875 s" \
  "$work/bad_labels.err" || fail "labels outside: $(cat "$work/bad_labels.err")"
[ ! -e "$work/bad_labels_out" ] || fail "output written for labels outside the signal"

# [monitor] series_csv: a bad value exits 2 naming the key and the choices; "never" leaves
# alarms.csv and features.csv out, says so in summary.json and gives the same results.
study_with bad_series_csv 's/^snapshot_times_s = .*/&\nseries_csv = "sometimes"/'
expect_exit 2 "$work/bad_series_csv" "$bin" run "$work/studies/bad_series_csv.toml" --out "$work/bad_series_csv_out"
grep -qF 'bad_series_csv.toml:30: monitor.series_csv = "sometimes": not one of: always, auto, never' \
  "$work/bad_series_csv.err" || fail "bad series_csv: $(cat "$work/bad_series_csv.err")"
[ ! -e "$work/bad_series_csv_out" ] || fail "output written for a bad series_csv"

study_with never 's/^snapshot_times_s = .*/&\nseries_csv = "never"/'
expect_exit 0 "$work/never" "$bin" run "$work/studies/never.toml" --out "$work/never_out"
[ ! -e "$work/never_out/alarms.csv" ] && [ ! -e "$work/never_out/features.csv" ] ||
  fail "series_csv = \"never\": alarms.csv or features.csv written"
grep -qF '"series_csv": "not written: 8000 samples, monitor.series_csv = \"never\"' "$work/never_out/summary.json" ||
  fail "series_csv = \"never\": summary.json does not say why the tables are missing"
[ "$(tail -n 1 "$work/never_out/results.csv")" = "$(tail -n 1 "$out/results.csv")" ] ||
  fail "series_csv = \"never\" changed results.csv"
finish
