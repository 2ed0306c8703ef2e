#!/usr/bin/env bash
# Tests check_study_claims on made-up studies: true claims pass silently; a false claim, a claim
# that cannot be evaluated and a study without claims fail, each named with its line, its text
# and the value found. Usage: check_study_claims_test.sh CHECK_STUDY_CLAIMS WORK_DIR
set -u
tool=$1 work=$2
rm -rf "$work" && mkdir -p "$work/studies" "$work/out/good" "$work/out/bad" "$work/out/silent"
fail() { echo "FAIL: $*" >&2; sed 's/^/  | /' "$work/log" >&2; exit 1; }

cat >"$work/out/good/results.csv" <<'CSV'
k_n_per_m,mode,growth_rate_per_s,fit_valid,status
2e4,a,1.5,true,completed
2e4,b,0.5,true,completed
4e5,a,-0.25,1,completed
CSV
echo '{"peaks": [{"frequency_hz": 841.0}], "verdict": "chatter", "stable": false}' >"$work/out/good/summary.json"
cp "$work/out/good/"* "$work/out/bad/"
cp "$work/out/good/"* "$work/out/silent/"

cat >"$work/studies/good.toml" <<'TOML'
# claim: results.csv max(growth_rate_per_s) > 0            -- the centre chatters
# claim: results.csv all(fit_valid)
# claim: results.csv max(growth_rate_per_s[k_n_per_m=2e4]) > max(growth_rate_per_s[k_n_per_m=4e5])
# claim: results.csv growth_rate_per_s[k_n_per_m=2e4&mode=b] ~ 0.5 1e-12
# claim: results.csv count(status[growth_rate_per_s<0]) == 1
# claim: results.csv min(growth_rate_per_s[growth_rate_per_s>0]) >= 0.5
# claim: summary.json /peaks/0/frequency_hz ~ 840 2%       -- carrier near 840 Hz
# claim: summary.json /verdict == "chatter"
# claim: summary.json /stable == false
# claim: results.csv sd(growth_rate_per_s[mode=a]) ~ 0.875 1e-12
# claim: summary.json /peaks/0/frequency_hz > results.csv:max(growth_rate_per_s)
[study]
kind = "simulate"
TOML
cat >"$work/studies/bad.toml" <<'TOML'
# Prose header.
# claim: results.csv min(growth_rate_per_s) > 0            -- every point chatters
# claim: summary.json /peaks/0/frequency_hz ~ 800 2%
# claim: results.csv max(no_such_column) > 0
# claim: results.csv growth_rate_per_s[mode=a] > 0
# claim: results.csv max(growth_rate_per_s) >> 0
# claim: results.csv max(growth_rate_per_s) > summary.json:/peaks/0/frequency_hz
[study]
kind = "simulate"
TOML
printf '# Says nothing checkable.\n[study]\nkind = "simulate"\n' >"$work/studies/silent.toml"

# True claims alone: exit 0.
mkdir -p "$work/only_good" && cp "$work/studies/good.toml" "$work/only_good/"
"$tool" "$work/only_good" "$work/out" >"$work/log" 2>&1 || fail "true claims reported as failing"
grep -q "all 11 claims of 1 studies hold" "$work/log" || fail "no summary of the true claims"

"$tool" "$work/studies" "$work/out" >"$work/log" 2>&1
[ $? -eq 1 ] || fail "false claims: exit status is not 1"
expect() { grep -qF -- "$1" "$work/log" || fail "missing message: $1"; }
expect "FAIL: bad.toml:2: claim 'results.csv min(growth_rate_per_s) > 0            -- every point chatters': found min(growth_rate_per_s) = -0.25"
expect "FAIL: bad.toml:3: claim 'summary.json /peaks/0/frequency_hz ~ 800 2%': found /peaks/0/frequency_hz = 841"
expect "FAIL: bad.toml:4: claim 'results.csv max(no_such_column) > 0': cannot evaluate: no column 'no_such_column'"
expect "FAIL: bad.toml:5: claim 'results.csv growth_rate_per_s[mode=a] > 0': cannot evaluate: growth_rate_per_s[mode=a] selects 2 rows"
expect "FAIL: bad.toml:6: claim 'results.csv max(growth_rate_per_s) >> 0': cannot evaluate: expected an operator"
expect "FAIL: bad.toml:7: claim 'results.csv max(growth_rate_per_s) > summary.json:/peaks/0/frequency_hz': found max(growth_rate_per_s) = 1.5, summary.json:/peaks/0/frequency_hz = 841"
expect "FAIL: silent.toml: states no claim"
grep -q "good.toml" "$work/log" && fail "a true claim was reported"
echo "check_study_claims reports false, unevaluable and missing claims"
