#!/usr/bin/env bash
# `render` shared out (docs/scale-out.md), end to end.
#   devices: two contexts (--device 0,0) give the EXR, variance layer
#            included, byte for byte, of one device with the same --chunk-spp.
#   mpi:     2 ranks give the 1-process image byte for byte; rank 1 killed
#            mid-render: a clear error naming it, the merged samples written and
#            checkpointed, and the resumed render equals the uninterrupted
#            one; a rank that cannot load the scene stops the job at start
#            with its message (no hang), failed even under mpirun
#            --enable-recovery. Skips (77) in a build without MPI.
#   lost:    rank 1 stops (SIGSTOP) holding a chunk: rank 0 gives up on it
#            after --rank-timeout, its chunk is rendered again and the image
#            equals 1 process; continued (SIGCONT) while rank 0 still runs,
#            rank 1 hears that it was given up on and does not end the job.
#            The whole job stopped longer than --rank-timeout, then continued:
#            no rank is lost. Skips (77) without MPI.
#   heartbeat: rank 1's device hung, or rank 1 killed without mpirun
#            ending the job: rank 0 finishes without it within --rank-timeout,
#            the image equal to 1 process. Rank 0's device hung: rank 1 renders
#            every chunk, chunk 0 included, and the image, every AOV and the
#            ids included, equals 1 process. Rank 0 hung: rank 1 ends the job
#            naming it, failed even under mpirun --enable-recovery, and its
#            checkpoint resumes to the uninterrupted image. A rank hung while
#            starting: the other names it (--start-timeout 1).
#            Skips (77) without MPI.
#   hosts:   two hosts on this machine: mpirun's hostfile names a second
#            host whose rsh agent runs Open MPI's daemon (orted) here, so rank
#            1 talks to rank 0 over TCP, as across machines. Rank 1 killed:
#            Open MPI blocks rank 0 inside MPI reporting the lost peer, and
#            rank 0's watchdog writes the merged samples (equal to 1 process)
#            before mpirun's SIGKILL, naming rank 1. Under mpirun
#            --enable-recovery the job is refused at start, also with rank 0
#            on the second host (no hang). Skips (77)
#            without MPI or without a network interface other than lo.
#   devices also: --aov all, --debug, --target-error and --reference on two
#            devices equal one device with the same --chunk-spp; one of two
#            devices hung: the other finishes the same image.
#
# usage: cli_scale_out.sh WAVETRACE SCRATCH_DIR devices|mpi|lost|heartbeat|hosts [WT_MPI]
set -u
if [ -n "${WT_TRACE_TS:-}" ]; then PS4='+ $(date +%s.%N) '; set -x; fi
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
base=(--width 24 --height 16 --max-bounces 4 --seed 9)
common=("${base[@]}" --aov variance)

# the split render ($1: devices "0,0" or "" for one) of the options after it
# writes $dir/NAME.exr and NAME.csv (the --reference log without its seconds
# column) and NAME.out (stdout without timings)
split() {
  local name=$1 devices=$2
  shift 2
  local dev=()
  [ -n "$devices" ] && dev=(--device "$devices")
  "$exe" render "${base[@]}" "${dev[@]}" "$@" -o "$dir/$name.exr" >"$dir/$name.raw" 2>"$dir/$name.err" ||
    fail "$name: $(cat "$dir/$name.raw" "$dir/$name.err")"
  # status lines: stdout, or stderr where stdout is the error log
  cat "$dir/$name.raw" "$dir/$name.err" | sed -E 's/, [0-9.]+ (s|ms|min)[^,]* of rendering//' | grep -v '^samples,\|^[0-9]*,' | sed "s/$name/NAME/" >"$dir/$name.out"
  grep '^[0-9]*,' "$dir/$name.raw" | cut -d, -f1,3- >"$dir/$name.csv" || true
}
same() {
  cmp "$dir/$1.exr" "$dir/$2.exr" || fail "$1 and $2 differ: $(cat "$dir/$1.out" "$dir/$2.out")"
  cmp "$dir/$1.out" "$dir/$2.out" || fail "$1 and $2 report differently: $(cat "$dir/$1.out" "$dir/$2.out")"
  cmp "$dir/$1.csv" "$dir/$2.csv" || fail "$1 and $2 log other errors: $(cat "$dir/$1.csv" "$dir/$2.csv")"
}
# a 512-spp render of another seed: the reference --reference measures against
reference() {
  "$exe" render --width 24 --height 16 --max-bounces 4 --seed 77 --spp 512 -q -o "$dir/ref.exr" >/dev/null 2>&1 ||
    fail "reference render failed"
}
# the pid of rank $1 of the job $2 (timeout, its child mpirun, mpirun's children the ranks)
rankPid() {
  local p
  for p in $(pgrep -P "$(pgrep -P "$2" | tr '\n' ',' | sed 's/,$//')"); do
    tr '\0' '\n' <"/proc/$p/environ" 2>/dev/null | grep -qx "OMPI_COMM_WORLD_RANK=$1" && echo "$p"
  done
}
# the sample count of a wavetrace EXR (its int attribute wavetraceSamples:
# name, NUL, "int", NUL, size 4, value)
exrSamples() {
  local at
  at=$(grep -abo wavetraceSamples "$1" | head -1 | cut -d: -f1)
  [ -n "$at" ] && od -An -t d4 -j $((at + 17 + 4 + 4)) -N 4 "$1" | tr -d ' '
}
# wait until $1 exists while the job $2 runs (at most 120 s)
waitForFile() {
  local _
  for _ in $(seq 1200); do
    [ -f "$1" ] && return 0
    kill -0 "$2" 2>/dev/null || fail "the job exited before writing $1: $(cat "${1%.exr.wtckpt}.log")"
    sleep 0.1
  done
  fail "no $1 after 120 s"
}
# kill rank process $1 of the job $2 0.3 s from now and wait for the job,
# which must end (timeout's 124 means it did not within $3 s) non-zero;
# $4: its log. Sets status.
killRankAndWait() {
  sleep 0.3
  kill -9 "$1"
  wait "$2"
  status=$?
  [ $status -eq 124 ] && fail "the job did not end within $3 s of rank 1 being killed: $(cat "$4")"
  [ $status -ne 0 ] || fail "the job exited 0 after a rank was killed"
}

