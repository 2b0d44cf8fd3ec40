#!/usr/bin/env bash
# Installs osgBTF's Debian 12 dependencies and builds it into build/ (Release with debug info).
# Usage: bash tools/setup.sh [extra cmake arguments]
# OSGBTF_BUILD_TARGETS="t1 t2" builds only those targets (and what they need), not everything;
# OSGBTF_TEST_PACKAGES=0 installs only what building and running needs, not what the tests need.
set -euo pipefail
cd "$(dirname "$0")/.."

PACKAGES=(
  build-essential cmake ninja-build pkg-config ccache  # ccache: rebuilds of unchanged sources
  libopenscenegraph-dev openscenegraph          # OSG 3.6.5 libraries, osgviewer, osgconv
  libopenexr-dev openexr libopenimageio-dev openimageio-tools   # float images, exrheader, oiiotool
  libglm-dev libeigen3-dev libceres-dev libtbb-dev libzip-dev zip unzip
  libembree-dev               # ray-cast environment visibility (libosgBTFEnvironment)
  libtorch-dev                # the neural method's training (libosgBTFFit; ~52 MB to download)
  zlib1g-dev libcurl4-openssl-dev nginx-light  # BSVTF: tile codec, HTTP streaming, serve-tiles.sh
  libgtest-dev libgmock-dev libcli11-dev nlohmann-json3-dev
  libosmesa6-dev libegl-dev libegl-mesa0 libgl1-mesa-dri libgl-dev  # headless OpenGL (llvmpipe)
  pybind11-dev python3-dev python3-numpy   # the Python module osgbtf (python/)
)
# Only the tests need these (about half of what a fresh machine downloads: clang and Chromium are
# the big ones); OSGBTF_TEST_PACKAGES=0 leaves them out (tools/run-sample.sh does).
TEST_PACKAGES=(
  xvfb xauth libglx-mesa0     # X server for the viewer tests and xvfb-run (osgviewer, btfviewer)
  chromium                    # headless browser: the gallery and leaderboard page tests
  slurm-wlm munge             # a real single-node Slurm for `btf batch run --slurm` (tests/slurm/)
  dpkg-dev file               # cpack -G DEB: dpkg-shlibdeps finds the package's dependencies
  clang libclang-rt-14-dev    # CI's sanitizer build and the fuzz targets (libFuzzer, ASan, UBSan)
  python3-pytest python3-matplotlib  # the osgbtf module's tests (python.pytest), its examples
)
if [ "${OSGBTF_TEST_PACKAGES:-1}" != 0 ]; then PACKAGES+=("${TEST_PACKAGES[@]}"); fi
SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO=sudo; fi
missing=()
for p in "${PACKAGES[@]}"; do dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p"); done
if [ ${#missing[@]} -gt 0 ]; then
  echo "== installing ${#missing[@]} Debian packages: ${missing[*]}"
  $SUDO apt-get update
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y --no-install-recommends "${missing[@]}"
fi

# OpenSeadragon, the deep-zoom client the web-layout test opens the written pyramids with
# (tests/viewer/deepzoom_test.cpp): from the npm registry, not vendored; npm from Debian where the
# machine has none (a Node.js from elsewhere brings its own).
if [ "${OSGBTF_TEST_PACKAGES:-1}" != 0 ] && [ ! -f build/web/node_modules/openseadragon/package.json ]; then
  if ! command -v npm >/dev/null; then
    $SUDO apt-get update
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y --no-install-recommends npm
  fi
  mkdir -p build/web
  npm install --no-audit --no-fund --prefix build/web openseadragon@6.1.1
fi

# $PWD, not ".": the path the script was started by, a link included (CMake would resolve "."),
# so that .ci/run can build every clone at one path and ccache reuses the last run's objects.
cmake -S "$PWD" -B "$PWD/build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo "$@"
targets=()
for t in ${OSGBTF_BUILD_TARGETS:-}; do targets+=(--target "$t"); done
cmake --build build -j "$(nproc)" "${targets[@]}"
