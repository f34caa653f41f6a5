#!/usr/bin/env bash
# Set up everything Glint needs on Debian 12 and build it. Idempotent: packages
# already installed are not touched, and the build is incremental.
#   GLINT_BUILD_DIR  build directory (default: <checkout>/build)
#   GLINT_NO_APT=1   skip the package step (e.g. no root)
#   GLINT_WITH_FUZZERS=1  also install clang and libFuzzer for fuzz/ (scripts/test.sh sets it)
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${GLINT_BUILD_DIR:-$root/build}

packages=(
  build-essential cmake ninja-build pkg-config zlib1g-dev
  python3-dev python3-numpy python3-pytest python3-pytest-xdist pybind11-dev
  libglm-dev libopenexr-dev libembree-dev
  libegl-dev libegl-mesa0 libgl1-mesa-dri libgl-dev
  googletest libgtest-dev libbenchmark-dev
  blender xvfb xauth python3-matplotlib ccache
)
# Only where the libFuzzer harnesses are built (scripts/fuzz.sh).
if [[ "${GLINT_WITH_FUZZERS:-0}" == 1 ]]; then packages+=(clang-14 libfuzzer-14-dev); fi

if [[ "${GLINT_NO_APT:-0}" != 1 ]]; then
  missing=()
  for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if ((${#missing[@]})); then
    echo "glint setup: installing ${missing[*]}"
    sudo_cmd=()
    [[ $(id -u) -ne 0 ]] && sudo_cmd=(sudo)
    "${sudo_cmd[@]}" apt-get update -qq
    DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
  fi
fi

# ccache keeps the compiled objects between builds and between checkouts.
source "$root/scripts/ccache.sh"
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release "${launcher[@]}" >/dev/null
cmake --build "$build" -j"$(nproc)"
echo "glint setup: built in $build (python module: $build/python)"
