#!/bin/sh
# methods fitted straight from a UBO2014 file's factors (BtfSource: each
# block a method reads is decoded with one GEMM; the 22 GB of values never exist at once).
# Each `btf fit` runs under /usr/bin/time -v for wall time and peak RSS; its own output gives
# the fit time and the error (on btf fit's default random subsample of 4096 texels). The base
# level alone (--no-mipmap), as the issue's bounds were set.
#
# Usage: bench/fit_ubo2014.sh [BUILD_DIR] [SIZE] [METHODS]
#   BUILD_DIR (default ./build) must hold bin/btf and bin/bench_make_ubo2014
#   (cmake -DOSGBTF_BUILD_BENCH=ON). SIZE: texels per side (default 400, the files' size).
#   METHODS: space-separated (default "pca lpca", the two the issue bounds: <= 10 min and
#   <= 6 GB peak RSS each at 400x400 on the 2-core machine). The per-texel methods (laf, slaf,
#   rf) take hours at full size; measure them at a smaller SIZE (e.g. 64) and scale by texels.
# Input: made once with bench_make_ubo2014 (DFMF, colour model 11, 151 x 151 Dome-1 directions,
# K = 100 per channel, half scalars) and cached in $TMPDIR (default /tmp), shared with
# bench/open_ubo2014.sh. Timings depend on other load: run it on an otherwise idle machine.
set -eu
build=${1:-build}
size=${2:-400}
methods=${3:-pca lpca}
. "$(dirname "$0")/ubo2014_input.sh"
ubo2014_input "$build" "$size" 100 btf
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for method in $methods; do
    echo "== btf fit $file -m $method"
    if ! /usr/bin/time -v "$build/bin/btf" --no-progress fit "$file" -m "$method" \
        --no-mipmap -o "$out/$method.btfmat" >"$out/log" 2>"$out/time"; then
        cat "$out/log" "$out/time" >&2
        exit 1
    fi
    grep -E "^time:|^memory:|^error over|^per-texel" "$out/log" | sed 's/^/    /'
    grep -E "Elapsed \(wall clock\)|Maximum resident set size" "$out/time" | sed 's/^\s*/    /'
    rm -f "$out/$method.btfmat"
done