if [ "$mode" = devices ]; then
  "$exe" render "${common[@]}" -v --spp 24 --chunk-spp 3 --device 0,0 -o "$dir/two.exr" >"$dir/two.log" 2>&1 ||
    fail "two devices: $(cat "$dir/two.log")"
  grep -q "on device 0 (.*), device 0 (.*); chunks of 3 samples" "$dir/two.log" || fail "no device list: $(cat "$dir/two.log")"
  "$exe" render "${common[@]}" -q --spp 24 --chunk-spp 3 -o "$dir/one.exr" >/dev/null 2>&1 || fail "one device failed"
  cmp "$dir/two.exr" "$dir/one.exr" || fail "two devices differ from one"
  echo "two devices equal one, byte for byte"
  # the first device to take a chunk hangs on it: after --rank-timeout the
  # other takes that chunk, and the process ends without waiting for the hung one
  WT_TEST_STALL=0:device timeout -k 5 60 "$exe" render "${common[@]}" --spp 24 --chunk-spp 3 --device 0,0 \
    --rank-timeout 1 -o "$dir/stalled.exr" >"$dir/stalled.log" 2>&1 || fail "one device hung: exit status $?: $(cat "$dir/stalled.log")"
  grep -q "warning: device 0 (.*) did no sample pass for [0-9.]* s (--rank-timeout 1) on its chunk [0-9]* (samples [0-9]*-[0-9]*): handed out again" \
    "$dir/stalled.log" || fail "one device hung: no warning naming it: $(cat "$dir/stalled.log")"
  cmp "$dir/stalled.exr" "$dir/one.exr" || fail "one device hung: the image differs from one device"
  echo "one of two devices hung: the other finished the same image"
  # every AOV merged as the image is; --target-error stops at the same chunk
  # boundary and --reference logs the same errors (a reference of another seed)
  reference
  split aov2 0,0 -q --chunk-spp 2 --aov all --target-error 0.06 --reference "$dir/ref.exr"
  split aov1 "" -q --chunk-spp 2 --aov all --target-error 0.06 --reference "$dir/ref.exr"
  same aov2 aov1
  grep -q "stopped after [0-9]* samples (--target-error reached)" "$dir/aov1.out" || fail "no target error: $(cat "$dir/aov1.out")"
  grep -q "error at [0-9]* samples: estimated 0\.0[0-5][0-9]*, measured 0\.0[0-9]*[1-9]" "$dir/aov1.out" ||
    fail "no error line: $(cat "$dir/aov1.out")"
  [ "$(wc -l <"$dir/aov1.csv")" -ge 5 ] || fail "too few error rows: $(cat "$dir/aov1.csv")"
  echo "--aov all, --target-error 0.06, --reference: two devices equal one (image, AOVs, stopping sample, error log)"
  split dbg2 0,0 -q --spp 24 --chunk-spp 3 --debug albedo
  split dbg1 "" -q --spp 24 --chunk-spp 3 --debug albedo
  same dbg2 dbg1
  echo "--debug albedo: two devices equal one, byte for byte"
  # what is not merged is refused, by name
  out=$("$exe" render "${base[@]}" --spp 4 --device 0,0 --profile -o "$dir/profile.exr" 2>&1) &&
    fail "--profile on two devices was accepted: $out"
  echo "$out" | grep -q "error: .*--profile/--profile-json: not on several devices" || fail "no --profile refusal: $out"
  [ -f "$dir/profile.exr" ] && fail "--profile refused, yet an image was written"
  echo "--profile on two devices: refused by name"
  exit 0
