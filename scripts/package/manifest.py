"""Write the add-on's extension manifest (Blender 4.2+) from its ``bl_info``.

``bl_info`` in addon/glint/__init__.py is the one place the add-on's name,
version and description are written: Blender 3.4 reads it there, and this
script turns it into the ``blender_manifest.toml`` that 4.2 and later read
from an extension package. Plain Python, no bpy:

    /usr/bin/python3 scripts/package/manifest.py addon/glint/__init__.py OUT.toml PLATFORM

PLATFORM is Blender's name for the platform the bundled native module was
built for (linux-x64 here): a package with a compiled module says so, and
Blender refuses it elsewhere.
"""
import ast
import sys

# The first Blender that installs extensions; older ones take the legacy zip.
EXTENSIONS_SINCE = (4, 2, 0)


def bl_info(init_path):
    tree = ast.parse(open(init_path, encoding="utf-8").read(), init_path)
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "bl_info" for t in node.targets):
            return ast.literal_eval(node.value)
    raise SystemExit(f"manifest: no bl_info in {init_path}")


def manifest(info, platform):
    version = ".".join(str(v) for v in info["version"])
    # The legacy "3.4" minimum means nothing to the extension system, which starts at 4.2.
    minimum = ".".join(str(v) for v in max(tuple(info["blender"]), EXTENSIONS_SINCE))
    lines = [
        'schema_version = "1.0.0"',
        'id = "glint"',
        f'version = "{version}"',
        f'name = "{info["name"]}"',
        f'tagline = "{info["description"][:63]}"',
        f'maintainer = "{info["author"]}"',
        'type = "add-on"',
        f'website = "{info["doc_url"]}"',
        'tags = ["Render", "Compositing"]',
        f'blender_version_min = "{minimum}"',
        'license = ["SPDX:GPL-3.0-or-later"]',
        f'platforms = ["{platform}"]',
        "",
        "[permissions]",
        'files = "Writes the reflection layers EXR beside the rendered frames"',
        "",
        "[build]",
        'paths_exclude_pattern = ["__pycache__/", "/.git/", "*.pyc"]',
        "",
    ]
    return "\n".join(lines)


if __name__ == "__main__":
    if len(sys.argv) != 4:
        raise SystemExit(__doc__)
    with open(sys.argv[2], "w", encoding="utf-8") as f:
        f.write(manifest(bl_info(sys.argv[1]), sys.argv[3]))
