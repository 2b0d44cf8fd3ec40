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
