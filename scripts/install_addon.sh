#!/usr/bin/env bash
# One-line install of the add-on from this checkout:
#   scripts/install_addon.sh            link the checkout (edits are live)
#   scripts/install_addon.sh --package  install the package this Blender takes
# The default symlinks addon/glint into Blender's user add-on folder, which
# every Blender from 3.4 to 5.x loads (4.2+ lists it as a legacy add-on), and
# enables it in the saved preferences; the native module is then found in
# <checkout>/build/python (or $GLINT_CORE_PATH).
# --package builds what scripts/build_addon_zip.sh makes for this Blender and
# installs it the way that Blender installs add-ons: an extension on 4.2 and
# later (`blender --command extension install-file`), the add-on zip before.
#   BLENDER               Blender to use (default: blender)
#   BLENDER_USER_SCRIPTS  user scripts folder (default: ~/.config/blender/<version>/scripts)
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
blender=${BLENDER:-blender}
command -v "$blender" >/dev/null || { echo "install_addon: $blender not found" >&2; exit 1; }

# Enable the add-on (after PRE, Python run first) and save the user's preferences.
enable_and_save() {  # PRE MESSAGE
  "$blender" -b --python-expr "
import bpy, sys
$1
bpy.ops.preferences.addon_enable(module='glint')
if 'glint' not in bpy.context.preferences.addons:
    sys.exit('install_addon: enabling the add-on failed')
bpy.context.preferences.is_dirty = True
bpy.ops.wm.save_userpref()
print('install_addon: $2')
" 2>&1 | grep -E '^install_addon|Error|rror:' || true
}

if [[ ${1:-} == --package ]]; then
  pkg=$(mktemp -d)/glint.zip
  BLENDER=$blender bash "$root/scripts/build_addon_zip.sh" "${GLINT_BUILD_DIR:-$root/build}" "$pkg"
  # What was built decides: an extension carries blender_manifest.toml.
  if "${GLINT_PYTHON:-/usr/bin/python3}" -c "import sys, zipfile
sys.exit(0 if any(n.endswith('blender_manifest.toml') for n in zipfile.ZipFile(sys.argv[1]).namelist()) else 1)" "$pkg"; then
    "$blender" --command extension install-file -r user_default -e "$pkg"
    echo "install_addon: installed and enabled the extension"
  else
    enable_and_save "bpy.ops.preferences.addon_install(filepath='$pkg', overwrite=True)" \
      "installed the add-on zip and enabled it"
  fi
  exit 0
fi
[[ $# -eq 0 ]] || { echo "install_addon: usage: install_addon.sh [--package]" >&2; exit 1; }

version=$("$blender" --version 2>/dev/null | sed -n 's/^Blender \([0-9]*\.[0-9]*\).*/\1/p' | head -n1)
[[ -n $version ]] || { echo "install_addon: cannot tell the Blender version" >&2; exit 1; }
scripts=${BLENDER_USER_SCRIPTS:-$HOME/.config/blender/$version/scripts}
addons="$scripts/addons"
mkdir -p "$addons"
target="$addons/glint"
if [[ -e $target && ! -L $target ]]; then
  echo "install_addon: $target exists and is not a symlink; remove it first" >&2
  exit 1
fi
ln -sfn "$root/addon/glint" "$target"
echo "install_addon: $target -> $root/addon/glint"

# Enable it and save the preferences (the user's own preferences, kept as they are).
enable_and_save "" "enabled in the saved preferences"
[[ -d $root/build/python ]] || echo "install_addon: note: no $root/build/python yet; build with scripts/setup.sh (or set GLINT_CORE_PATH)"
