#!/usr/bin/env bash
# Regenerates the README's pictures (docs/pictures/) from the built-in sample: the gallery of
# btf-examples (32 x 32 sample; every method side by side on spheres from btf compare, a floor into the distance
# and the shadowed cloth scene), three of its PNGs copied. Needs a build (tools/setup.sh) and a
# headless OpenGL context (EGL, or OSMesa with OSGBTF_HEADLESS=osmesa).
#   tools/readme-pictures.sh [BUILD]     (default: build)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$build/bin/btf-examples" --gallery "$work/gallery" --size 32 \
  --methods lambert,laf,pca,lpca,fmf,ptm,hsh --no-progress
mkdir -p docs/pictures
cp "$work/gallery/compare/pictures/spheres.png" docs/pictures/spheres.png
cp "$work/gallery/pictures/pca-distance.png" docs/pictures/floor.png
cp "$work/gallery/pictures/fmf-shadows.png" docs/pictures/shadows.png
du -ch docs/pictures/*.png | tail -1

# The real capture relit (docs/pictures/relit.png), when CAPTURE=DIR names it (the NeuralRTI
# example capture, 402 x 395, 72 photos and dirs.lp; not in this repository) fitted with rbf (relight's default model) on its
# photos as they are encoded (--decode linear keeps the JPEGs' values), its photos 3 and 48 beside
# osgBTF's image under the same two lights (btf eval, the GPU path).
capture=${CAPTURE:-}
if [ -n "$capture" ] && [ -f "$capture/dirs.lp" ]; then
  "$build/bin/btf" --no-progress fit "$capture" --decode linear -m rbf --no-mipmap \
    -o "$work/relit.btfmat" >/dev/null
  row=()
  for photo in 3 48; do
    line=$(sed -n "$((photo + 1))p" "$capture/dirs.lp")
    name=$(echo "$line" | awk '{print $1}')
    # The light's (theta, phi) in degrees from its x, y, z.
    light=$(echo "$line" | awk '{r = sqrt($2*$2 + $3*$3 + $4*$4); t = atan2(sqrt($2*$2 + $3*$3), $4) * 57.29578;
      p = atan2($3, $2) * 57.29578; if (p < 0) p += 360; printf "%.3f,%.3f", t, p}')
    "$build/bin/btf" eval "$work/relit.btfmat" --light "$light" -o "$work/relit-$photo.png" >/dev/null
    row+=("$capture/$name" "$work/relit-$photo.png")
  done
  oiiotool "${row[@]}" --mosaic:pad=4 4x1 --resize 50% -o docs/pictures/relit.png
fi
