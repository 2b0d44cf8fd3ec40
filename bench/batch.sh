#!/usr/bin/env bash
# `btf batch` on a generated database, locally: wall time and peak memory per job, jobs per hour,
# and the leaderboard (OUT/index.html, OUT/report.md).
#
# Usage: bench/batch.sh [BUILD_DIR] [OUT] [SIZE] [METHODS] [JOBS]
#   BUILD_DIR (default ./build) holds bin/btf. OUT (default out/leaderboard). SIZE: texels per side
#   of the built-in sample family (default 32). METHODS: btf batch plan --methods (default all).
#   JOBS: jobs at once (default: the number of cores).
# The family: six variants of the built-in sample (btf sample: weave repeats, per-cell variation,
# 8-bit JPEG or PNG members) in three class folders, 81 x 81 Bonn directions each. Set
# UBO2014_SIZE=N (and build with -DOSGBTF_BUILD_BENCH=ON) to add MATERIALS=12 (default) generated
# full-direction UBO2014 DFMF files of N x N texels (bench_make_ubo2014, varied by seed) instead.
# WITH_SLURM=1 runs the same plan again through a local single-node Slurm (tools/slurm-local.sh,
# Debian's slurm-wlm and munge) into OUT-slurm and prints both runs' wall time and peak memory per
# job side by side.
set -eu
build=${1:-build}
out=${2:-out/leaderboard}
size=${3:-32}
methods=${4:-all}
jobs=${5:-$(nproc)}
btf="$build/bin/btf"
db=$(mktemp -d)
trap 'rm -rf "$db"' EXIT
if [ -n "${UBO2014_SIZE:-}" ]; then
    mkdir -p "$db/ubo2014"
    i=1
    while [ "$i" -le "${MATERIALS:-12}" ]; do
        "$build/bin/bench_make_ubo2014" -o "$db/ubo2014/synthetic$(printf %02d "$i").btf" \
            --size "$UBO2014_SIZE" --seed "$i" >/dev/null
        i=$((i + 1))
    done
else
    mkdir -p "$db/fabric" "$db/weave" "$db/tinted"
    "$btf" --no-progress sample -o "$db/fabric/wool01.zip" --size "$size" >/dev/null
    "$btf" --no-progress sample -o "$db/fabric/wool02.zip" --size "$size" --format png >/dev/null
    "$btf" --no-progress sample -o "$db/weave/coarse01.zip" --size "$size" --weave-repeats 1 >/dev/null
    "$btf" --no-progress sample -o "$db/weave/fine02.zip" --size "$size" --weave-repeats 4 >/dev/null
    "$btf" --no-progress sample -o "$db/tinted/tinted01.zip" --size "$size" --variation 0.5 >/dev/null
    "$btf" --no-progress sample -o "$db/tinted/tinted02.zip" --size "$size" --variation 1 >/dev/null
fi
rm -rf "$out"
"$btf" --no-progress batch plan "$db" --out "$out" --methods "$methods"
start=$(date +%s)
"$btf" batch run "$out" --jobs "$jobs" || true  # a failed job is in the report
seconds=$(( $(date +%s) - start ))
"$btf" --no-progress batch report "$out"
count=$(grep -c '"state": "done"' "$out"/jobs/*/result.json | awk -F: '{ s += $2 } END { print s }')
echo "== $count jobs done in $seconds s with $jobs at once: $(( count * 3600 / (seconds > 0 ? seconds : 1) )) jobs per hour"
sed -n '/^## Every job/,$p' "$out/report.md"
if [ "${WITH_SLURM:-0}" = 1 ]; then
    state=$(mktemp -d)
    chmod 0711 "$state"
    trap 'tools/slurm-local.sh stop "$state/s" >/dev/null 2>&1; rm -rf "$db" "$state"' EXIT
    tools/slurm-local.sh start "$state/s" >/dev/null
    # shellcheck disable=SC1091
    . "$state/s/env.sh"
    rm -rf "$out-slurm"
    mkdir -p "$out-slurm"
    cp "$out/manifest.json" "$out-slurm/"
    start=$(date +%s)
    "$btf" --no-progress batch run "$out-slurm" --slurm --wait >/dev/null || true
    slurm_seconds=$(( $(date +%s) - start ))
    "$btf" --no-progress batch report "$out-slurm" >/dev/null
    echo "== through Slurm: $slurm_seconds s (here: $seconds s)"
    echo "job, wall s here, wall s Slurm, peak MiB here, peak MiB Slurm"
    # results.csv: job is column 1, wall_seconds 20, peak_rss_bytes 21.
    join -t, <(cut -d, -f1,20,21 "$out/results.csv" | tail -n +2 | sort) \
        <(cut -d, -f1,20,21 "$out-slurm/results.csv" | tail -n +2 | sort) |
        awk -F, '{ printf "%s, %.1f, %.1f, %.0f, %.0f\n", $1, $2, $4, $3 / 1048576, $5 / 1048576 }'
fi