fi

if [ "$withMpi" != ON ]; then
  echo "SKIP: wavetrace was built without MPI (WT_MPI=$withMpi; install libopenmpi-dev openmpi-bin and reconfigure)"
  exit 77
fi
command -v mpirun >/dev/null || { echo "SKIP: no mpirun on PATH (openmpi-bin)"; exit 77; }
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
# an Open MPI session folder of this test's own: two mpiruns of parallel tests
# starting at once race to create /tmp/ompi.HOST.UID and one fails ("File exists")
TMPDIR=$(mktemp -d /tmp/wt-mpi.XXXXXX) || fail "mktemp"
export TMPDIR
trap 'rm -rf "$TMPDIR"' EXIT
# every job bounded: a hang fails the section it is in, with its log
mpi=(timeout -k 5 120 mpirun --oversubscribe -np 2)

# A worker rank that hangs, stops, or dies without a launcher that ends the
# job: rank 0 notices within --rank-timeout, hands its chunks out again (its
# own device takes them) and finishes the image, the same as 1 process byte
# for byte (the merge is in chunk order, whoever rendered a chunk).
lostCheck() {  # $1: the case, $2: the job's exit status, $3: "held" if rank 1 surely held a chunk
  [ "$2" -eq 124 ] && fail "$1: rank 0 still waited 60 s after rank 1 stopped: $(cat "$dir/$1.log")"
  [ "$2" -eq 0 ] || fail "$1: exit status $2: $(cat "$dir/$1.log")"
  # silent, or (killed) a receive from it that failed or stopped mid-message
  grep -Eq "warning: rank 1 (showed no progress for [0-9.]* s \(--rank-timeout 1\)|failed while sending|stopped sending)" \
    "$dir/$1.log" ||
    fail "$1: no message naming rank 1: $(cat "$dir/$1.log")"
  [ "${3:-}" != held ] || grep -q "its chunks [0-9]* (samples [0-9]*-[0-9]*).* were handed out again" "$dir/$1.log" ||
    fail "$1: rank 1 held no chunk (nothing to hand out again): $(cat "$dir/$1.log")"
  cmp "$dir/$1.exr" "$dir/process.exr" || fail "$1: the image differs from 1 process"
}

