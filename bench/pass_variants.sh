#!/bin/bash
# ptm's and hsh's pass against lambert's (btf compare, Table 3: the pass minus the empty pass), with
# variant shaders that each remove one suspect, timed in the same runs (issue 63, section 1).
#
#   bench/pass_variants.sh BUILD [OLD_BUILD] [ROUNDS]
#
# BUILD: the build to time ("new"); OLD_BUILD (optional): a build of a commit before
# fe38b8e (e.g. 22c8bef) whose btf and libraries are timed as "old", with variants of ITS shaders
# given as overrides on OSG_FILE_PATH (core/ShaderSource.h):
#   V1  the views=all path removed from btfEvaluate (front view only)
#   V2  V1, and ptm's luminance branch removed / hsh's loop to the uniform hshTerms made "k < 9"
#   V3  V2, and each coefficient read by textureLod only (not both sides of btfBilinear's select)
#   V4  the original shader with only the select of V3 removed
# and, on BUILD: N (each coefficient read by texelFetch: no bilinear filter, not the same image)
# and L (lambert's select removed the same way). Every run times lambert, ptm and hsh (their
# defaults: rgb, front view, order 3) on a 32 x 32 sample, 15 frames per pass; the fits are made
# once and reused. Prints each run's "- empty" ms and the median per variant. A benchmark: it
# never fails on a time; run it on an idle machine (medians of ROUNDS rounds, default 5).
set -euo pipefail
BUILD=$(cd "${1:?usage: bench/pass_variants.sh BUILD [OLD_BUILD] [ROUNDS]}" && pwd)
OLD=${2:-}
ROUNDS=${3:-5}
[ -n "$OLD" ] && OLD=$(cd "$OLD" && pwd)
SRC=$(cd "$(dirname "$0")/.." && pwd)
WORK=${TMPDIR:-/tmp}/osgbtf-pass-variants
mkdir -p "$WORK"
cd "$WORK"
[ -f sample-32.zip ] || "$BUILD/bin/btf" sample --size 32 -o sample-32.zip >/dev/null

# The variant shaders, from the old build's sources (OLD_SOURCE: the commit it was built from).
if [ -n "$OLD" ]; then
    OLD_SOURCE=${OLD_SOURCE:-22c8bef}
    git -C "$SRC" show "$OLD_SOURCE:materials/ptm/ptm.frag" >ptm-old.frag
    git -C "$SRC" show "$OLD_SOURCE:materials/hsh/hsh.frag" >hsh-old.frag
    python3 - <<'EOF'
import os
ptm, hsh = open('ptm-old.frag').read(), open('hsh-old.frag').read()
def cut(src, start):
    return src[:src.index(start)]
lod_ptm = ('''    return btfBilinear ? textureLod(s, vec3(btfBilinearCoordinate, float(layer)), 0.0).rgb
                       : texelFetch(s, ivec3(texel, layer), 0).rgb;''',
           '''    return textureLod(s, vec3(btfBilinearCoordinate, float(layer)), 0.0).rgb;''')
lod_hsh = ('''    return btfBilinear
               ? textureLod(hshCoefficients, vec3(btfBilinearCoordinate, float(layer)), 0.0).rgb
               : texelFetch(hshCoefficients, ivec3(texel, layer), 0).rgb;''',
           '''    return textureLod(hshCoefficients, vec3(btfBilinearCoordinate, float(layer)), 0.0).rgb;''')
def replaced(src, pair):
    assert pair[0] in src, pair[0][:40]
    return src.replace(*pair)
p1 = cut(ptm, 'vec3 btfEvaluate(') + '''vec3 btfEvaluate(ivec2 texel, vec3 view, vec3 light) {
    return max(ptmField(texel, 0, light.x, light.y), vec3(0.0));
}
'''
h1 = cut(hsh, 'vec3 btfEvaluate(') + '''vec3 btfEvaluate(ivec2 texel, vec3 view, vec3 light) {
    float h[16];
    hshBasis(light, h);
    return max(hshField(texel, 0, h), vec3(0.0));
}
'''
p2 = p1[:p1.index('    if (ptmLuminance != 0) {')] + p1[p1.index('    int layer = 6 * slot;'):]
h2 = replaced(h1, ('for (int k = 0; k < hshTerms; ++k)', 'for (int k = 0; k < 9; ++k)'))
variants = {'V1': (p1, h1), 'V2': (p2, h2),
            'V3': (replaced(p2, lod_ptm), replaced(h2, lod_hsh)),
            'V4': (replaced(ptm, lod_ptm), replaced(hsh, lod_hsh))}
