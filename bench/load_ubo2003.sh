#!/bin/sh
# Times osgBTF::loadUbo2003 on a UBO2003-style zip: 6561 JPEG members (Bonn 81 lights x 81
# views) of 256x256 texels, loaded into float storage. Goal: <= 8 s on a 2-core machine.
#
# Usage: bench/load_ubo2003.sh [BUILD_DIR] [SIZE]
#   BUILD_DIR (default ./build) must hold bin/bench_load_ubo2003
#   (ninja -C BUILD_DIR bench_load_ubo2003). SIZE defaults to 256 texels per side.
#
# Input: when BUILD_DIR/bin/btf exists, `btf sample -o ZIP --size SIZE` writes the built-in
# sample material (realistic structure); otherwise bench_load_ubo2003 generates a synthetic BTF
# itself (smooth pattern plus noise). Both write JPEG quality 95 via osgBTF::writeUbo2003Zip. The
# zip is cached in $TMPDIR (default /tmp) and reused by later runs; delete it to regenerate.
# Memory: ~5 GiB for the loaded float BTF (plus the generated BTF while writing the zip).
# Timings depend on other load on the machine: run it on an otherwise idle machine.
set -eu
build=${1:-build}
size=${2:-256}
bench="$build/bin/bench_load_ubo2003"
if [ ! -x "$bench" ]; then
    echo "missing $bench; build it with: ninja -C $build bench_load_ubo2003" >&2
    exit 1
fi
zip="${TMPDIR:-/tmp}/osgbtf-bench-ubo2003-sample-$size.zip"
if [ ! -f "$zip" ] && [ -x "$build/bin/btf" ]; then
    echo "writing $zip with: btf sample -o $zip --size $size"
    start=$(date +%s.%N)
    "$build/bin/btf" sample -o "$zip" --size "$size"
    echo "written in $(echo "$(date +%s.%N) - $start" | bc) s"
fi
if [ -f "$zip" ]; then
    exec "$bench" --zip "$zip"
fi
exec "$bench" --size "$size" --keep
