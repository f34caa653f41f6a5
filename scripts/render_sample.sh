#!/usr/bin/env bash
# Set up everything (scripts/setup.sh), then render the mirror-floor sample
# scene with Blender and Glint exactly as a farm would: `blender -b scene.blend
# -f 1` with the add-on enabled and its settings read from the .blend.
#   usage: scripts/render_sample.sh [scene.blend] [frame]
#   output: out/<scene>_<frame>.png (and the log beside it)
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
export GLINT_BUILD_DIR=${GLINT_BUILD_DIR:-$root/build}
blend=${1:-$root/blend_samples/mirror_floor.blend}
frame=${2:-1}

bash "$root/scripts/setup.sh"

# A private user-scripts folder whose addons/glint links to this checkout, so
# the user's own Blender set-up is neither needed nor touched.
scripts="$GLINT_BUILD_DIR/blender-user/scripts"
mkdir -p "$scripts/addons"
ln -sfn "$root/addon/glint" "$scripts/addons/glint"

name=$(basename "$blend" .blend)
out="$root/out"
mkdir -p "$out"
BLENDER_USER_SCRIPTS="$scripts" GLINT_CORE_PATH="$GLINT_BUILD_DIR/python" \
  blender -b --factory-startup -noaudio "$blend" --addons glint \
  -o "$out/${name}_####" -F PNG -f "$frame" 2>&1 | tee "$out/${name}.log" | grep -E "^Glint|Saved:|Error" || true

image=$(printf "%s/%s_%04d.png" "$out" "$name" "$frame")
[[ -f $image ]] || { echo "render_sample: no image was written; see $out/$name.log" >&2; exit 1; }
grep -q "^Glint: .*reflections" "$out/$name.log" || echo "render_sample: note: the log has no Glint line; see $out/$name.log" >&2
echo "render_sample: wrote $image"
