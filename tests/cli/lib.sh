# Shared helpers of the CLI end-to-end tests (sourced by the *.sh scripts here). Plain bash and
# awk only: the tests must run on a fresh Debian without Python packages.
set -u
CLI_TESTS_DIR=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
CSV_AWK=$(cat "$CLI_TESTS_DIR/csv.awk")
failures=0

fail() {
  echo "FAIL: $*" >&2
  failures=$((failures + 1))
}

# Ends the script: exit 1 if any check failed.
finish() {
  if [ "$failures" -gt 0 ]; then
    echo "$failures check(s) failed" >&2
    exit 1
  fi
  echo "all checks passed"
}

# expect_exit CODE LOG_PREFIX COMMAND...: runs COMMAND with stdout/stderr in LOG_PREFIX.out/.err.
expect_exit() {
  local want=$1 log=$2
  shift 2
  "$@" >"$log.out" 2>"$log.err"
  local got=$?
  if [ "$got" -ne "$want" ]; then
    fail "exit code $got (expected $want): $*"
    sed 's/^/  | /' "$log.out" "$log.err" >&2
  fi
}

# csv_column FILE NAME: the values of column NAME, one line per data row, unquoted.
csv_column() {
  awk -v name="$2" "$CSV_AWK"'
    NR == 1 { n = csvsplit($0, h); for (i = 1; i <= n; i++) if (h[i] == name) c = i
              if (!c) { print "no column " name > "/dev/stderr"; exit 3 } next }
    { csvsplit($0, f); print f[c] }' "$1"
}

# csv_header FILE: the header line.
csv_header() { head -n 1 "$1"; }

# close_to ACTUAL EXPECTED ABS_TOL: true when |ACTUAL - EXPECTED| <= ABS_TOL (and ACTUAL is a number).
close_to() {
  awk -v a="$1" -v e="$2" -v t="$3" 'BEGIN {
    if (a !~ /^[-+]?[0-9.]+([eE][-+]?[0-9]+)?$/) exit 1
    d = a - e; if (d < 0) d = -d; exit !(d <= t) }'
}

# json_number FILE KEY: the first "KEY": <number> in a JSON file (meta.json is pretty-printed).
json_number() {
  grep -o "\"$2\": *-\?[0-9][0-9.eE+-]*" "$1" | head -n 1 | sed 's/.*: *//'
}

# is_png FILE / is_svg FILE: the file exists and starts like one.
is_png() { [ -s "$1" ] && [ "$(head -c 4 "$1" | tail -c 3)" = "PNG" ]; }
is_svg() { [ -s "$1" ] && grep -q "<svg" "$1"; }

# expect_plots DIR STEM...: STEM.png and STEM.svg exist and are images.
expect_plots() {
  local dir=$1
  shift
  for stem in "$@"; do
    is_png "$dir/$stem.png" || fail "$dir/$stem.png missing or not a PNG"
    is_svg "$dir/$stem.svg" || fail "$dir/$stem.svg missing or not an SVG"
  done
}

# mpirun as root inside containers needs these; harmless otherwise.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1

# misbehaving_study FILE PLUGIN BEHAVIOURS [RUN_TABLE]: a stability_map study of the test plugin
# misbehaving_model (tests/external_plugin/misbehaving_model.cpp) with a grid over its decay rate
# ($DECAYS, default [1, 2, 3] per s: ok points have their root at -decay) and over BEHAVIOURS (a
# TOML list of strings, e.g. '["ok", "segfault"]'; the faster axis), and RUN_TABLE written as
# [run] when given.
misbehaving_study() {
  {
    echo "plugins = [\"$2\"]"
    printf '[study]\nkind = "stability_map"\n[model]\ntype = "misbehaving_model"\nsleep_s = 1\n'
    printf '[stability]\nmax_frequency_hz = 1\n'
    [ -n "${4:-}" ] && printf '[run]\n%s\n' "$4"
    printf '[grid]\n"model.decay_rate_per_s" = %s\n"model.behaviour" = %s\n' "${DECAYS:-[1, 2, 3]}" "$3"
  } >"$1"
}

# journal_records DIR: complete records in DIR/journal (newline-terminated lines after each
# file's header line).
journal_records() {
  local total=0 lines f
  for f in "$1"/journal/points-*.jsonl; do
    [ -e "$f" ] || continue
    lines=$(wc -l <"$f")
    [ "$lines" -gt 1 ] && total=$((total + lines - 1))
  done
  echo "$total"
}

# wait_for SECONDS COMMAND...: polls COMMAND every 0.05 s until it succeeds; false on time-out.
wait_for() {
  local deadline=$(($(date +%s) + $1))
  shift
  until "$@"; do
    [ "$(date +%s)" -ge "$deadline" ] && return 1
    sleep 0.05
  done
}

# no_partial_files DIR: no temporary (*.tmp<pid>.<n>) or empty files are left anywhere in DIR.
no_partial_files() {
  local found
  found=$(find "$1" -type f \( -name '*.tmp[0-9]*' -o -empty \) ! -name '.chatterlab-output' \
          ! -name '.chatterlab-lock' | head -n 5)
  [ -z "$found" ] || { fail "partial files left in $1: $found"; return 1; }
}
