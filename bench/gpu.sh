#!/bin/bash
# Every GPU benchmark of osgBTF, run from an existing build, tables into one folder.
#
# Usage: bench/gpu.sh [BUILD_DIR] [OUT_DIR]
#   BUILD_DIR  a build folder with bin/btf and bin/btf-examples (default $OSGBTF_BUILD, else
#              ./build); bin/bench_lpca_pass_time and bin/bench_fit_analytic are run when present
#              (-DOSGBTF_BUILD_BENCH=ON).
#   OUT_DIR    where the tables go (default $OSGBTF_BENCH_OUT, else ./gpu-bench); created, files
#              in it replaced. OUT_DIR/tables.md collects every table; OUT_DIR/work/ keeps the
#              inputs, fits and full reports.
# Needs only the build's binaries and the shared libraries they load: no cmake, no sources (the
# shaders are inside libosgBTF). Where the libraries are not installed, point LD_LIBRARY_PATH at
# them, or set OSGBTF_LIBS to that folder (added to LD_LIBRARY_PATH and, with its
# osgPlugins-3.6.5, to OSG_LIBRARY_PATH); on a GPU machine whose NVIDIA EGL vendor is not found by
# default set __EGL_VENDOR_LIBRARY_FILENAMES to the driver's 10_nvidia.json
# (docs/gpu.md). The renderer each run used is in its table.
#
# Sizes (environment; the defaults are for a GPU, small values make a quick llvmpipe run):
#   SIZE=64                texels per side of the sample BTF that `btf compare` fits
#   RESOLUTIONS="1024 2048" viewports of the timed `btf compare` passes
#   LIGHTS="1 8"           light counts of the timed passes and of the scenes
#   TARGETS=rgba8,rgba16f  colour targets of the timed passes
#   FRAMES=20 WARMUP=3     timed and untimed frames per measurement
#   METHODS=all            methods of `btf compare` (lambert is always added)
#   SCENE_SIZE=32 SCENE_METHODS=lambert,laf,slaf,rf,pca,lpca,lpca-revised
#   SCENE_RESOLUTION=1920x1080
#   LPCA_VIEWPORT=1024     viewport of bench_lpca_pass_time
#   BSVTF_ARGS="--width 1280 --height 720"  options of bench_bsvtf (Schwartz et al. 2013,
#                                            Tables 1-2, Fig. 5)
# A step that fails is reported in tables.md and the others still run; the exit status is the
# number of failed steps (0: all ran).
set -u

build=${1:-${OSGBTF_BUILD:-build}}
out=${2:-${OSGBTF_BENCH_OUT:-gpu-bench}}
SIZE=${SIZE:-64}
RESOLUTIONS=${RESOLUTIONS:-"1024 2048"}
LIGHTS=${LIGHTS:-"1 8"}
TARGETS=${TARGETS:-rgba8,rgba16f}
FRAMES=${FRAMES:-20}
WARMUP=${WARMUP:-3}
METHODS=${METHODS:-all}
SCENE_SIZE=${SCENE_SIZE:-32}
SCENE_METHODS=${SCENE_METHODS:-lambert,laf,slaf,rf,pca,lpca,lpca-revised}
SCENE_RESOLUTION=${SCENE_RESOLUTION:-1920x1080}
LPCA_VIEWPORT=${LPCA_VIEWPORT:-1024}

bin="$build/bin"
for tool in btf btf-examples; do
    if [ ! -x "$bin/$tool" ]; then
        echo "gpu.sh: $bin/$tool: not found (give the build folder as the first argument or in" \
            "OSGBTF_BUILD)" >&2
        exit 100
    fi
done
if ! mkdir -p "$out/work"; then
    echo "gpu.sh: $out: cannot create the output folder" >&2
    exit 100
fi
out=$(cd "$out" && pwd)
work="$out/work"

if [ -n "${OSGBTF_LIBS:-}" ]; then
    export LD_LIBRARY_PATH="$OSGBTF_LIBS${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
    export OSG_LIBRARY_PATH="$OSGBTF_LIBS${OSG_LIBRARY_PATH:+:$OSG_LIBRARY_PATH}"
fi
# osgBTF's own plugins (btf-examples writes .osgt through OSG's osgdb_osg, found by OSG itself).
export OSG_LIBRARY_PATH="$build/lib${OSG_LIBRARY_PATH:+:$OSG_LIBRARY_PATH}"

tables="$out/tables.md"
failures=0
{
    echo "# osgBTF GPU benchmarks"
    echo
    echo "$(date -u '+%Y-%m-%d %H:%M UTC') on $(uname -n); build $build; SIZE=$SIZE" \
        "RESOLUTIONS=\"$RESOLUTIONS\" LIGHTS=\"$LIGHTS\" TARGETS=$TARGETS FRAMES=$FRAMES" \
        "WARMUP=$WARMUP SCENE_SIZE=$SCENE_SIZE SCENE_RESOLUTION=$SCENE_RESOLUTION"
    echo
} > "$tables"

# step NAME COMMAND...: runs it, stdout in work/NAME.log, stderr (progress, messages) in
# work/NAME.err; a failure is noted in the tables, not fatal.
step() {
    local name=$1
    shift
    echo "gpu.sh: $name" >&2
    if "$@" > "$work/$name.log" 2> "$work/$name.err"; then
        return 0
    fi
    failures=$((failures + 1))
    {
        echo "## $name: FAILED"
        echo
        echo '```'
        tail -n 20 "$work/$name.log" "$work/$name.err"
        echo '```'
        echo
    } >> "$tables"
    return 1
}

