#!/bin/sh
# Time per sample with the scene's specialised program and with the general
# program (render --general-program: every kernel switch on), alternating
# the two in one run so that both see the same machine load. Prints one row
# per scene: median ms per sample of each, and specialised/general speed-up.
#   scripts/specialised/vs_general.sh BUILD_DIR [RUNS] [SPP] [SIZE] [SCENE...]
# Scenes default to the built-in Cornell box and DamagedHelmet from
# ../shared/assets. The first render of each kind is a warm-up (PoCL's
# kernel cache), not counted.
set -eu
build=${1:?usage: vs_general.sh BUILD_DIR [RUNS] [SPP] [SIZE] [SCENE...]}
runs=${2:-5}
spp=${3:-16}
size=${4:-512}
shift $(( $# < 4 ? $# : 4 ))
root=$(cd "$(dirname "$0")/../.." && pwd)
[ $# -gt 0 ] || set -- cornell "$root/../shared/assets/gltf/DamagedHelmet/glTF/DamagedHelmet.gltf"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
ms_per_sample() {  # scene, extra flag: the -v line "... ms per sample"
  scene=$1; shift
  if [ "$scene" = cornell ]; then set -- "$@"; else set -- "$scene" "$@"; fi
  "$build/wavetrace" render "$@" -v --spp "$spp" --width "$size" --height "$size" --seed 1 -o "$out/x.exr" 2>&1 |
    sed -n 's/.*: \([0-9.]*\) ms per sample/\1/p'
}
median() { sort -n | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}'; }
printf "%-20s %12s %12s %8s\n" scene specialised general speed-up
for scene in "$@"; do
  ms_per_sample "$scene" >/dev/null
  ms_per_sample "$scene" --general-program >/dev/null
  : >"$out/s"; : >"$out/g"
  i=0
  while [ $i -lt "$runs" ]; do
    ms_per_sample "$scene" >>"$out/s"
    ms_per_sample "$scene" --general-program >>"$out/g"
    i=$((i + 1))
  done
  s=$(median <"$out/s"); g=$(median <"$out/g")
  printf "%-20s %12s %12s %8s\n" "$(basename "$scene")" "$s" "$g" "$(echo "$g $s" | awk '{printf "%.3f", $1 / $2}')"
  echo "  specialised runs: $(tr '\n' ' ' <"$out/s")" >&2
  echo "  general runs:     $(tr '\n' ' ' <"$out/g")" >&2
done
