#!/usr/bin/env bash
# studies/stability_chart.toml (G1 eq 2-21, book fig 2-4) through the `chatterlab` command: the
# leftmost point of the single-mode circle is -1/(4 zeta (1 + zeta) k) = -9.5238e-8 m/N at
# 250 sqrt(1 + 2 zeta) = 262.20 Hz, the process line -(1/2)(2/kc + 1/kg + 1/kw) = -1.3e-8 m/N, they
# meet; chart.csv and the plot are written. Also studies/contact_stiffness_chart.toml (kc sweep).
# Usage: stability_chart.cli.sh CHATTERLAB WORK_DIR SOURCE_DIR
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2 src=$3
rm -rf "$work" && mkdir -p "$work"
expect_exit 0 "$work/run" "$bin" run "$src/studies/stability_chart.toml" --out "$work/out" --no-progress
csv=$work/out/results.csv
close_to "$(csv_column "$csv" leftmost_real_compliance_m_per_n)" -9.5238095e-8 1e-14 || fail "leftmost point"
close_to "$(csv_column "$csv" leftmost_frequency_hz)" 262.202 0.01 || fail "leftmost frequency"
close_to "$(csv_column "$csv" process_line_m_per_n)" -1.3e-8 1e-20 || fail "process line"
[ "$(csv_column "$csv" intersects)" = true ] || fail "curve and line should meet"
[ "$(wc -l < "$work/out/chart.csv")" -eq 20001 ] || fail "chart.csv should have 20000 samples"
expect_plots "$work/out" stability_chart
# studies/contact_stiffness_chart.toml: the line approaches the curve as kc rises (ratio increasing)
# and first meets it between kc = 1e7 and 1.26e7 N/m for that machine.
expect_exit 0 "$work/kc" "$bin" run "$src/studies/contact_stiffness_chart.toml" --out "$work/kc_out" --no-progress
paste -d' ' <(csv_column "$work/kc_out/results.csv" contact_stiffness_n_per_m) \
  <(csv_column "$work/kc_out/results.csv" line_depth_ratio) |
  awk 'NR > 1 && $2 <= last { print "ratio falls at kc " $1; bad = 1 }
       { if ($2 > 1 && first == "") first = $1; last = $2 }
       END { if (!(first > 1e7 && first < 1.3e7)) { print "first meeting at kc " first; bad = 1 }; exit bad }' ||
  fail "contact_stiffness_chart: line depth not rising with kc or meeting at the wrong kc"
expect_plots "$work/kc_out" line_depth_ratio
# A model without a machine compliance is bad input: exit 2, nothing written.
sed 's/type = "plunge_regenerative"/type = "linear_dde"/' "$src/studies/stability_chart.toml" > "$work/bad.toml"
expect_exit 2 "$work/bad" "$bin" run "$work/bad.toml" --out "$work/bad_out"
[ ! -e "$work/bad_out" ] || fail "bad input wrote $work/bad_out"
finish
