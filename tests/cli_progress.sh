#!/usr/bin/env bash
# The progress output: on a terminal one line redrawn in place (carriage
# returns), elsewhere plain lines, and nothing with --quiet; with --reference
# and no --error-log, stdout is the error log's CSV alone.
#
# usage: cli_progress.sh WAVETRACE SCRATCH_DIR   (needs script(1), util-linux)
set -u
exe=$1
dir=$2
mkdir -p "$dir"
fail() {
  echo "FAIL: $*"
  exit 1
}
command -v script >/dev/null || { echo "script(1) not installed: skipped"; exit 77; }
args="render --width 8 --height 8 --spp 300 -o $dir/progress.png"

# a terminal (a pseudo-terminal from script): the line starts with \r, not a new line
tty_out=$(script -qec "$exe $args" /dev/null) || fail "render on a terminal failed: $tty_out"
printf '%s' "$tty_out" | grep -q $'\rsample [0-9]*/300  [0-9.]* Mrays/s' || fail "no redrawn line on a terminal: $tty_out"
printf '%s' "$tty_out" | grep -q $'\rsample 300/300 ' || fail "no final line on a terminal: $tty_out"

# a pipe: plain lines, no carriage return
pipe_out=$($exe $args 2>&1) || fail "render failed: $pipe_out"
printf '%s' "$pipe_out" | grep -q '^sample 300/300  [0-9.]* Mrays/s' || fail "no plain progress line: $pipe_out"
printf '%s' "$pipe_out" | grep -q $'\r' && fail "carriage return where stderr is no terminal: $pipe_out"

# --quiet: no progress at all, on a terminal either
quiet_out=$(script -qec "$exe $args --quiet" /dev/null) || fail "quiet render failed: $quiet_out"
printf '%s' "$quiet_out" | grep -q 'sample [0-9]' && fail "progress despite --quiet: $quiet_out"
printf '%s' "$quiet_out" | grep -q 'wrote .*progress.png' || fail "no 'wrote' line with --quiet: $quiet_out"

# --reference without --error-log: the CSV on stdout, every status line on stderr
ref="render --width 8 --height 8 --seed 3"
$exe $ref --spp 64 -q -o "$dir/ref.exr" >/dev/null || fail "reference render failed"
csv=$($exe $ref --spp 6 -q -o "$dir/err.exr" --reference "$dir/ref.exr" 2>"$dir/err.stderr") || fail "render with --reference failed"
[ "$(printf '%s\n' "$csv" | head -1)" = "samples,seconds,rmse,relmse,relmse_raw,p99,mean_ratio" ] || fail "stdout does not start with the CSV header: $csv"
bad=$(printf '%s\n' "$csv" | tail -n +2 | grep -Ev '^[0-9]+(,[-0-9.e+naif]+){6}$')
[ -z "$bad" ] || fail "stdout holds lines that are not error-log rows: $bad"
[ "$(printf '%s\n' "$csv" | tail -n +2 | cut -d, -f1 | tr '\n' ' ')" = "1 2 4 6 " ] || fail "rows not at 1, 2, 4 and 6 samples: $csv"
grep -q 'stopped after 6 samples' "$dir/err.stderr" || fail "the stop line is not on stderr: $(cat "$dir/err.stderr")"
grep -q 'wrote .*err.exr' "$dir/err.stderr" || fail "the 'wrote' line is not on stderr: $(cat "$dir/err.stderr")"
echo PASS
