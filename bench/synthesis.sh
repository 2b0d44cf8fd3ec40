#!/bin/sh
# Boßerhoff and Nicoll 2003 Table 1 in our run: `btf synthesize` with 3 levels on the 64x64
# built-in sample (all 6561 images), at the paper's five settings, beside the paper's times (Pentium 4 2.4 GHz; the
# paper times the synthesis "without the time for calculating the texton map", so the table's
# `synthesis` column is the one to compare; `analysis` is our texton map, texton matrix and
# candidate lists, which depend on k and the neighbourhood).
#
# Usage: bench/synthesis.sh [BUILD_DIR] [SIZE]
#   BUILD_DIR (default ./build) must hold bin/btf; SIZE is the sample's side (default 64).
# The sample zip is cached in $TMPDIR (default /tmp); the maps are written there too.
# Timings depend on other load on the machine (printed first): run it on an idle machine.
set -eu
build=${1:-build}
size=${2:-64}
btf="$build/bin/btf"
if [ ! -x "$btf" ]; then
    echo "missing $btf; build it with: ninja -C $build btf" >&2
    exit 1
fi
tmp=${TMPDIR:-/tmp}
zip="$tmp/osgbtf-bench-synthesis-sample-$size.zip"
[ -f "$zip" ] || "$btf" --no-progress sample -o "$zip" --size "$size" >/dev/null
echo "machine: $(nproc) cores, load: $(uptime | sed 's/.*load average: //')"
echo
echo "| output | k | neighbourhood | paper (s) | synthesis (s) | analysis (s) | load (s) | coherence rate | seam ratio |"
echo "|---|---|---|---|---|---|---|---|---|"
for setting in "256 1 2 1.9" "256 3 2 2.7" "256 6 2 3.7" "256 6 3 13.6" "512 6 2 13.4"; do
    set -- $setting
    out=$("$btf" --no-progress synthesize "$zip" --size "$1" --k "$2" --neighbourhood "$3" \
        --levels 3 --seed 1 -o "$tmp/osgbtf-bench-synthesis-$1-$2-$3.exr")
    times=$(echo "$out" | sed -n 's/^time: load \([0-9.]*\) s, analysis \([0-9.]*\) s, synthesis \([0-9.]*\) s$/\1 \2 \3/p')
    rate=$(echo "$out" | sed -n 's/^coherence rate \([0-9.]*\) .*/\1/p')
    seam=$(echo "$out" | sed -n 's/^seam ratio \([0-9.]*\) .*/\1/p')
    set -- $1 $2 $3 $4 $times
    echo "| ${1}x$1 | $2 | $3 | $4 | $7 | $6 | $5 | $rate | $seam |"
done
