#!/bin/bash
# The first image of a full-size UBO2014 file on the CPU, like for like (issue 63, section 3):
# the Free BTF Library's btf.hh (load the file, decode one (light, view) image) against osgBTF's
# CPU paths for the same image, each a fresh process, interleaved, medians of ROUNDS rounds:
#   btf.hh            bench/btfhh/first_image_btfhh.cpp compiled against the btf.hh you name
#   btf eval --cpu    open the file as an fmf material (no OpenGL context), evaluate, write EXR
#   python load       osgbtf.load(FILE).image(view, light): the measured BTF, decoded on demand
#   python material   osgbtf.open_material(FILE).image(view, light): the fmf material's CPU image
#   python import     the interpreter, numpy and osgbtf alone: what the two Python rows carry
#
#   bench/first_image_cpu.sh BUILD BTF_HH [ROUNDS]
#
# BUILD: a build with bin/btf, bin/bench_make_ubo2014 and python/osgbtf*.so (-DOSGBTF_BUILD_BENCH=ON).
# BTF_HH: path to btf.hh (github.com/zeroeffects/btf, MIT; not shipped with osgBTF). Input: the
# synthetic full-size file of bench/ubo2014_input.sh (400 x 400 texels, 151 x 151 directions,
# K = 100 half scalars: 110 MB), made once in $TMPDIR. Reports CPU seconds (user + system: what
# another load on the machine stretches least), wall seconds and peak resident memory; the sums
# of the image's channels show that every path decoded the same values. A benchmark: it never
# fails on a time.
set -euo pipefail
BUILD=$(cd "${1:?usage: bench/first_image_cpu.sh BUILD BTF_HH [ROUNDS]}" && pwd)
BTF_HH=${2:?usage: bench/first_image_cpu.sh BUILD BTF_HH [ROUNDS]}
ROUNDS=${3:-5}
SRC=$(cd "$(dirname "$0")/.." && pwd)
. "$SRC/bench/ubo2014_input.sh"
ubo2014_input "$BUILD" 400 100 btf
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
[ -f "$BTF_HH" ] || { echo "no btf.hh at $BTF_HH" >&2; exit 1; }
g++ -O2 -march=native -std=c++17 -I"$(dirname "$BTF_HH")" "$SRC/bench/btfhh/first_image_btfhh.cpp" \
    -o "$WORK/first_image_btfhh"
LIGHT=10 VIEW=20
line=$("$WORK/first_image_btfhh" "$file" $LIGHT $VIEW)
echo "$line"
light=$(sed -E 's/.*light ([0-9.]+,[0-9.]+).*/\1/' <<<"$line")
view=$(sed -E 's/.* view ([0-9.]+,[0-9.]+).*/\1/' <<<"$line")
export OSG_LIBRARY_PATH="$BUILD/lib" PYTHONPATH="$BUILD/python"
cat >"$WORK/image.py" <<PY
import sys, numpy as np, osgbtf
path, mode = sys.argv[1], sys.argv[2]
if mode == "import":
    image = np.zeros((1, 3))
elif mode == "load":
    image = osgbtf.load(path).image($VIEW, $LIGHT)
else:
    image = osgbtf.open_material(path).image(($view), ($light))
print("sum", " ".join("%.6g" % v for v in image.reshape(-1, 3).sum(0, dtype=np.float64)))
PY
run() {  # NAME COMMAND...: appends "NAME cpu wall peak_kib" to $WORK/times
    local name=$1
    shift
    /usr/bin/time -f "%U %S %e %M" -o "$WORK/t" "$@" >"$WORK/out" 2>&1 ||
        { cat "$WORK/out" >&2; exit 1; }
    read -r user sys wall peak <"$WORK/t"
    echo "$name $(echo "$user + $sys" | bc) $wall $peak" >>"$WORK/times"
    [ "$round" = 1 ] && echo "  $name: $(grep -o 'sum.*' "$WORK/out" | head -1)"
    return 0
}
for round in $(seq "$ROUNDS"); do
    run btf.hh "$WORK/first_image_btfhh" "$file" $LIGHT $VIEW
    run "btf-eval-cpu" "$BUILD/bin/btf" --no-progress eval "$file" --view "$view" \
        --light "$light" --cpu -o "$WORK/cpu.exr"
    run "python-load" /usr/bin/python3 "$WORK/image.py" "$file" load
    run "python-material" /usr/bin/python3 "$WORK/image.py" "$file" material
    run "python-import-only" /usr/bin/python3 "$WORK/image.py" "$file" import
done
echo
echo "| path | CPU s (median of $ROUNDS) | wall s | peak RSS MiB |"
echo "|---|---|---|---|"
for name in btf.hh btf-eval-cpu python-load python-material python-import-only; do
    awk -v n="$name" '$1 == n {print $2, $3, $4}' "$WORK/times" | sort -n | awk -v n="$name" '
        {cpu[NR] = $1; wall[NR] = $2; peak[NR] = $3}
        END {m = int((NR + 1) / 2); printf "| %s | %.2f | %.2f | %.0f |\n", n, cpu[m], wall[m], peak[m] / 1024}'
done
