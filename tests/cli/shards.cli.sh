#!/usr/bin/env bash
# `chatterlab run --shard I/N` and `chatterlab merge` (chatterlab/shards.hpp, docs/cluster.md):
# the merged shards write the single run's results.csv byte for byte, in any order of the shard
# directories, with the plots drawn once at the merge; malformed --shard values and shards that
# are missing, given twice, unfinished, of another study or split differently are refused with
# exit 2, a message naming the value or shard, and nothing written.
# Usage: shards.cli.sh CHATTERLAB WORK_DIR SOURCE_DIR
source "$(dirname "$0")/lib.sh"
bin=$1 work=$2 src=$3
rm -rf "$work" && mkdir -p "$work"
study=$src/tests/cli/studies/cost_varying.toml
other=$src/tests/cli/studies/plunge_2d.toml

# expect_error LOG TEXT COMMAND...: exit 2 and TEXT on stderr.
expect_error() {
  local log=$1 text=$2
  shift 2
  expect_exit 2 "$log" "$@"
  grep -qF -- "$text" "$log.err" || fail "$*: stderr lacks '$text': $(cat "$log.err")"
}

expect_exit 0 "$work/single" "$bin" run "$study" --out "$work/single" --threads 2
for i in 1 2 3; do
  expect_exit 0 "$work/s$i" "$bin" run "$study" --out "$work/s$i" --threads 1 --shard "$i/3"
  grep -q "; shard $i/3 in " "$work/s$i.out" || fail "shard $i: summary does not name the shard"
  [ -e "$work/s$i/results.csv" ] && fail "shard $i wrote a results.csv"
  grep -q '"state": "shard_complete"' "$work/s$i/meta.json" || fail "shard $i: state not shard_complete"
done
[ "$(json_number "$work/s1/meta.json" points_computed)" = 4 ] || fail "shard 1/3 of 12 points did not compute 4"

expect_exit 0 "$work/merged" "$bin" merge "$work/merged" "$work/s1" "$work/s2" "$work/s3"
cmp "$work/single/results.csv" "$work/merged/results.csv" || fail "merged results.csv differs from the single run's"
grep -q '"state": "complete"' "$work/merged/meta.json" || fail "merged meta.json not complete"
grep -q '"merged_from"' "$work/merged/meta.json" || fail "merged meta.json does not list its shards"
grep -q "12 points: 12 ok, 0 failed; results in" "$work/merged.out" || fail "merge summary: $(cat "$work/merged.out")"
# The grid plots come from the merge, the same files as the single run's.
[ "$(cd "$work/single" && ls ./*.png ./*.svg)" = "$(cd "$work/merged" && ls ./*.png ./*.svg)" ] ||
  fail "merged plots differ from the single run's"
expect_exit 0 "$work/merged_order" "$bin" merge "$work/merged_order" "$work/s3" "$work/s1" "$work/s2"
cmp "$work/single/results.csv" "$work/merged_order/results.csv" || fail "merge depends on the order of the shards"

# Refused, with nothing written.
expect_error "$work/missing" "shard(s) 2/3 missing (2 of 3 shard directories given)" \
  "$bin" merge "$work/m_missing" "$work/s1" "$work/s3"
expect_error "$work/duplicate" "shards $work/s1 and $work/s1 are both shard 1/3" \
  "$bin" merge "$work/m_duplicate" "$work/s1" "$work/s1" "$work/s2" "$work/s3"
expect_exit 0 "$work/foreign" "$bin" run "$other" --out "$work/foreign" --threads 1 --shard 3/3
expect_error "$work/foreign_merge" "shard $work/foreign does not belong with shard $work/s1: meta.json field study_fingerprint differs" \
  "$bin" merge "$work/m_foreign" "$work/s1" "$work/s2" "$work/foreign"
expect_exit 0 "$work/quarter" "$bin" run "$study" --out "$work/quarter" --threads 1 --shard 2/4
expect_error "$work/split" "shard $work/quarter is shard 2/4, shard $work/s1 is shard 1/3" \
  "$bin" merge "$work/m_split" "$work/s1" "$work/quarter" "$work/s3"
expect_error "$work/whole" "shard $work/single: meta.json has no \"shard\" field" \
  "$bin" merge "$work/m_whole" "$work/single" "$work/s2"
cp -r "$work/s2" "$work/s2_running"
sed -i 's/"state": "shard_complete"/"state": "running (or interrupted: complete it with --resume)"/' "$work/s2_running/meta.json"
expect_error "$work/running" "shard $work/s2_running (shard 2/3): meta.json says state \"running" \
  "$bin" merge "$work/m_running" "$work/s1" "$work/s2_running" "$work/s3"
cp -r "$work/s2" "$work/s2_cut"
head -n 2 "$work/s2/journal/points-1-0.jsonl" > "$work/s2_cut/journal/points-1-0.jsonl"
expect_error "$work/cut" "shard $work/s2_cut (shard 2/3) lacks 3 of its 4 points (first: point 4)" \
  "$bin" merge "$work/m_cut" "$work/s1" "$work/s2_cut" "$work/s3"
# A shard directory that another shard's points went into (a reused --out).
cp -r "$work/s2" "$work/s2_mixed" && cp "$work/s1/journal/points-1-0.jsonl" "$work/s2_mixed/journal/points-2-0.jsonl"
expect_error "$work/mixed" "shard $work/s2_mixed (shard 2/3) holds point 0, which belongs to shard 1/3" \
  "$bin" merge "$work/m_mixed" "$work/s1" "$work/s2_mixed" "$work/s3"
for m in missing duplicate foreign split whole running cut mixed; do
  [ -e "$work/m_$m" ] && fail "refused merge ($m) wrote $work/m_$m"
done

# Malformed --shard values: exit 2 naming the value and the limit, nothing written.
expect_error "$work/zero" "--shard 0/3: the shard number I must be between 1 and N = 3" \
  "$bin" run "$study" --out "$work/r_zero" --shard 0/3
expect_error "$work/over" "--shard 4/3: the shard number I must be between 1 and N = 3" \
  "$bin" run "$study" --out "$work/r_over" --shard 4/3
expect_error "$work/text" "--shard three: expected I/N, two whole numbers with 1 <= I <= N" \
  "$bin" run "$study" --out "$work/r_text" --shard three
expect_error "$work/none" "--shard 1/0: the number of shards N must be at least 1" \
  "$bin" run "$study" --out "$work/r_none" --shard 1/0
expect_error "$work/many" "--shard 1/13: $study has 12 grid point(s), so at most 12 shard(s)" \
  "$bin" run "$study" --out "$work/r_many" --shard 1/13
for r in zero over text none many; do
  [ -e "$work/r_$r" ] && fail "refused --shard ($r) wrote $work/r_$r"
done
finish
