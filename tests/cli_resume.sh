#!/usr/bin/env bash
# Checkpoint and resume, end to end: kill -9 a `wavetrace render --checkpoint`
# mid-render, resume it, and require the same EXR, byte for byte, as an
# uninterrupted render of the same total sample count (the accumulation is
# per pixel and in sample order, so resuming it is exact). Then a truncated,
# a bit-flipped, an other-scene and an other-settings checkpoint must each be
# refused with its message, before anything is rendered or written.
#
# usage: cli_resume.sh WAVETRACE SCRATCH_DIR [single|kahan|double][_aov]
# (_aov: with every AOV, whose layers must resume exactly as well)
set -u
exe=$1
dir=$2
mode=${3:-kahan}
mkdir -p "$dir"
rm -f "$dir"/*
common=(--width 16 --height 16 --accumulation "${mode%_aov}")
[ "$mode" != "${mode%_aov}" ] && common+=(--aov all)
fail() {
  echo "FAIL: $*"
  exit 1
}

# --- kill -9 mid-render --------------------------------------------------
"$exe" render "${common[@]}" -q --spp 1000000 --checkpoint 0.1 -o "$dir/killed.exr" &
pid=$!
# the first checkpoint (after a cold kernel build: seconds), then more passes
for _ in $(seq 1200); do
  [ -f "$dir/killed.exr.wtckpt" ] && break
  kill -0 $pid 2>/dev/null || fail "the render exited before its first checkpoint"
  sleep 0.1
done
[ -f "$dir/killed.exr.wtckpt" ] || fail "no checkpoint after 120 s"
sleep 0.35
kill -9 $pid
wait $pid
status=$?
[ $status -eq 137 ] || fail "the render was not killed by SIGKILL (exit status $status)"
[ -f "$dir/killed.exr" ] && fail "the killed render wrote an image"

done=$(grep -a -o -m1 'samples_done [0-9]*' "$dir/killed.exr.wtckpt" | head -1 | cut -d' ' -f2)
[ -n "$done" ] && [ "$done" -gt 0 ] || fail "no samples_done in the checkpoint header"
total=$((done + 37))
echo "killed with a checkpoint of $done samples; resuming to $total"

"$exe" render "${common[@]}" --spp $total --resume -o "$dir/killed.exr" >"$dir/resume.log" 2>&1 ||
  fail "resume failed: $(cat "$dir/resume.log")"
grep -q "resumed from .*killed.exr.wtckpt at $done samples" "$dir/resume.log" || fail "$(cat "$dir/resume.log")"
grep -q "stopped after $total samples" "$dir/resume.log" || fail "$(cat "$dir/resume.log")"
"$exe" render "${common[@]}" -q --spp $total -o "$dir/straight.exr" >/dev/null || fail "uninterrupted render failed"
cmp "$dir/killed.exr" "$dir/straight.exr" || fail "resumed image differs from the uninterrupted render"
echo "resumed image equals the uninterrupted one, byte for byte"

# --- damaged and foreign checkpoints --------------------------------------
# refused: exit status not 0, the message, and no image written
refused() {
  local name=$1 pattern=$2
  shift 2
  local out
  out=$("$exe" render "$@" --resume -o "$dir/$name.exr" 2>&1) && fail "$name: accepted: $out"
  echo "$out" | grep -q -- "$pattern" || fail "$name: expected '$pattern' in: $out"
  [ -f "$dir/$name.exr" ] && fail "$name: an image was written"
  echo "$name: refused ($pattern)"
}
ckpt="$dir/killed.exr.wtckpt"
size=$(stat -c %s "$ckpt")

head -c $((size / 2)) "$ckpt" >"$dir/truncated.exr.wtckpt"
refused truncated "truncated.exr.wtckpt: truncated checkpoint" "${common[@]}" --spp $total

cp "$ckpt" "$dir/flipped.exr.wtckpt"
# the third byte of the last pixel's sample count (0 below 65536 samples)
printf '\x40' | dd of="$dir/flipped.exr.wtckpt" bs=1 seek=$((size - 10)) conv=notrunc status=none
refused flipped "flipped.exr.wtckpt: corrupt checkpoint (checksum" "${common[@]}" --spp $total

cp "$ckpt" "$dir/other_scene.exr.wtckpt"
refused other_scene "other_scene.exr.wtckpt: the checkpoint is of another render: another scene" \
  cornell_small_light "${common[@]}" --spp $total

cp "$ckpt" "$dir/other_settings.exr.wtckpt"
refused other_settings "the checkpoint is of another render: seed 0 in the checkpoint, 5 here" \
  "${common[@]}" --spp $total --seed 5

refused missing "missing.exr.wtckpt: cannot read the checkpoint" "${common[@]}" --spp $total
echo "PASS"
