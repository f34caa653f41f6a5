#!/usr/bin/env bash
# Build the core and run the tests inside one host chroot (scripts/hosts/host.sh),
# against that Debian's Blender, Python, numpy, Embree and OpenEXR.
#   scripts/hosts/test_host.sh NAME [pytest paths...]
# Default paths: $GLINT_HOST_TESTS, else the add-on and Blender suites and the
# exact march's tests (Embree 4's calls differ from Debian 12's Embree 3). The
# build goes to build/host-NAME in the checkout (kept between runs).
set -uo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
name=${1:?usage: test_host.sh NAME [pytest paths...]}
shift
paths=("$@")
if ((${#paths[@]} == 0)); then read -r -a paths <<<"${GLINT_HOST_TESTS:-tests/addon tests/blender tests/python/test_exact.py tests/python/test_exact_scene.py}"; fi

bash "$here/host.sh" make "$name" >/dev/null || exit 1
# GLINT_TEST_JOBS: pytest-xdist workers, as scripts/test.sh (1: one process).
bash "$here/host.sh" run "$name" env GLINT_TEST_JOBS="${GLINT_TEST_JOBS:-$(nproc)}" bash -c '
  set -o pipefail
  build=/glint/build/host-$GLINT_HOST
  mkdir -p "$build"
  echo "== $GLINT_HOST: $(cat /.glint-blender-version 2>/dev/null), $(python3 --version)"
  cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DGLINT_BUILD_TESTS=OFF \
    -DGLINT_BUILD_BENCHMARKS=OFF -DGLINT_BUILD_TOOLS=OFF >"$build/configure.log" 2>&1 ||
    { cat "$build/configure.log"; echo "== $GLINT_HOST: configure failed"; exit 1; }
  cmake --build "$build" -j"$(nproc)" >"$build/build.log" 2>&1 ||
    { tail -40 "$build/build.log"; echo "== $GLINT_HOST: build failed"; exit 1; }
  xdist=()
  if [[ $GLINT_TEST_JOBS != 1 ]] && python3 -c "import xdist" 2>/dev/null; then xdist=(-n "$GLINT_TEST_JOBS"); fi
  GLINT_BUILD_DIR=$build python3 -m pytest -q -p no:cacheprovider --durations=15 "${xdist[@]}" "$@"
' test_host "${paths[@]}"
