#!/usr/bin/env bash
# Make the installable add-on package for the Blender at hand:
#   glint/            the add-on package from addon/glint
#   glint/native/     glint_core*.so and libglint.so from the build, found there first
# On Blender 4.2 and later an extension (blender_manifest.toml written from
# bl_info by scripts/package/manifest.py, packed by Blender's own
# `blender --command extension build`): Preferences > Get Extensions >
# Install from Disk, or `blender --command extension install-file -r user_default -e PKG`.
# On older Blenders the legacy add-on zip: Preferences > Add-ons > Install.
# The native module is the one built for that Blender's Python (the build dir).
# Usage: scripts/build_addon_zip.sh [build-dir] [out.zip]
#   build-dir  default: $GLINT_BUILD_DIR or <checkout>/build
#   out.zip    default: <build-dir>/glint-addon.zip
#   GLINT_PACKAGE  extension | legacy | auto (default: what $BLENDER offers)
#   BLENDER        the Blender to package for (default: blender)
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${1:-${GLINT_BUILD_DIR:-$root/build}}
out=${2:-$build/glint-addon.zip}
python=${GLINT_PYTHON:-/usr/bin/python3}
blender=${BLENDER:-blender}
kind=${GLINT_PACKAGE:-auto}
if [[ $kind == auto ]]; then
  # A feature test, not a version number: does this Blender build extensions?
  # (Before 4.2 `--command` is an unknown argument and `--help` prints Blender's
  # own usage with status 0, so the test is the extension builder's own option.)
  if "$blender" --command extension build --help 2>/dev/null | grep -q -- "--source-dir"; then
    kind=extension
  else
    kind=legacy
  fi
fi
[[ $kind == extension || $kind == legacy ]] || { echo "build_addon_zip: GLINT_PACKAGE=$kind: expected extension, legacy or auto" >&2; exit 1; }

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
out=$(cd "$(dirname "$out")" && pwd)/$(basename "$out")
if [[ $kind == extension ]]; then
  "$python" "$root/scripts/package/manifest.py" "$stage/glint/__init__.py" "$stage/glint/blender_manifest.toml" linux-x64
  "$blender" --command extension build --source-dir "$stage/glint" --output-filepath "$out" >"$stage/build.log" 2>&1 ||
    { cat "$stage/build.log" >&2; echo "build_addon_zip: blender could not build the extension" >&2; exit 1; }
  echo "build_addon_zip: wrote $out (extension)"
  exit 0
fi
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
echo "build_addon_zip: wrote $out (legacy add-on zip)"