# 1. Pass cost (`btf compare`): every method against the empty pass, per target, per viewport and
#    light count. The first run fits; the others reuse its fits (copied, newer than the input).
# The sample is kept between runs (it depends on SIZE alone), so a second run into the same
# OUT_DIR reuses the fits of the first; delete OUT_DIR/work to start over.
sample="$work/sample-$SIZE.zip"
if [ -f "$sample" ] || step sample "$bin/btf" --no-progress sample --size "$SIZE" -o "$sample"; then
    first=""
    for resolution in $RESOLUTIONS; do
        for lights in $LIGHTS; do
            name="compare-${resolution}-${lights}l"
            dir="$work/$name"
            if [ -n "$first" ] && [ -d "$first/fits" ] && [ "$first" != "$dir" ]; then
                rm -rf "$dir" && mkdir -p "$dir" && cp -p -r "$first/fits" "$dir/"
            fi
            if step "$name" "$bin/btf" --no-progress compare "$sample" --out "$dir" \
                --methods "$METHODS" --resolution "$resolution" --lights "$lights" \
                --frames "$FRAMES" --warmup-frames "$WARMUP" --targets "$TARGETS"; then
                [ -z "$first" ] && first="$dir"
                {
                    echo "## btf compare: ${resolution}x${resolution}, $lights light(s)"
                    echo
                    # The pass-cost table with its explanation, then the error table's rows.
                    sed -n '/^## Table 3/,/^## Fitting/p' "$dir/report.md" | sed '$d' | sed '1d'
                    echo '```'
                    cat "$work/$name.log"
                    echo '```'
                    echo
                } >> "$tables"
            fi
        done
    done
fi

# 2. Frames per second of the example scenes, each method on every object, 1 and 8 lights.
scene_lights=$(echo "$LIGHTS" | tr ' ' ',')
if step scenes "$bin/btf-examples" --no-progress --out "$work/examples" --size "$SCENE_SIZE" \
    --methods "$SCENE_METHODS" --bench-fps --bench-resolution "$SCENE_RESOLUTION" \
    --bench-lights "$scene_lights" --bench-frames "$FRAMES" --bench-warmup "$WARMUP"; then
    {
        echo "## Example scenes (btf-examples --bench-fps)"
        echo
        cat "$work/examples/bench-fps.md"
        echo
    } >> "$tables"
    cp "$work/examples/bench-fps.md" "$work/examples/bench-fps.csv" "$out/"
fi

# 3. Original against revised LPCA per pass (Schneider 2004 Table 1), when the benchmarks were
#    built.
if [ -x "$bin/bench_lpca_pass_time" ]; then
    if step lpca-pass-time "$bin/bench_lpca_pass_time" --size "$SIZE" --frames "$FRAMES" \
        --viewport "$LPCA_VIEWPORT"; then
        {
            echo "## bench_lpca_pass_time (${LPCA_VIEWPORT}x${LPCA_VIEWPORT}, data ${SIZE}x${SIZE})"
            echo
            cat "$work/lpca-pass-time.log"
            echo
        } >> "$tables"
    fi
else
    printf '## bench_lpca_pass_time: not built (-DOSGBTF_BUILD_BENCH=ON)\n\n' >> "$tables"
fi

# 4. One 1024x1024 lambert pass through bench_fit_analytic --gpu (fit time plus the pass).
if [ -x "$bin/bench_fit_analytic" ]; then
    if step fit-analytic-gpu "$bin/bench_fit_analytic" --method lambert --size "$SIZE" --gpu \
        --frames "$FRAMES"; then
        {
            echo "## bench_fit_analytic --method lambert --gpu"
            echo
            cat "$work/fit-analytic-gpu.log"
            echo
        } >> "$tables"
    fi
fi

# 5. fmf at the rank of Schwartz et al. 2013 (C = 100; step 1 times the default C = 32).
if [ -f "$sample" ]; then
    resolution=${RESOLUTIONS%% *}
    name="compare-fmf100-${resolution}-1l"
    if step "$name" "$bin/btf" --no-progress compare "$sample" --out "$work/$name" \
        --methods fmf --set fmf:components=100 --resolution "$resolution" --lights 1 \
        --frames "$FRAMES" --warmup-frames "$WARMUP" --targets "$TARGETS"; then
        {
            echo "## btf compare: fmf with 100 components, ${resolution}x${resolution}, 1 light"
            echo
            sed -n '/^## Table 3/,/^## Fitting/p' "$work/$name/report.md" | sed '$d' | sed '1d'
            echo
        } >> "$tables"
    fi
fi

# 6. BSVTF: GPU memory and frame time for 1, 5, 25 and 100 streamed materials against
#    plain fmf, preprocessing, bytes received against SSIM (Schwartz et al. 2013 Tables 1-2,
#    Fig. 5).
if [ -x "$bin/bench_bsvtf" ]; then
    # shellcheck disable=SC2086  # BSVTF_ARGS is a list of options
    if step bsvtf "$bin/bench_bsvtf" --work "$work/bsvtf" --frames "$FRAMES" \
        ${BSVTF_ARGS:---width 1280 --height 720}; then
        cat "$work/bsvtf.log" >> "$tables"
        echo >> "$tables"
    fi
else
    printf '## bench_bsvtf: not built (-DOSGBTF_BUILD_BENCH=ON)\n\n' >> "$tables"
fi

for f in "$work"/compare-*/report.md; do
    [ -f "$f" ] && cp "$f" "$out/$(basename "$(dirname "$f")").md"
done
echo "gpu.sh: $failures failed step(s); tables in $tables" >&2
cat "$tables"
exit "$failures"
