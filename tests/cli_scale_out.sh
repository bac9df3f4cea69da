#!/usr/bin/env bash
# `render` shared out (docs/scale-out.md), end to end.
#   devices: two contexts (--device 0,0) give the EXR, variance layer
#            included, byte for byte, of one device with the same --chunk-spp.
#   mpi:     2 ranks give the 1-process image byte for byte; rank 1 killed
#            mid-render: a clear error, the merged samples written and
#            checkpointed, and the resumed render equals the uninterrupted
#            one; a rank that cannot load the scene stops the job at start
#            with its message (no hang). Skips (77) in a build without MPI.
#
# usage: cli_scale_out.sh WAVETRACE SCRATCH_DIR devices|mpi [WT_MPI]
set -u
exe=$1
dir=$2
mode=$3
withMpi=${4:-OFF}
mkdir -p "$dir"
rm -f "$dir"/*
fail() {
  echo "FAIL: $*"
  exit 1
}
# one PoCL thread per process: the ranks share this machine's cores
export POCL_MAX_PTHREAD_COUNT=1
common=(--width 24 --height 16 --max-bounces 4 --seed 9 --aov variance)

if [ "$mode" = devices ]; then
  "$exe" render "${common[@]}" -v --spp 24 --chunk-spp 3 --device 0,0 -o "$dir/two.exr" >"$dir/two.log" 2>&1 ||
    fail "two devices: $(cat "$dir/two.log")"
  grep -q "on device 0 (.*), device 0 (.*); chunks of 3 samples" "$dir/two.log" || fail "no device list: $(cat "$dir/two.log")"
  "$exe" render "${common[@]}" -q --spp 24 --chunk-spp 3 -o "$dir/one.exr" >/dev/null 2>&1 || fail "one device failed"
  cmp "$dir/two.exr" "$dir/one.exr" || fail "two devices differ from one"
  echo "two devices equal one, byte for byte"
  exit 0
fi

if [ "$withMpi" != ON ]; then
  echo "SKIP: wavetrace was built without MPI (WT_MPI=$withMpi; install libopenmpi-dev openmpi-bin and reconfigure)"
  exit 77
fi
command -v mpirun >/dev/null || { echo "SKIP: no mpirun on PATH (openmpi-bin)"; exit 77; }
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
# every job bounded: a hang fails the section it is in, with its log
mpi=(timeout -k 5 120 mpirun --oversubscribe -np 2)

# --- 2 ranks vs 1 process ---------------------------------------------------
# enough work (16 chunks of about 30 ms each) that rank 1, started with rank 0,
# gets chunks even when the machine is busy
big=(--width 64 --height 64 --max-bounces 4 --seed 9 --aov variance)
"${mpi[@]}" "$exe" render "${big[@]}" -v --spp 64 --chunk-spp 4 -o "$dir/ranks.exr" >"$dir/ranks.log" 2>&1 ||
  fail "2 ranks (exit status $?): $(cat "$dir/ranks.log")"
grep -q "2 ranks, on device" "$dir/ranks.log" || fail "not 2 ranks: $(cat "$dir/ranks.log")"
grep -q "chunks by rank: [1-9][0-9]*, [1-9]" "$dir/ranks.log" || fail "a rank rendered no chunk: $(cat "$dir/ranks.log")"
"$exe" render "${big[@]}" -q --spp 64 --chunk-spp 4 -o "$dir/process.exr" >/dev/null 2>&1 || fail "1 process failed"
cmp "$dir/ranks.exr" "$dir/process.exr" || fail "2 ranks differ from 1 process"
echo "2 ranks equal 1 process, byte for byte (variance layer included) (at ${SECONDS} s)"

# --- rank 1 killed mid-render -------------------------------------------------
dbl=(--width 24 --height 16 --max-bounces 4 --seed 9 --accumulation double --chunk-spp 2)
"${mpi[@]}" "$exe" render "${dbl[@]}" -q --spp 1000000 --checkpoint 0.2 -o "$dir/killed.exr" >"$dir/killed.log" 2>&1 &
job=$!
for _ in $(seq 1200); do
  [ -f "$dir/killed.exr.wtckpt" ] && break
  kill -0 $job 2>/dev/null || fail "the job exited before its first checkpoint: $(cat "$dir/killed.log")"
  sleep 0.1
done
[ -f "$dir/killed.exr.wtckpt" ] || fail "no checkpoint after 120 s"
rank1=""
# the job is timeout, its child mpirun, mpirun's children the ranks
for p in $(pgrep -P "$(pgrep -P $job | tr '\n' ',' | sed 's/,$//')"); do
  tr '\0' '\n' <"/proc/$p/environ" 2>/dev/null | grep -qx "OMPI_COMM_WORLD_RANK=1" && rank1=$p
done
[ -n "$rank1" ] || fail "rank 1's process not found among mpirun's children: $(ps -o pid,ppid,stat,comm --ppid $job) $(cat "$dir/killed.log")"
sleep 0.3
kill -9 "$rank1"
wait $job
status=$?
[ $status -eq 124 ] && fail "the job did not end within 120 s of rank 1 being killed: $(cat "$dir/killed.log")"
[ $status -ne 0 ] || fail "the job exited 0 after a rank was killed"
grep -q "stopped by a signal after [0-9]* of 1000000 samples (under mpirun also when a rank died" "$dir/killed.log" ||
  fail "no clear error: $(cat "$dir/killed.log")"
grep -q "merged samples were written" "$dir/killed.log" || fail "nothing written: $(cat "$dir/killed.log")"
[ -f "$dir/killed.exr" ] || fail "no partial image"
done=$(grep -a -o -m1 'samples_done [0-9]*' "$dir/killed.exr.wtckpt" | head -1 | cut -d' ' -f2)
[ -n "$done" ] && [ "$done" -gt 0 ] || fail "no samples_done in the checkpoint"
echo "rank 1 killed: clear error, partial image and a checkpoint of $done samples written (at ${SECONDS} s)"
total=$((done + 6))
"${mpi[@]}" "$exe" render "${dbl[@]}" -q --spp $total --resume -o "$dir/killed.exr" >"$dir/resume.log" 2>&1 ||
  fail "resume (exit status $?): $(cat "$dir/resume.log")"
"$exe" render "${dbl[@]}" -q --spp $total -o "$dir/straight.exr" >/dev/null 2>&1 || fail "uninterrupted render failed"
cmp "$dir/killed.exr" "$dir/straight.exr" || fail "resumed image differs from the uninterrupted one"
echo "resumed on 2 ranks to $total samples: equals the uninterrupted render, byte for byte (at ${SECONDS} s)"

# --- a rank that cannot load the scene ------------------------------------------
out=$(timeout 120 mpirun --oversubscribe -np 1 "$exe" render --width 8 --height 8 --spp 4 -o "$dir/noscene.exr" : \
  -np 1 "$exe" render "$dir/missing.gltf" --width 8 --height 8 --spp 4 -o "$dir/noscene.exr" 2>&1)
status=$?
[ $status -eq 124 ] && fail "the job hung when rank 1 could not load its scene"
[ $status -ne 0 ] || fail "the job exited 0 when rank 1 could not load its scene"
echo "$out" | grep -q "the job could not start: rank 1: .*missing.gltf" || fail "no rank 1 message: $out"
[ -f "$dir/noscene.exr" ] && fail "an image was written"
echo "rank 1 without its scene: the job stopped at start with its message (at ${SECONDS} s)"
exit 0
