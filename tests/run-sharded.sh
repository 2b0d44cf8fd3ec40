#!/usr/bin/env bash
# Runs a GoogleTest executable as a few processes at once (GoogleTest's own sharding:
# GTEST_TOTAL_SHARDS / GTEST_SHARD_INDEX), each shuffled with one seed, instead of one process per
# test as ctest does.
#
# Why: under AddressSanitizer one process of osgBTF_tests needs about a second before its first
# test (some 290 shared libraries to relocate, the sanitizer's set-up, LeakSanitizer's scan at
# exit): with ~490 tests that was half of CI's sanitizer test time. Every test still runs exactly
# once; the tests pass in any order inside one process (tests/README.md), and a shuffled order
# checks that one test leaves nothing behind that changes the next.
#
# Four shards per core, run one per core at a time (--jobs, default the number of cores), each
# with one TBB thread (OSGBTF_TEST_TBB_THREADS, read by tests/TestUtil.cpp). GoogleTest splits
# the tests by count, not by time: with one shard per core the shard that drew the long fits
# ended 100 s after the other, while smaller shards taken as cores free up even that out. One
# thread each costs no parallelism (the shards are the parallelism) and under the sanitizers
# removes the threads' contention on libFuzzer's coverage counters. CI's sanitizer test time,
# measured: 393 s as two shards of two threads, 334 s as eight of one (30 CPU-s of it from one
# test made shorter, materials_filtering_test.cpp), 256 s once the long accuracy fits moved to
# the normal build (.ci/run). Six shards per core measured 274 s against those 256 s (runs differ
# by +-20 s here): no gain shown, so four.
#
# Usage: tests/run-sharded.sh [--shards N] [--jobs J] [--seed S] [--timeout SECONDS] [--logs DIR]
#                             EXECUTABLE [GoogleTest arguments...]
# Exit status 0 when every shard passed. A failing shard's failures and the end of its log are
# printed (a sanitizer report or a crash ends the log); the whole logs stay in DIR.
set -euo pipefail

jobs=$(nproc)
shards=$((4 * jobs))
seed=1
timeout_s=1800
logs=""
while [ $# -gt 0 ]; do
  case "$1" in
    --shards) shards=$2; shift 2 ;;
    --jobs) jobs=$2; shift 2 ;;
    --seed) seed=$2; shift 2 ;;
    --timeout) timeout_s=$2; shift 2 ;;
    --logs) logs=$2; shift 2 ;;
    -*) echo "run-sharded.sh: unknown option $1" >&2; exit 2 ;;
    *) break ;;
  esac
done
if [ $# -lt 1 ] || [ ! -x "$1" ]; then
  echo "run-sharded.sh: no executable given, or '${1:-}' is not executable" >&2
  exit 2
fi
executable=$1
shift
logs=${logs:-$(mktemp -d)}
mkdir -p "$logs"

start=$(date +%s)
run_shard() {
  local status=0
  OSGBTF_TEST_TBB_THREADS=1 GTEST_TOTAL_SHARDS=$shards GTEST_SHARD_INDEX=$1 \
    timeout --kill-after=30 "$timeout_s" \
    "$executable" --gtest_shuffle --gtest_random_seed="$seed" --gtest_brief=1 \
    --gtest_output="xml:$logs/shard-$1.xml" "${test_arguments[@]}" \
    >"$logs/shard-$1.log" 2>&1 || status=$?
  echo "$status" >"$logs/shard-$1.status"
}
test_arguments=("$@")
running=0
for ((i = 0; i < shards; ++i)); do
  if [ "$running" -ge "$jobs" ]; then
    wait -n
    running=$((running - 1))
  fi
  run_shard "$i" &
  running=$((running + 1))
done
wait
failed=0
for ((i = 0; i < shards; ++i)); do
  status=$(cat "$logs/shard-$i.status")
  log=$logs/shard-$i.log
  summary=$(grep -E '^\[==========\] .* ran\.' "$log" || true)
  if [ "$status" -eq 0 ]; then
    echo "shard $((i + 1))/$shards: ${summary#\[==========\] } passed"
    continue
  fi
  failed=1
  if [ "$status" -eq 124 ] || [ "$status" -eq 137 ]; then
    echo "shard $((i + 1))/$shards: killed after ${timeout_s} s (exit $status)"
  else
    echo "shard $((i + 1))/$shards: FAILED (exit $status)"
  fi
  grep -E '^\[  FAILED  \]' "$log" | sort -u || true
  echo "--- last 200 lines of $log"
  tail -n 200 "$log"
  echo "---"
done
echo "$(basename "$executable"): $shards shards, $jobs at a time, seed $seed, $(($(date +%s) - start)) s; logs in $logs"
# Where the time goes (GoogleTest's XML reports): the slowest tests, for whoever shortens CI.
echo "slowest tests (s):"
cat "$logs"/shard-*.xml 2>/dev/null | grep -o '<testcase name="[^"]*".* time="[^"]*".* classname="[^"]*"' |
  sed -E 's/<testcase name="([^"]*)".* time="([^"]*)".* classname="([^"]*)"/\2 \3.\1/' |
  sort -rn | head -n 12 | sed 's/^/  /' || true
exit "$failed"