if [ "$mode" = hosts ]; then
  ls /sys/class/net 2>/dev/null | grep -qvx lo ||
    { echo "SKIP: no network interface other than lo (Open MPI's TCP transport between the two hosts needs one)"; exit 77; }
  # the rsh agent: Open MPI calls it as `agent HOST COMMAND...` (ssh's syntax); it runs COMMAND here
  printf '#!/bin/sh\nshift\nexec sh -c "$*"\n' >"$dir/agent"
  chmod +x "$dir/agent"
  printf 'localhost slots=1\nwt-second-host slots=1\n' >"$dir/hosts"
  hosts=(mpirun --hostfile "$dir/hosts" -np 2 --map-by node --mca plm_rsh_agent "$dir/agent")
  dbl=(--width 24 --height 16 --max-bounces 4 --seed 9 --accumulation double --chunk-spp 2)
  start=$SECONDS
  timeout -k 5 60 "${hosts[@]}" "$exe" render "${dbl[@]}" -q --spp 1000000 --checkpoint 0.2 -o "$dir/killed.exr" \
    >"$dir/killed.log" 2>&1 &
  job=$!
  waitForFile "$dir/killed.exr.wtckpt" $job
  rank1=$(for p in $(pgrep -f "wavetrace render.*$dir/killed.exr"); do
    tr '\0' '\n' <"/proc/$p/environ" 2>/dev/null | grep -qx OMPI_COMM_WORLD_RANK=1 && echo "$p"; done)
  [ -n "$rank1" ] || fail "rank 1's process not found: $(cat "$dir/killed.log")"
  [ "$(cat "/proc/$(awk '{print $4}' "/proc/$rank1/stat")/comm")" = orted ] || fail "rank 1 is not orted's child"
  killRankAndWait "$rank1" $job 60 "$dir/killed.log"
  line=$(grep "^error: render failed after [0-9]* of 1000000 samples: rank 0 was blocked for [0-9.]* s inside Open MPI (.* rank 1 on host .*; the [0-9]* merged samples were written" "$dir/killed.log") ||
    fail "no error naming the block and rank 1, or nothing written: $(cat "$dir/killed.log")"
  done=$(echo "$line" | sed -E 's/.*render failed after ([0-9]+) of.*/\1/')
  "$exe" render "${dbl[@]}" -q --spp "$done" -o "$dir/process.exr" >/dev/null 2>&1 || fail "1 process failed"
  cmp "$dir/killed.exr" "$dir/process.exr" || fail "the image of the $done merged samples differs from 1 process"
  echo "rank 1 killed on the second host: rank 0, blocked in Open MPI, wrote its $done samples (equal to 1 process) in $((SECONDS - start)) s"
  # across hosts Open MPI 4.1's mpirun --enable-recovery cannot end a job
  # whose rank died or hung: refused at start, failed (rank 0 stops mpirun)
  start=$SECONDS
  timeout -k 5 60 "${hosts[@]}" --enable-recovery "$exe" render "${dbl[@]}" -q --spp 4 -o "$dir/recovery.exr" \
    >"$dir/recovery.log" 2>&1
  status=$?
  [ $status -eq 124 ] && fail "--enable-recovery: the job hung: $(cat "$dir/recovery.log")"
  [ $status -ne 0 ] || fail "--enable-recovery across hosts: the job exited 0: $(cat "$dir/recovery.log")"
  grep -q "error: the job could not start: rank 1: started by Open MPI's daemon (orted) .* under mpirun --enable-recovery" \
    "$dir/recovery.log" || fail "--enable-recovery: no message naming it: $(cat "$dir/recovery.log")"
  [ -f "$dir/recovery.exr" ] && fail "--enable-recovery: an image was written"
  echo "mpirun --enable-recovery across hosts: refused at start, exit status $status, in $((SECONDS - start)) s"
  # every rank on the second host: rank 0 cannot stop mpirun, and there any
  # non-zero exit status leaves mpirun waiting forever: refused, exit 0
  start=$SECONDS
  printf 'wt-second-host slots=2\n' >"$dir/hosts2"
  timeout -k 5 30 mpirun --hostfile "$dir/hosts2" -np 2 --mca plm_rsh_agent "$dir/agent" --enable-recovery "$exe" render \
    "${dbl[@]}" -q --spp 4 -o "$dir/recovery2.exr" >"$dir/recovery2.log" 2>&1
  status=$?
  [ $status -eq 124 ] && fail "--enable-recovery, rank 0 on the second host: the job hung: $(cat "$dir/recovery2.log")"
  grep -q "error: the job could not start: rank 0: started by Open MPI's daemon (orted)" "$dir/recovery2.log" ||
    fail "--enable-recovery, rank 0 on the second host: not refused by name: $(cat "$dir/recovery2.log")"
  [ -f "$dir/recovery2.exr" ] && fail "--enable-recovery, rank 0 on the second host: an image was written"
  echo "the same with rank 0 on the second host: refused, exit status $status, in $((SECONDS - start)) s"
  exit 0
fi