for name, (p, h) in variants.items():
    os.makedirs(name + '/shaders', exist_ok=True)
    open(name + '/shaders/ptm.frag', 'w').write(p)
    open(name + '/shaders/hsh.frag', 'w').write(h)
EOF
fi
# Variants of the new build's shaders.
mkdir -p N/shaders L/shaders
sed 's/#if defined(OSGBTF_PTM_FILTERED) \&\& !defined(OSGBTF_COORDINATE_MAP)/#if 0/' \
    "$SRC/materials/ptm/ptm.frag" >N/shaders/ptm.frag
sed 's/#if defined(OSGBTF_HSH_FILTERED) \&\& !defined(OSGBTF_COORDINATE_MAP)/#if 0/' \
    "$SRC/materials/hsh/hsh.frag" >N/shaders/hsh.frag
python3 - "$SRC/materials/lambert/lambert.frag" <<'EOF'
import sys
s = open(sys.argv[1]).read()
old = '''    vec3 albedo = btfBilinear ? textureLod(lambertAlbedo, btfBilinearCoordinate, 0.0).rgb
                              : texelFetch(lambertAlbedo, texel, 0).rgb;'''
assert old in s
open('L/shaders/lambert.frag', 'w').write(
    s.replace(old, '    vec3 albedo = textureLod(lambertAlbedo, btfBilinearCoordinate, 0.0).rgb;'))
EOF

compare() {  # BTF_DIR [OSG_FILE_PATH]
    env ${2:+OSG_FILE_PATH=$2} LD_LIBRARY_PATH="$1/lib" "$1/bin/btf" compare sample-32.zip \
        --methods ptm,hsh --holdout-fraction 0 --targets rgba8 --frames 15 --out cmp >/dev/null 2>&1
    awk -F'|' '/^## Table 3/{t=1} /^## Fitting/{t=0}
        t && /^\| (lambert|ptm|hsh) \|/ {gsub(/ /,"",$2); printf "%s= %s ", $2, $9}' cmp/report.md
    echo
}
variants="new new-N new-L"
[ -n "$OLD" ] && variants="old old-V1 old-V2 old-V3 old-V4 $variants"
: >runs.log
for r in $(seq 1 "$ROUNDS"); do
    for v in $variants; do
        case $v in
            old) row=$(compare "$OLD") ;;
            old-*) row=$(compare "$OLD" "$WORK/${v#old-}") ;;
            new) row=$(compare "$BUILD") ;;
            new-*) row=$(compare "$BUILD" "$WORK/${v#new-}") ;;
        esac
        echo "round $r $v $row" | tee -a runs.log
    done
done
python3 - runs.log <<'EOF'
import re, statistics as st, sys
rows = {}
for line in open(sys.argv[1]):
    m = re.match(r'round \d+ (\S+) (.*)', line)
    if m:
        rows.setdefault(m.group(1), []).append(
            {k: float(v) for k, v in re.findall(r'(\w+)=\s*([\d.]+)', m.group(2))})
print("| variant | lambert ms | ptm ms | hsh ms | ptm / lambert | hsh / lambert |")
print("|---|---|---|---|---|---|")
for v, rs in rows.items():
    med = lambda k: st.median(r[k] for r in rs)
    ratio = lambda k: st.median(r[k] / r['lambert'] for r in rs)
    print(f"| {v} | {med('lambert'):.2f} | {med('ptm'):.2f} | {med('hsh'):.2f} | "
          f"{ratio('ptm'):.2f} | {ratio('hsh'):.2f} |")
EOF
