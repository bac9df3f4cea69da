#!/usr/bin/env bash
# The progress output: on a terminal one line redrawn in place (carriage
# returns), elsewhere plain lines, and nothing with --quiet.
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
echo PASS