if [ "$mode" = lost ]; then
  # rank 1 stops itself (SIGSTOP, every thread: WT_TEST_STALL=1:pause) once it
  # holds a chunk; rank 0, having lost it, goes on for 2 --rank-timeout
  lost=(--width 24 --height 16 --max-bounces 4 --seed 9 --aov all --chunk-spp 2)
  "$exe" render "${lost[@]}" --spp 32 -q -o "$dir/process.exr" >/dev/null 2>&1 || fail "1 process failed"
  start=$SECONDS
  WT_TEST_STALL=1:pause timeout -k 5 60 mpirun --oversubscribe -np 2 "$exe" render "${lost[@]}" --spp 32 -q --rank-timeout 1 \
    -o "$dir/paused.exr" >"$dir/paused.log" 2>&1 &
  job=$!
  for _ in $(seq 1200); do
    grep -q "warning: rank 1 showed no progress" "$dir/paused.log" && break
    kill -0 $job 2>/dev/null || fail "the job ended before rank 0 gave up on rank 1: $(cat "$dir/paused.log")"
    sleep 0.05
  done
  grep -q "warning: rank 1 showed no progress" "$dir/paused.log" ||
    fail "rank 0 did not give up on rank 1 within 60 s: $(cat "$dir/paused.log")"
  rank1=$(rankPid 1 $job)
  [ -n "$rank1" ] || fail "rank 1's process not found: $(cat "$dir/paused.log")"
  [ "$(ps -o stat= -p "$rank1" | cut -c1)" = T ] || fail "rank 1 is not stopped: $(ps -o stat= -p "$rank1")"
  kill -CONT "$rank1"
  wait $job
  lostCheck paused $? held
  # it came back while rank 0 ran: it heard the release instead of taking rank
  # 0's silence towards it for a hung rank 0 (that would end the job, failed)
  grep -q "warning: rank 1: rank 0 gave up on this rank" "$dir/paused.log" ||
    fail "paused: rank 1, continued, was not told it was given up on: $(cat "$dir/paused.log")"
  echo "rank 1 stopped holding a chunk: rank 0 finished without it, equal to 1 process; continued, it let the job end (in $((SECONDS - start)) s)"
  # the whole job stopped for longer than --rank-timeout and continued (as
  # Slurm's scontrol suspend/resume does), each rank in turn first: the
  # watchers do not count the time they were stopped themselves, so neither
  # rank takes the other for lost; then mpirun is stopped (SIGTERM)
  start=$SECONDS
  "${mpi[@]}" "$exe" render "${lost[@]}" -q --spp 1000000 --rank-timeout 1 --checkpoint 0.1 \
    -o "$dir/suspended.exr" >"$dir/suspended.log" 2>&1 &
  job=$!
  waitForFile "$dir/suspended.exr.wtckpt" $job
  rank0=$(rankPid 0 $job) rank1=$(rankPid 1 $job)
  [ -n "$rank0" ] && [ -n "$rank1" ] || fail "suspended: the ranks' processes not found: $(cat "$dir/suspended.log")"
  for first in "$rank0 $rank1" "$rank1 $rank0"; do
    read -r a b <<<"$first"
    kill -STOP "$rank0" "$rank1" || fail "suspended: the job ended: $(cat "$dir/suspended.log")"
    sleep 1.5
    kill -CONT "$a"
    sleep 0.3
    kill -CONT "$b"
    sleep 0.5  # both run: the next stop finds no message of this one waiting
  done
  kill -0 "$rank0" "$rank1" || fail "suspended: the job ended: $(cat "$dir/suspended.log")"
  kill -TERM "$(pgrep -P $job)"
  wait $job
  grep -q "stopped by a signal after [0-9]* of 1000000 samples" "$dir/suspended.log" ||
    fail "suspended: rank 0 did not end the job on mpirun's signal: $(cat "$dir/suspended.log")"
  grep -q "warning: rank\|warning: device\|sent nothing" "$dir/suspended.log" &&
    fail "suspended: a rank or device was taken for lost: $(cat "$dir/suspended.log")"
  echo "the job stopped twice for 1.5 s (--rank-timeout 1) and continued: no rank lost (in $((SECONDS - start)) s)"
  exit 0
fi

