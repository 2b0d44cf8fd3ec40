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
# Usage: tests/run-sharded.sh [--shards N] [--seed S] [--timeout SECONDS] [--logs DIR]
#                             EXECUTABLE [GoogleTest arguments...]
# Exit status 0 when every shard passed. A failing shard's failures and the end of its log are
# printed (a sanitizer report or a crash ends the log); the whole logs stay in DIR.
set -euo pipefail

shards=$(nproc)
seed=1
timeout_s=1800
logs=""
while [ $# -gt 0 ]; do
  case "$1" in
    --shards) shards=$2; shift 2 ;;
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
pids=()
for ((i = 0; i < shards; ++i)); do
  GTEST_TOTAL_SHARDS=$shards GTEST_SHARD_INDEX=$i timeout --kill-after=30 "$timeout_s" \
    "$executable" --gtest_shuffle --gtest_random_seed="$seed" --gtest_brief=1 "$@" \
    >"$logs/shard-$i.log" 2>&1 &
  pids+=($!)
done
failed=0
for ((i = 0; i < shards; ++i)); do
  status=0
  wait "${pids[$i]}" || status=$?
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
echo "$(basename "$executable"): $shards shards, seed $seed, $(($(date +%s) - start)) s; logs in $logs"
exit "$failed"
