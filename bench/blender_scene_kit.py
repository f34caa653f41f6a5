"""What the scripts that build scenes inside Blender share (bench/frame_bench.py,
bench/look_compare.py, blend_samples/make_samples.py): their options after Blender's "--", registering the
add-on from a folder, and a Principled material from a few values. Importable
only under Blender (bpy)."""
from __future__ import annotations

import os
import sys

import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def script_options(defaults, parse):
    """``--key value`` pairs after Blender's ``--`` over ``defaults``; each value
    goes through ``parse[key]`` (as it is when absent), which raises ValueError
    naming what was wrong."""
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    opts = dict(defaults)
    for i in range(0, len(argv), 2):
        key, value = argv[i].lstrip("-"), argv[i + 1] if i + 1 < len(argv) else None
        if value is None or key not in opts:
            raise ValueError(f"{argv[i]}: expected one of --{', --'.join(opts)} with a value")
        opts[key] = parse.get(key, str)(value)
    return opts


def frame_size(value):
    """'WxH' -> (W, H)."""
    w, h = value.lower().split("x")
    return int(w), int(h)


def names_among(choices, key):
    """A parser for ``--key a,b``: the names, each one of ``choices`` (ValueError
    listing them otherwise)."""
    def parse(value):
        names = [v.strip() for v in value.split(",") if v.strip()]
        if not names or any(n not in choices for n in names):
            raise ValueError(f"--{key} {value}: choose among {','.join(choices)}")
        return names
    return parse


def register_addon(parent):
    """Register glint/ from ``parent``; the core comes from GLINT_CORE_PATH
    (default: <checkout>/build/python)."""
    os.environ.setdefault("GLINT_CORE_PATH", os.path.join(ROOT, "build", "python"))
    sys.path.insert(0, parent)
    import glint
    glint.register()
    return glint


def use_eevee(scene, own_reflections=False):
    """Render ``scene`` with this Blender's Eevee (Legacy or Next, host layer),
    with or without Eevee's own reflections (SSR or ray tracing)."""
    from glint.host import engines
    scene.render.engine = engines.eevee_id()
    engines.set_eevee_traces_reflections_for_comparison(scene, own_reflections)


def eevee_reflections_name(scene):
    from glint.host import engines
    return engines.eevee_reflections_name(scene)


def default_material(name):
    """A material as Blender makes a new one: Principled defaults (grey, Specular
    0.5, Roughness 0.5), a rough dielectric reflector."""
    from glint.host import data
    mat = bpy.data.materials.new(name)
    data.enable_nodes(mat)
    return mat


def principled(name, colour, roughness=0.5, specular=0.5, metallic=0.0):
    """A Principled material; Specular 0 on a dielectric means "not reflective" to Glint.
    The viewport's colour, metallic and roughness follow (Workbench's material colour)."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    p = mat.node_tree.nodes["Principled BSDF"]
    p.inputs["Base Color"].default_value = (*colour, 1.0)
    p.inputs["Roughness"].default_value = roughness
    p.inputs["Metallic"].default_value = metallic
    if "Specular" in p.inputs:  # 3.x
        p.inputs["Specular"].default_value = specular
    else:  # 4.x: the same F0 through "Specular IOR Level" at IOR 1.5
        p.inputs["Specular IOR Level"].default_value = specular
    mat.diffuse_color = (*colour, 1.0)
    mat.metallic = metallic
    mat.roughness = roughness
    return mat