if [ "$mode" = heartbeat ]; then
  hb=(--width 48 --height 48 --max-bounces 4 --seed 9 --aov all --spp 96 --chunk-spp 2)
  "$exe" render "${hb[@]}" -q -o "$dir/process.exr" >/dev/null 2>&1 || fail "1 process failed"
  # a 2-rank job with the hang $1 (WT_TEST_STALL), NAME $2, --rank-timeout 1,
  # bounded by 60 s, its exit status in $status; the render's options follow
  # ($recovery: more mpirun options)
  stalled() {
    local stall=$1 name=$2
    shift 2
    start=$SECONDS
    WT_TEST_STALL=$stall timeout -k 5 60 mpirun --oversubscribe ${recovery:-} -np 2 "$exe" render "$@" --rank-timeout 1 \
      -o "$dir/$name.exr" >"$dir/$name.log" 2>&1
    status=$?
    return $status
  }
  # rank 1's device hangs on its chunk while its heartbeat goes on: no progress
  stalled 1:device device "${hb[@]}" -q
  lostCheck device $status held
  # rank 1 is alive: rank 0 tells it that it was given up on, so that it does
  # not take rank 0's silence towards it for a hung rank 0 and end the job
  grep -q "warning: rank 1: rank 0 gave up on this rank" "$dir/device.log" ||
    fail "device: rank 1 was not told it was given up on: $(cat "$dir/device.log")"
  echo "rank 1's device hung (heartbeats without progress): finished without it in $((SECONDS - start)) s, equal"
  # rank 1 killed under a launcher that lets the job go on (--enable-recovery);
  # hung on its first chunk first, so that the job cannot end before the kill
  start=$SECONDS
  rm -f "$dir/killed.exr.wtckpt"
  WT_TEST_STALL=1:process timeout -k 5 60 mpirun --oversubscribe --enable-recovery -np 2 "$exe" render "${hb[@]}" -q --rank-timeout 1 \
    --checkpoint 0.1 -o "$dir/killed.exr" >"$dir/killed.log" 2>&1 &
  job=$!
  waitForFile "$dir/killed.exr.wtckpt" $job
  rank1=$(rankPid 1 $job)
  [ -n "$rank1" ] || fail "killed: rank 1's process not found: $(cat "$dir/killed.log")"
  kill -9 "$rank1"
  wait $job
  lostCheck killed $? held
  echo "rank 1 killed (mpirun --enable-recovery): finished without it in $((SECONDS - start)) s, equal"
  # rank 0's device hangs on its first chunk: rank 1 renders every chunk
  # (chunk 0 too: the AOV ids of sample 0 cross ranks) and rank 0 ends the
  # job without waiting for its device
  stalled 0:device rank0device "${hb[@]}" -v
  [ $status -eq 0 ] || fail "rank 0's device hung: exit status $status: $(cat "$dir/rank0device.log")"
  grep -q "warning: device 0 (.*) of rank 0 did no sample pass for [0-9.]* s (--rank-timeout 1) on its chunk" \
    "$dir/rank0device.log" || fail "rank 0's device hung: no warning naming it: $(cat "$dir/rank0device.log")"
  grep -q "chunks by rank: 0, 48$" "$dir/rank0device.log" ||
    fail "rank 0's device hung: rank 1 did not render all 48 chunks: $(cat "$dir/rank0device.log")"
  cmp "$dir/rank0device.exr" "$dir/process.exr" ||
    fail "rank 0's device hung: the image differs from 1 process (every AOV layer, the ids of chunk 0 from rank 1)"
  echo "rank 0's device hung: rank 1 rendered all 48 chunks in $((SECONDS - start)) s; equal, every AOV and the ids included"
  # rank 0 itself hangs (after its first checkpoint): rank 1 hears nothing
  # from it for --rank-timeout and ends the job naming it, failed even under
  # mpirun --enable-recovery (whose mpirun exits 0 after any MPI_Abort: rank 1
  # stops mpirun instead); the checkpoint resumes (double accumulation, no
  # AOVs: a checkpoint holds the image alone) to the uninterrupted image
  r0=(--width 48 --height 48 --max-bounces 4 --seed 9 --accumulation double --spp 96 --chunk-spp 2)
  "$exe" render "${r0[@]}" -q -o "$dir/straight.exr" >/dev/null 2>&1 || fail "uninterrupted render failed"
  rm -f "$dir/rank0.exr.wtckpt"
  recovery=--enable-recovery stalled 0:process rank0 "${r0[@]}" -q --checkpoint 0.1
  [ $status -eq 124 ] && fail "rank 0 hung: the job still ran after 60 s: $(cat "$dir/rank0.log")"
  [ $status -ne 0 ] || fail "rank 0 hung: the job exited 0 (mpirun --enable-recovery): $(cat "$dir/rank0.log")"
  grep -q "error: rank 1: rank 0 (which merges and writes the image) sent nothing for [0-9.]* s (--rank-timeout 1)" \
    "$dir/rank0.log" || fail "rank 0 hung: no message naming it: $(cat "$dir/rank0.log")"
  grep -q "error: ending the job as failed by stopping mpirun (SIGTERM): under --enable-recovery" \
    "$dir/rank0.log" || fail "rank 0 hung: no word of why mpirun was stopped: $(cat "$dir/rank0.log")"
  [ -f "$dir/rank0.exr.wtckpt" ] || fail "rank 0 hung: no checkpoint"
  "$exe" render "${r0[@]}" --resume -o "$dir/rank0.exr" >"$dir/rank0-resume.log" 2>&1 ||
    fail "rank 0 hung: its checkpoint does not resume: $(cat "$dir/rank0-resume.log")"
  grep -q "resumed from .* at [1-9][0-9]* samples" "$dir/rank0-resume.log" ||
    fail "rank 0 hung: the checkpoint held no samples: $(cat "$dir/rank0-resume.log")"
  cmp "$dir/rank0.exr" "$dir/straight.exr" || fail "rank 0 hung: the resumed image differs from the uninterrupted one"
  echo "rank 0 hung: rank 1 ended the job in $((SECONDS - start)) s naming it; its checkpoint resumed to the same image"
  # rank 1 hangs before it has started: rank 0 names it and ends the job;
  # and rank 0 hangs before it has started: rank 1 names it. Both jobs at
  # once: each waits on its own --start-timeout, which load only lengthens
  start=$SECONDS
  stalled 1:startup startup "${hb[@]}" -q --start-timeout 1 &
  startup1=$!
  stalled 0:startup startup0 "${hb[@]}" -q --start-timeout 1 &
  startup0=$!
  wait $startup1
  status=$?
  [ $status -eq 124 ] && fail "startup: rank 0 still waited 60 s for rank 1 to start: $(cat "$dir/startup.log")"
  [ $status -ne 0 ] || fail "startup: the job exited 0 without rank 1"
  grep -q "error: the job could not start: rank 1 had not finished starting 1 s after rank 0 (--start-timeout)" \
    "$dir/startup.log" || fail "startup: no message naming rank 1: $(cat "$dir/startup.log")"
  [ -f "$dir/startup.exr" ] && fail "startup: an image was written"
  wait $startup0
  status=$?
  echo "rank 1 hung while starting: the job ended naming it"
  [ $status -eq 124 ] && fail "startup0: rank 1 still waited 60 s for rank 0 to start: $(cat "$dir/startup0.log")"
  [ $status -ne 0 ] || fail "startup0: the job exited 0 without rank 0"
  grep -q "error: the job could not start: rank 0 had not finished starting 1 s after rank 1 (--start-timeout)" \
    "$dir/startup0.log" || fail "startup0: no message naming rank 0: $(cat "$dir/startup0.log")"
  echo "rank 0 hung while starting: the job ended naming it (both in $((SECONDS - start)) s)"
  exit 0
