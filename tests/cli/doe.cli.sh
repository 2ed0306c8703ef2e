#!/usr/bin/env bash
# The doe study kind through the `chatterlab` command on the book's L9 experiment (MODELS.md S4):
# exit 0, summary.json holds the recomputed sums of squares (S_A = 155.74, S_B = 265.13,
# S_C = 392.11, S_e = 71.43, S_T = 884.41; derivation in plugins/study_kinds/doe/doe_test.cpp) and
# the best combination A1 B3 C1, results.csv the F values, the plots exist; a missing factor
# column is bad input (exit 2, message, nothing written).
# Usage: doe.cli.sh CHATTERLAB WORK_DIR SOURCE_DIR
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2 src=$3
rm -rf "$work" && mkdir -p "$work"

out=$work/l9
expect_exit 0 "$work/l9" "$bin" run "$src/studies/doe_book_l9.toml" --out "$out"
s=$out/summary.json
# "S" of A, B, C, error, total in that order inside "anova".
svals=$(awk '/"anova"/ { on = 1 } on && /"S":/ { gsub(/[",]/, ""); print $2 } /"correction_term"/ { on = 0 }' "$s")
set -- $svals
close_to "${1:-x}" 155.742222 1e-4 || fail "S_A = ${1:-none}"
close_to "${2:-x}" 265.128889 1e-4 || fail "S_B = ${2:-none}"
close_to "${3:-x}" 392.108889 1e-4 || fail "S_C = ${3:-none}"
close_to "${4:-x}" 71.428889 1e-4 || fail "S_error = ${4:-none}"
close_to "${5:-x}" 884.408889 1e-4 || fail "S_total = ${5:-none}"
grep -q '"best_combination": "A1 B3 C1"' "$s" || fail "best combination"
close_to "$(csv_column "$out/results.csv" F_C)" 5.4895 1e-5 || fail "F_C in results.csv"
expect_plots "$out" effects effect_A effect_B effect_C anova regression

cp "$src/studies/data/book_l9.csv" "$work/l9.csv"
cat > "$work/bad.toml" <<'TOML'
[study]
kind = "doe"
[input]
file = "l9.csv"
response = "chatter_mv"
factors = ["A", "B", "D"]
TOML
expect_exit 2 "$work/bad" "$bin" run "$work/bad.toml" --out "$work/bad_out"
grep -q 'bad.toml:6: input.factors: no column "D"' "$work/bad.err" || fail "missing factor message"
[ ! -e "$work/bad_out" ] || fail "output written for bad input"

finish
