#!/usr/bin/env bash
# The main job on the built-in sample: set up, generate the sample BTF, describe it, write a
# contact sheet of (view, light) images, and compare every compression method on a 32x32 sample
# (btf compare: tables, pictures, recommendation; about 4.5 minutes on 2 cores, half of it the
# two neural fits of 8000 steps, the method's own and the held-out one; measured 2026-12-07).
# Outputs go to out/ (or the folder given as $1).
set -euo pipefail
cd "$(dirname "$0")/.."
OUT="${1:-out}"
# Only the btf tool and what it links (not the tests, examples, viewer and plugins, nor the
# packages only the tests need: the first result in minutes), with the library flags of .ci/run
# (no debug info: -g costs ~20 % of the compile time; a unity build: GCC parses the headers once
# for eight sources), so either script reuses what the other built.
OSGBTF_BUILD_TARGETS=btf OSGBTF_TEST_PACKAGES=0 bash tools/setup.sh -DCMAKE_UNITY_BUILD=ON \
  -DOSGBTF_BUILD_BENCH=OFF -DCMAKE_INSTALL_PREFIX=/usr \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -DNDEBUG" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O2 -DNDEBUG" \
  -DOSGBTF_TEST_OPTIMIZE=-Og
mkdir -p "$OUT"
./build/bin/btf sample -o "$OUT/sample.zip"
./build/bin/btf info "$OUT/sample.zip"
./build/bin/btf contact-sheet "$OUT/sample.zip" -o "$OUT/contact-sheet.png"
./build/bin/btf sample --size 32 -o "$OUT/sample-32.zip"
./build/bin/btf --progress compare "$OUT/sample-32.zip" --methods all --out "$OUT/compare"
echo "== done: $OUT/sample.zip, $OUT/contact-sheet.png; comparison report: $OUT/compare/report.md"
