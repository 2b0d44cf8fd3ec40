#!/usr/bin/env bash
# Runs every fuzz target (or the ones named) for SECONDS each, one after the other, on a corpus
# that starts from the seeds and the regression inputs; prints libFuzzer's final figures.
#   fuzz/run.sh BUILD_FUZZ SEEDS SECONDS [TARGET...]
# BUILD_FUZZ: a build with -DOSGBTF_BUILD_FUZZERS=ON (fuzz/README.md); SEEDS: the output folder
# of osgbtf_fuzz_seeds. Corpora grow in fuzz/out/corpus/<target> (kept between runs), findings
# land in fuzz/out/findings/<target>-*, logs in fuzz/out/logs/<target>.log. FUZZ_ARGS: more
# libFuzzer flags (e.g. FUZZ_ARGS=-runs=1000000: stop at a million executions or SECONDS).
set -euo pipefail
if [ $# -lt 3 ]; then
  sed -n '2,7p' "$0"
  exit 2
fi
build=$(realpath "$1") seeds=$(realpath "$2") seconds=$3
shift 3
here=$(cd "$(dirname "$0")" && pwd)
targets=("$@")
[ ${#targets[@]} -gt 0 ] ||
  targets=(ubo2003_zip ubo2014 fitted_material coordinate_map btfmat_plugin plugin_names scene_file)
out=$here/out
mkdir -p "$out/corpus" "$out/findings" "$out/logs"
for t in "${targets[@]}"; do
  corpus=$out/corpus/$t
  mkdir -p "$corpus"
  if [ -d "$seeds/$t" ]; then cp -n "$seeds/$t"/* "$corpus"/ 2>/dev/null || true; fi
  cp -n "$here/regression/$t"/* "$corpus"/ 2>/dev/null || true
  # -timeout=5: an input over 5 s is a hang; -rss_limit_mb: libFuzzer's default,
  # stated; -max_len: large enough for the seeds (fitted materials of a few KB).
  set +e
  # shellcheck disable=SC2086  # FUZZ_ARGS: separate libFuzzer flags
  # /usr/bin/time: the CPU seconds the target really had (on a shared machine, less than its
  # wall time), the figure a campaign's table needs next to the executions.
  # -detect_leaks=0 as in ci.sh: the two leaks of fuzz/open/ are OSG's and an image library's and
  # stop a target within seconds; osgBTF's own leaks are the unit tests' (LeakSanitizer on).
  ASAN_OPTIONS="detect_leaks=0${ASAN_OPTIONS:+:$ASAN_OPTIONS}" \
    /usr/bin/time -f "cpu: %U s user + %S s system, %e s wall" -o "$out/logs/$t.time" \
    "$build/bin/fuzz_$t" "$corpus" -dict="$here/dict/$t.dict" -max_total_time="$seconds" \
    -timeout=5 -rss_limit_mb=2048 -max_len=65536 -print_final_stats=1 -detect_leaks=0 \
    -artifact_prefix="$out/findings/$t-" ${FUZZ_ARGS:-} >"$out/logs/$t.log" 2>&1
  status=$?
  set -e
  echo "== $t (exit $status): $(grep -E '^#[0-9]+' "$out/logs/$t.log" | tail -1)"
  grep -E '^stat::(number_of_executed_units|peak_rss_mb)' "$out/logs/$t.log" || true
  cat "$out/logs/$t.time"
  find "$out/findings" -maxdepth 1 -name "$t-*" -printf '%f\n'
done
