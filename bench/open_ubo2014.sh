#!/bin/sh
# Benchmarks on a full-size UBO2014 file used as stored (no decode, no refit):
#   1. `btf info FILE` (header and factors; goal < 1 s),
#   2. bench_open_ubo2014: open (read + fmf material) and the first rendered frame, headless
#      (goal <= 5 s, peak RSS <= 1.5 GB),
#   3. `btfviewer FILE --frames 1` under Xvfb: the viewer's open + first frame + exit (same goal),
# each under /usr/bin/time -v for wall time and peak RSS.
#
# Usage: bench/open_ubo2014.sh [BUILD_DIR] [SIZE] [COMPONENTS]
#   BUILD_DIR (default ./build) must hold bin/btf, bin/btfviewer, bin/bench_make_ubo2014 and
#   bin/bench_open_ubo2014 (cmake -DOSGBTF_BUILD_BENCH=ON). SIZE defaults to 400 texels per side,
#   COMPONENTS to 100 per channel (the UBO2014 files' size).
# Input: made once with bench_make_ubo2014 (DFMF, colour model 11, 151 x 151 Dome-1 directions,
# half scalars: 110 MB at full size) and cached in $TMPDIR (default /tmp); delete it to remake.
# Timings depend on other load on the machine: run it on an otherwise idle machine.
set -eu
build=${1:-build}
size=${2:-400}
components=${3:-100}
. "$(dirname "$0")/ubo2014_input.sh"
ubo2014_input "$build" "$size" "$components" btf btfviewer bench_open_ubo2014
measure() {
    # Wall time and peak RSS from GNU time; the command's own output first.
    /usr/bin/time -v "$@" 2>"$tmp" || { cat "$tmp" >&2; exit 1; }
    grep -E "Elapsed \(wall clock\)|Maximum resident set size" "$tmp" | sed 's/^\s*/    /'
}
tmp=$(mktemp)
trap 'rm -f "$tmp"' EXIT
echo "== btf info $file"
measure "$build/bin/btf" --no-progress info "$file"
echo "== bench_open_ubo2014 (headless EGL)"
measure "$build/bin/bench_open_ubo2014" "$file"
echo "== btfviewer --frames 1 under Xvfb"
export OSG_LIBRARY_PATH="$build/lib"
measure xvfb-run -a -s "-screen 0 1280x1024x24" "$build/bin/btfviewer" "$file" --frames 1 \
    --window 0 0 1024 768
