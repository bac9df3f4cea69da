#!/usr/bin/env bash
# probe.sh BIN SUITE TAG: per-case processes (cold cache, then warm) against one process for the suite (cold, warm)
# prints CPU-s (user+sys) and wall for each mode
set -u
bin=$1; suite=$2; tag=$3
cases=$($bin --gtest_list_tests --gtest_filter="$suite.*" | awk '/^[^ ]/ {s=$1} /^  / {print s $1}')
t() { /usr/bin/time -f "%U %S %e" -o /tmp/ci16/t.$$ "$@" >/dev/null 2>&1; rc=$?; awk -v rc=$rc '{printf "%.2f %.2f rc%s", $1+$2, $3, rc}' /tmp/ci16/t.$$; }
export WAVETRACE_CACHE_DIR=off
for mode in case-cold case-warm suite-cold suite-warm; do
  case $mode in
    *-cold) d=/tmp/ci16/pc/$tag-$mode; rm -rf $d; mkdir -p $d; export POCL_CACHE_DIR=$d ;;
  esac
  cpu=0; wall=0
  if [[ $mode == case-* ]]; then
    tot=0; tw=0
    for c in $cases; do r=$(t $bin --gtest_filter=$c); tot=$(echo "$tot + ${r%% *}" | bc); w=$(echo $r | cut -d' ' -f2); tw=$(echo "$tw + $w" | bc); done
    echo "$suite $mode cpu $tot wall $tw n=$(echo $cases | wc -w) load $(cut -d' ' -f1 /proc/loadavg)"
  else
    r=$(t $bin --gtest_filter="$suite.*"); echo "$suite $mode $r load $(cut -d' ' -f1 /proc/loadavg)"
  fi
done
