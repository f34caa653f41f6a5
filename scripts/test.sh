#!/usr/bin/env bash
# Set up, build and run every test: the C++ tests through ctest, then the
# Python, add-on and Blender tests through Debian's pytest. Exits non-zero
# when anything fails.
set -uo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
export GLINT_BUILD_DIR=${GLINT_BUILD_DIR:-$root/build}
export GLINT_TEST_OUT=${GLINT_TEST_OUT:-$GLINT_BUILD_DIR/test-out}

# The fuzz harnesses need clang and libFuzzer unless they are skipped.
[[ "${GLINT_SKIP_FUZZ:-0}" != 1 ]] && export GLINT_WITH_FUZZERS=1
bash "$root/scripts/setup.sh" || exit 1

# The newer Blenders (scripts/hosts/hosts.conf: Debian 13's 4.3, sid's 5.2),
# each in a chroot of its own, cached outside the checkout. GLINT_HOSTS picks
# which ("trixie", "trixie sid", "none"); GLINT_HOST_TESTS which suites.
# A chroot not yet made is made in the background from here (debootstrap and
# apt wait on the network more than on the CPU) while the C++ tests run;
# test_host.sh waits for it (host.sh holds a lock per host while making one).
hosts=${GLINT_HOSTS:-$(bash "$root/scripts/hosts/host.sh" list | tr '\n' ' ')}
mkdir -p "$GLINT_TEST_OUT"
for h in $hosts; do
  [[ $h == none ]] && continue
  bash "$root/scripts/hosts/host.sh" make "$h" >"$GLINT_TEST_OUT/host-$h.make.log" 2>&1 &
done

status=0
echo "== ctest"
ctest --test-dir "$GLINT_BUILD_DIR" --output-on-failure -j2 || status=1

# The C++ tests again under AddressSanitizer and UBSan (scripts/test_sanitized.sh;
# about 3 minutes from scratch on 2 cores, seconds when ccache has the objects).
# GLINT_SKIP_SANITIZED=1 leaves them out.
if [[ "${GLINT_SKIP_SANITIZED:-0}" != 1 ]]; then
  echo "== ctest, sanitized"
  bash "$root/scripts/test_sanitized.sh" --cpp-only || status=1
fi

# Each libFuzzer harness for a short run from its seed corpus (scripts/fuzz.sh;
# about 20 s each after a build of 2-3 minutes). GLINT_SKIP_FUZZ=1 leaves them out.
if [[ "${GLINT_SKIP_FUZZ:-0}" != 1 ]]; then
  echo "== fuzz"
  bash "$root/scripts/fuzz.sh" "${GLINT_FUZZ_SECONDS:-20}" || status=1
fi

# The Python and Blender tests on every core (pytest-xdist): a Blender test is
# a process of its own that leaves a core idle a third of the time, and the
# 3.4 suite took 7.5 minutes in one process, 4.6 in two.
# GLINT_TEST_JOBS=1 runs each suite in one process.
export GLINT_TEST_JOBS=${GLINT_TEST_JOBS:-$(nproc)}
xdist=()
if [[ $GLINT_TEST_JOBS != 1 ]] && /usr/bin/python3 -c "import xdist" 2>/dev/null; then
  xdist=(-n "$GLINT_TEST_JOBS")
fi

echo "== pytest"
cd "$root"
suites=()
for d in tests/python tests/addon tests/blender; do
  [[ -d $d ]] && suites+=("$d")
done
/usr/bin/python3 -m pytest -q -p no:cacheprovider "${xdist[@]}" "${suites[@]}" || status=1

for h in $hosts; do
  [[ $h == none ]] && continue
  echo "== pytest on host $h"
  bash "$root/scripts/hosts/test_host.sh" "$h" || status=1
done
wait  # a background make that test_host.sh did not need (its host failed earlier)

exit $status
