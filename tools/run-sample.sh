#!/usr/bin/env bash
# The main job on the built-in sample: set up, generate the sample BTF, describe it, and write a
# contact sheet of (view, light) images. Outputs go to out/ (or the folder given as $1).
set -euo pipefail
cd "$(dirname "$0")/.."
OUT="${1:-out}"
bash tools/setup.sh
mkdir -p "$OUT"
./build/bin/btf sample -o "$OUT/sample.zip"
./build/bin/btf info "$OUT/sample.zip"
./build/bin/btf contact-sheet "$OUT/sample.zip" -o "$OUT/contact-sheet.png"
echo "== done: $OUT/sample.zip, $OUT/contact-sheet.png"
