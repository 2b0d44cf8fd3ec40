#!/usr/bin/env bash
# CI's short fuzz pass: every target for SECONDS on its seeds and regression inputs,
# JOBS targets at a time (one process each), in a fresh temporary folder. Fails when a target
# exits non-zero or leaves a crash-/leak-/timeout-/oom- file (libFuzzer stops at its first
# finding), and prints that target's log.
#   fuzz/ci.sh BUILD SEEDS SECONDS [JOBS]
# BUILD: a build with -DOSGBTF_BUILD_FUZZERS=ON (.ci/run's sanitizer build); SEEDS: the output
# folder of osgbtf_fuzz_seeds.
set -euo pipefail
if [ $# -lt 3 ]; then
  sed -n '2,8p' "$0"
  exit 2
fi
build=$(realpath "$1") seeds=$(realpath "$2") seconds=$3 jobs=${4:-2}
here=$(cd "$(dirname "$0")" && pwd)
targets=(ubo2003_zip ubo2014 fitted_material coordinate_map btfmat_plugin plugin_names scene_file
  bsvtf_tiles rti_files)
# The targets write every input to a file under $TMPDIR: memory, not disk, where there is one.
if [ -d /dev/shm ] && [ -w /dev/shm ]; then export TMPDIR=/dev/shm; fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

run_target() {
  local t=$1 corpus=$work/corpus/$1
  mkdir -p "$corpus" "$work/findings/$t"
  cp "$seeds/$t"/* "$corpus"/
  cp "$here/regression/$t"/* "$corpus"/  # the same name as a seed: the same seed
  # -detect_leaks=0: the first CI runs found two leaks that are not osgBTF's (fuzz/README.md
  # "Open"): OSG's reader keeps a scene whose UniqueIDs make a cycle of ref_ptrs, and a 31-byte
  # string from an uninstrumented image library on a damaged PNG. osgBTF's own leaks are checked by
  # the unit tests, which run with LeakSanitizer on.
  # -timeout=5: an input over 5 s is a hang. The new inputs go to the temporary corpus
  # (the first folder), never into the source tree.
  ASAN_OPTIONS="detect_leaks=0${ASAN_OPTIONS:+:$ASAN_OPTIONS}" "$build/bin/fuzz_$t" "$corpus" -dict="$here/dict/$t.dict" -max_total_time="$seconds" \
    -timeout=5 -rss_limit_mb=2048 -max_len=65536 -print_final_stats=1 -detect_leaks=0 \
    -artifact_prefix="$work/findings/$t/" >"$work/$t.log" 2>&1
}

failed=0
for ((i = 0; i < ${#targets[@]}; i += jobs)); do
  pids=() batch=("${targets[@]:i:jobs}")
  for t in "${batch[@]}"; do
    run_target "$t" &
    pids+=($!)
  done
  for k in "${!batch[@]}"; do
    t=${batch[k]}
    status=0
    wait "${pids[k]}" || status=$?
    findings=$(ls "$work/findings/$t")
    execs=$(awk '/^stat::number_of_executed_units/ {print $2}' "$work/$t.log" 2>/dev/null || true)
    cov=$(grep -E '^#[0-9]+' "$work/$t.log" 2>/dev/null | tail -1 | grep -oE 'cov: [0-9]+ ft: [0-9]+' || true)
    echo "fuzz_$t: exit $status, ${execs:-?} executions in ${seconds} s, $cov"
    if [ "$status" != 0 ] || [ -n "$findings" ]; then
      failed=1
      echo "fuzz_$t FAILED; findings: ${findings:-none}; the end of its log:"
      tail -60 "$work/$t.log" || true
      # The inputs, for reproducing (fuzz/README.md): base64, since CI keeps only the log.
      for f in $findings; do
        echo "== $f (base64)"
        base64 "$work/findings/$t/$f" | head -200
      done
    fi
  done
done
exit $failed