fi

# --- 2 ranks vs 1 process ---------------------------------------------------
# enough work (16 chunks of about 30 ms each) that rank 1, started with rank 0,
# gets chunks even when the machine is busy
big=(--width 64 --height 64 --max-bounces 4 --seed 9 --aov all)
"${mpi[@]}" "$exe" render "${big[@]}" -v --spp 64 --chunk-spp 4 -o "$dir/ranks.exr" >"$dir/ranks.log" 2>&1 ||
  fail "2 ranks (exit status $?): $(cat "$dir/ranks.log")"
grep -q "2 ranks, on device" "$dir/ranks.log" || fail "not 2 ranks: $(cat "$dir/ranks.log")"
# no --checkpoint: on by default in a job of several ranks, said once
grep -q "warning: a job of 2 ranks: every 60 s rank 0 writes the merged samples to .*ranks.exr, and the checkpoint .*--checkpoint 0 turns it off" \
  "$dir/ranks.log" || fail "no word of the default checkpoint: $(cat "$dir/ranks.log")"
grep -q "chunks by rank: [1-9][0-9]*, [1-9]" "$dir/ranks.log" || fail "a rank rendered no chunk: $(cat "$dir/ranks.log")"
"$exe" render "${big[@]}" -q --spp 64 --chunk-spp 4 -o "$dir/process.exr" >/dev/null 2>&1 || fail "1 process failed"
cmp "$dir/ranks.exr" "$dir/process.exr" || fail "2 ranks differ from 1 process (every AOV layer compared)"
echo "2 ranks equal 1 process, byte for byte (every AOV layer included) (at ${SECONDS} s)"

# --- --target-error and --reference on 2 ranks ---------------------------------
# rank 1's chunks that arrive after the boundary that met the target are dropped
reference
te=(--chunk-spp 2 --aov all --target-error 0.06 --reference "$dir/ref.exr" --error-log)
"${mpi[@]}" "$exe" render "${base[@]}" "${te[@]}" "$dir/te-ranks.csv" -o "$dir/te-ranks.exr" >"$dir/te-ranks.log" 2>&1 ||
  fail "2 ranks with --target-error (exit status $?): $(cat "$dir/te-ranks.log")"
"$exe" render "${base[@]}" "${te[@]}" "$dir/te-process.csv" -o "$dir/te-process.exr" >"$dir/te-process.log" 2>&1 ||
  fail "1 process with --target-error: $(cat "$dir/te-process.log")"
cmp "$dir/te-ranks.exr" "$dir/te-process.exr" || fail "--target-error: 2 ranks differ from 1 process"
stopped=$(grep -o "stopped after [0-9]* samples (--target-error reached)" "$dir/te-process.log")
[ -n "$stopped" ] || fail "--target-error not reached: $(cat "$dir/te-process.log")"
grep -q "$stopped" "$dir/te-ranks.log" || fail "2 ranks stopped elsewhere: $(cat "$dir/te-ranks.log")"
cmp <(cut -d, -f1,3- "$dir/te-ranks.csv") <(cut -d, -f1,3- "$dir/te-process.csv") ||
  fail "--reference: 2 ranks log other errors: $(cat "$dir/te-ranks.csv" "$dir/te-process.csv")"
echo "--target-error 0.06 and --reference on 2 ranks: $stopped, image and error log equal 1 process (at ${SECONDS} s)"

