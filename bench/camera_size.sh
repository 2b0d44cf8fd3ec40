#!/usr/bin/env bash
# Captures at camera size: the shared RTI capture (../shared/data/rti-icon or RTI_CAPTURE, 402 x
# 395 pixels, 72 photos) tiled C x R into camera-size photos (generated here with oiiotool, cached
# in $TMPDIR, never committed), then per size: `btf info`, `btf fit` of each method and its
# output, each under /usr/bin/time -v (wall time, peak resident memory).
# Usage: bench/camera_size.sh [BUILD] [TILINGS] [METHODS]
#   TILINGS: "10x8 13x12 18x17" (12.7, 24.8 and 48.6 megapixels); METHODS: "lambert ptm hsh pca
#   fmf neural". Extra `btf fit` options in FIT_OPTIONS (e.g. "--no-mip-map"). Prints a markdown
#   table; a fit that is refused shows its first error line instead of figures.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
tilings=${2:-10x8 13x12 18x17}
methods=${3:-lambert ptm hsh pca fmf neural}
capture=${RTI_CAPTURE:-$PWD/../shared/data/rti-icon}
[ -f "$capture/dirs.lp" ] || { echo "no RTI capture at $capture (set RTI_CAPTURE)" >&2; exit 1; }
btf=$build/bin/btf
work=${TMPDIR:-/tmp}/osgbtf-camera-size
mkdir -p "$work"

# One tiled copy of every photo, made in parallel; the light file is the same.
make_capture() {
  local tiling=$1 dir=$work/$1
  [ -f "$dir/dirs.lp" ] && return
  mkdir -p "$dir.part"
  local columns=${tiling%x*} rows=${tiling#*x}
  local copies=$((columns * rows - 1))
  ls "$capture"/*.jpg | xargs -P "$(nproc)" -I{} sh -c \
    "oiiotool '{}' $(printf -- '--dup %.0s' $(seq $copies)) --mosaic $tiling -o:quality=95 \
     '$dir.part/'\$(basename '{}')"
  cp "$capture/dirs.lp" "$dir.part/"
  mv "$dir.part" "$dir"
}

# "wall_s peak_MiB" of a command (its output in $2), or "refused: first error line".
measure() {
  local log=$1
  shift
  if /usr/bin/time -v "$@" >"$log" 2>&1; then
    local wall peak
    wall=$(grep 'Elapsed (wall clock)' "$log" | awk '{print $NF}' |
      awk -F: '{ if (NF == 3) print $1 * 3600 + $2 * 60 + $3; else print $1 * 60 + $2 }')
    peak=$(grep 'Maximum resident' "$log" | awk '{printf "%.0f", $NF / 1024}')
    echo "$wall $peak"
  else
    echo "refused: $(grep -m1 -v '^\s*$' "$log" | grep -v 'Command' | head -c 200)"
  fi
}

echo "| capture | step | wall s | peak RSS MiB | output |"
echo "|---|---|---|---|---|"
for tiling in $tilings; do
  make_capture "$tiling"
  dir=$work/$tiling
  size=$(oiiotool --info "$dir/image01.jpg" | grep -o '[0-9]* x [0-9]*' | head -1)
  label="$tiling ($size, 72 photos)"
  read -r wall peak < <(measure "$work/info.log" "$btf" --no-progress info "$dir" || true) || true
  echo "| $label | btf info | $wall | $peak | |"
  for method in $methods; do
    out=$work/$tiling-$method.btfmat
    rm -f "$out"
    # shellcheck disable=SC2086
    result=$(measure "$work/fit-$method.log" "$btf" --no-progress fit "$dir" -m "$method" -o "$out" \
      ${FIT_OPTIONS:-})
    if [[ $result == refused:* ]]; then
      echo "| $label | fit $method | | | ${result#refused: } |"
    else
      read -r wall peak <<<"$result"
      echo "| $label | fit $method | $wall | $peak | $(du -m "$out" | cut -f1) MiB |"
    fi
    rm -f "$out"
  done
done
