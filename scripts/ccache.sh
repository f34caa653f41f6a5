# Sourced by setup.sh, test_sanitized.sh and fuzz.sh (with $root set to the
# checkout): build through ccache where it is installed. With the checkout as
# its base dir the paths it hashes are relative, so a fresh clone elsewhere
# (CI's) finds the objects an earlier one made. Sets `launcher` for cmake.
launcher=()
if command -v ccache >/dev/null; then
  export CCACHE_BASEDIR=${CCACHE_BASEDIR:-$root}
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