# --- rank 1 killed mid-render -------------------------------------------------
dbl=(--width 24 --height 16 --max-bounces 4 --seed 9 --accumulation double --chunk-spp 2)
"${mpi[@]}" "$exe" render "${dbl[@]}" -q --spp 1000000 --checkpoint 0.2 -o "$dir/killed.exr" >"$dir/killed.log" 2>&1 &
job=$!
waitForFile "$dir/killed.exr.wtckpt" $job
rank1=$(rankPid 1 $job)
[ -n "$rank1" ] || fail "rank 1's process not found among mpirun's children: $(ps -o pid,ppid,stat,comm --ppid $job) $(cat "$dir/killed.log")"
killRankAndWait "$rank1" $job 120 "$dir/killed.log"
grep -q "stopped by a signal after [0-9]* of 1000000 samples (under mpirun also when a rank died" "$dir/killed.log" ||
  fail "no clear error: $(cat "$dir/killed.log")"
grep -q "merged samples were written" "$dir/killed.log" || fail "nothing written: $(cat "$dir/killed.log")"
# named: the rank heard from least recently, or (died mid-message) the rank lost
grep -Eq "the rank silent longest: rank 1 on host [^ ]+, for [0-9.]+ s\)|warning: rank 1 (failed while sending|stopped sending)" \
  "$dir/killed.log" || fail "rank 1 not named: $(cat "$dir/killed.log")"
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

# --- rank 0 killed with no signal before (as Slurm's srun kills a step) --------
# nothing is written at the end: what remains is the job's last periodic
# write (every checkpoint also writes the outputs in a job of several ranks).
# Rank 0 hangs once it has started its first checkpoint (WT_TEST_STALL), so
# that the files are of one write when it is killed: the EXR records its
# sample count, and it and the PNG equal 1 process with that many samples
rm -f "$dir/sigkill".*
WT_TEST_STALL=0:process "${mpi[@]}" "$exe" render "${dbl[@]}" -q --spp 1000000 --checkpoint 0.2 \
  -o "$dir/sigkill.exr" -o "$dir/sigkill.png" >"$dir/sigkill.log" 2>&1 &
job=$!
waitForFile "$dir/sigkill.png" $job
rank0=$(rankPid 0 $job)
[ -n "$rank0" ] || fail "rank 0's process not found: $(cat "$dir/sigkill.log")"
kill -9 "$rank0"
wait $job
[ $? -eq 124 ] && fail "rank 0 killed: the job did not end: $(cat "$dir/sigkill.log")"
[ -f "$dir/sigkill.exr" ] || fail "rank 0 killed: no periodic image: $(cat "$dir/sigkill.log")"
n=$(exrSamples "$dir/sigkill.exr")
[ -n "$n" ] && [ "$n" -gt 0 ] || fail "rank 0 killed: the image records no sample count"
"$exe" render "${dbl[@]}" -q --spp "$n" -o "$dir/sigkill1.exr" -o "$dir/sigkill1.png" >/dev/null 2>&1 || fail "1 process failed"
cmp "$dir/sigkill.exr" "$dir/sigkill1.exr" || fail "rank 0 killed: the periodic image differs from 1 process at $n samples"
cmp "$dir/sigkill.png" "$dir/sigkill1.png" || fail "rank 0 killed: the periodic PNG differs from 1 process at $n samples"
ls -A "$dir" | grep -q '^\.sigkill' && fail "rank 0 killed: hidden partial files left: $(ls -A "$dir")"
echo "rank 0 killed (SIGKILL): its periodic EXR and PNG of $n samples equal 1 process (at ${SECONDS} s)"

# --- a rank that cannot load the scene ------------------------------------------
# under mpirun --enable-recovery, which exits 0 whatever its ranks' exit
# status: rank 0 stops mpirun (a plain mpirun passes on rank 0's status 1)
out=$(timeout 120 mpirun --oversubscribe --enable-recovery -np 1 "$exe" render --width 8 --height 8 --spp 4 \
  -o "$dir/noscene.exr" : -np 1 "$exe" render "$dir/missing.gltf" --width 8 --height 8 --spp 4 -o "$dir/noscene.exr" 2>&1)
status=$?
[ $status -eq 124 ] && fail "the job hung when rank 1 could not load its scene"
[ $status -ne 0 ] || fail "the job exited 0 (mpirun --enable-recovery) when rank 1 could not load its scene: $out"
echo "$out" | grep -q "the job could not start: rank 1: .*missing.gltf" || fail "no rank 1 message: $out"
[ -f "$dir/noscene.exr" ] && fail "an image was written"
echo "rank 1 without its scene: the job stopped at start with its message (at ${SECONDS} s)"
exit 0
