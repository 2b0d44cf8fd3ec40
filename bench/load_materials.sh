#!/bin/sh
# Peak host memory of loading fitted materials against their size (issue goal: the growth while
# loading at most 1.1x the material's textures): fits each method to the built-in sample of SIZE
# x SIZE texels once (cached in $TMPDIR, default /tmp), then bench_load_material on the fits.
# Usage: bench/load_materials.sh [BUILD_DIR] [SIZE] [METHODS]
#   defaults: ./build, 256, "lambert pca fmf ptm lpca"; BUILD_DIR needs bin/btf and
#   bin/bench_load_material (cmake -DOSGBTF_BUILD_BENCH=ON).
set -eu
build=${1:-build}
size=${2:-256}
methods=${3:-lambert pca fmf ptm lpca}
for tool in btf bench_load_material; do
    if [ ! -x "$build/bin/$tool" ]; then
        echo "missing $build/bin/$tool; build with -DOSGBTF_BUILD_BENCH=ON" >&2
        exit 1
    fi
done
dir="${TMPDIR:-/tmp}/osgbtf-bench-load-$size"
mkdir -p "$dir"
[ -f "$dir/sample.zip" ] || "$build/bin/btf" --no-progress sample -o "$dir/sample.zip" --size "$size"
files=""
for m in $methods; do
    [ -f "$dir/$m.btfmat" ] || "$build/bin/btf" --no-progress fit "$dir/sample.zip" -m "$m" \
        --no-mipmap -o "$dir/$m.btfmat" >/dev/null
    files="$files $dir/$m.btfmat"
done
# shellcheck disable=SC2086
"$build/bin/bench_load_material" $files
