#!/usr/bin/env bash
# Make the installable add-on zip (Blender: Preferences > Add-ons > Install...):
#   glint/            the add-on package from addon/glint
#   glint/native/     glint_core*.so and libglint.so from the build, found there first
# Usage: scripts/build_addon_zip.sh [build-dir] [out.zip]
#   build-dir  default: $GLINT_BUILD_DIR or <checkout>/build
#   out.zip    default: <build-dir>/glint-addon.zip
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${1:-${GLINT_BUILD_DIR:-$root/build}}
out=${2:-$build/glint-addon.zip}
python=${GLINT_PYTHON:-/usr/bin/python3}

shopt -s nullglob
modules=("$build"/python/glint_core*.so)
libs=("$build"/python/libglint.so*)
if ((${#modules[@]} == 0)); then
  echo "build_addon_zip: no glint_core*.so in $build/python; build first (scripts/setup.sh)" >&2
  exit 1
fi
if ((${#libs[@]} == 0)); then
  echo "build_addon_zip: no libglint.so in $build/python" >&2
  exit 1
fi

stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT
mkdir -p "$stage/glint/native"
# The package without caches; symlinks resolved so the zip holds real files.
(cd "$root/addon" && find glint -name '__pycache__' -prune -o -type f -name '*.py' -print) |
  while read -r f; do
    mkdir -p "$stage/$(dirname "$f")"
    cp -L "$root/addon/$f" "$stage/$f"
  done
cp -L "${modules[@]}" "${libs[@]}" "$stage/glint/native/"
mkdir -p "$(dirname "$out")"
rm -f "$out"
"$python" - "$stage" "$out" <<'PY'
import os, sys, zipfile
stage, out = sys.argv[1], os.path.abspath(sys.argv[2])
with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as z:
    for base, _, files in os.walk(stage):
        for name in sorted(files):
            path = os.path.join(base, name)
            info = zipfile.ZipInfo.from_file(path, os.path.relpath(path, stage))
            info.compress_type = zipfile.ZIP_DEFLATED
            with open(path, "rb") as f:
                z.writestr(info, f.read())  # keeps the mode bits of the .so files
PY
echo "build_addon_zip: wrote $out"
