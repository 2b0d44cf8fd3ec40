# Sourced by the UBO2014 benchmarks: checks that BUILD_DIR has the tools they run and makes the
# synthetic full-size input once (bench_make_ubo2014: DFMF, colour model 11, 151 x 151 Dome-1
# directions, half scalars), cached in $TMPDIR (default /tmp).
# Usage: ubo2014_input BUILD_DIR SIZE COMPONENTS TOOL...   sets $file.
ubo2014_input() {
    _build=$1 _size=$2 _components=$3
    shift 3
    for _tool in bench_make_ubo2014 "$@"; do
        if [ ! -x "$_build/bin/$_tool" ]; then
            echo "missing $_build/bin/$_tool; build with -DOSGBTF_BUILD_BENCH=ON" >&2
            exit 1
        fi
    done
    file="${TMPDIR:-/tmp}/osgbtf-bench-ubo2014-$_size-k$_components.btf"
    if [ ! -f "$file" ]; then
        "$_build/bin/bench_make_ubo2014" -o "$file" --size "$_size" --components "$_components"
    fi
}
