"""Glint's cost per frame on the sample scenes, and export time against triangle count.

    /usr/bin/python3 blend_samples/measure_figures.py [--samples DIR] [--sizes 960x540,1920x1080]
                                                      [--scenes mirror_floor,...] [--triangles 10000,1000000]

Needs Blender on PATH, the add-on importable (this checkout's addon/ is put on
Blender's add-on path through a temporary BLENDER_USER_SCRIPTS) and the core
(GLINT_CORE_PATH, default <checkout>/build/python). For each scene and size it
renders frame 1 three ways - Glint off, Glint on with the CPU backend, Glint on
with 'auto' - and reads the times from Blender's log: Blender's own total, the
compositor's span ("Compositing" to "De-initializing"), and Glint's stages
(export, rasterize, trace, images) from its "Glint: frame" line. Then it times
``gather.export_scene`` alone on a grid mesh of each triangle count.
Prints a Markdown table.
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ENGINES = {"mirror_floor": "Eevee", "metals_roughness": "Cycles", "ortho_camera": "Workbench",
           "water_normal_map": "Eevee", "no_reflection": "Eevee", "animated_camera": "Eevee"}

SETUP = """
import bpy, sys, json
cfg = json.loads(sys.argv[sys.argv.index('--') + 1])
s = bpy.context.scene
s.render.resolution_x, s.render.resolution_y = cfg['size']
s.render.resolution_percentage = 100
s.render.filepath = cfg['out']
s.render.image_settings.file_format = 'PNG'
if cfg['glint'] is None:
    s.glint.enabled = False
else:
    s.glint.backend = cfg['glint']
    s.glint.enabled = True
"""

EXPORT_BENCH = """
import bpy, sys, json, time, statistics
import numpy as np
import glint.gather as gather
from glint import native
n = int(sys.argv[sys.argv.index('--') + 1])
s = bpy.context.scene
side = max(1, int(round((n / 2) ** 0.5)))
bpy.ops.mesh.primitive_grid_add(x_subdivisions=side, y_subdivisions=side, size=6, location=(0, 0, 0))
grid = bpy.context.object
grid.data.materials.append(bpy.data.materials['Mirror'])
for ob in list(s.objects):
    if ob.type == 'MESH' and ob != grid:
        bpy.data.objects.remove(ob)
dg = bpy.context.evaluated_depsgraph_get()
times, tris = [], 0
for _ in range(3):
    t0 = time.perf_counter()
    exp = gather.export_scene(dg)
    times.append((time.perf_counter() - t0) * 1000)
    tris = exp.triangles.count
core = native.load()
cam = exp.camera
t = exp.triangles
ras = []
for _ in range(2):
    t0 = time.perf_counter()
    core.rasterize(t.positions, t.normals, t.material_index, exp.materials, cam.projection.astype(np.float32),
                   cam.width, cam.height, backend='cpu')
    ras.append((time.perf_counter() - t0) * 1000)
print('EXPORT' + json.dumps({'triangles': tris, 'export_ms': statistics.median(times), 'rasterize_cpu_ms': min(ras),
                             'size': [cam.width, cam.height]}))
"""


def parse_log(log):
    out = {}
    m = re.findall(r"Time: (\d+):(\d+\.\d+) \(Saving", log)
    if m:
        mm, ss = m[-1]
        out["total_s"] = int(mm) * 60 + float(ss)
    comp = [(int(a) * 60 + float(b), what) for a, b, what in
            re.findall(r"Time:(\d+):(\d+\.\d+) \| Compositing(?: \| ([^\n]*))?", log)]
    if comp:
        out["composite_s"] = comp[-1][0] - comp[0][0]
    g = re.search(r"Glint: frame \d+: [^\n]*", log)
    if g:
        out["glint_line"] = g.group(0)
        stages = re.findall(r"(export|rasterize|trace|images) ([\d.]+) ms", g.group(0))
        out["glint_ms"] = {k: float(v) for k, v in stages}
        b = re.search(r"backend (\w+)", g.group(0))
        out["backend"] = b.group(1) if b else "-"
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--samples", default=os.path.join(ROOT, "blend_samples"))
    ap.add_argument("--sizes", default="960x540,1920x1080")
    ap.add_argument("--scenes", default="mirror_floor,metals_roughness,ortho_camera,no_reflection")
    ap.add_argument("--triangles", default="10000,100000,1000000")
    ap.add_argument("--blender", default=os.environ.get("BLENDER", "blender"))
    args = ap.parse_args()

    home = tempfile.mkdtemp(prefix="glint_figures_")
    os.makedirs(os.path.join(home, "scripts", "addons"))
    os.symlink(os.path.join(ROOT, "addon", "glint"), os.path.join(home, "scripts", "addons", "glint"))
    env = dict(os.environ, BLENDER_USER_SCRIPTS=os.path.join(home, "scripts"))
    env.setdefault("GLINT_CORE_PATH", os.path.join(ROOT, "build", "python"))
    setup = os.path.join(home, "setup.py")
    with open(setup, "w") as f:
        f.write(SETUP)
    bench = os.path.join(home, "bench.py")
    with open(bench, "w") as f:
        f.write(EXPORT_BENCH)

    def blender(argv):
        cmd = [args.blender, "-b", "--factory-startup", "-noaudio"] + argv
        return subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True).stdout

    import json
    print("| scene (engine) | size | render, Glint off | render, Glint on (backend) | export | rasterize | "
          "trace | images | composite (on - off) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for scene in args.scenes.split(","):
        blend = os.path.join(args.samples, scene + ".blend")
        for size in args.sizes.split(","):
            w, h = (int(v) for v in size.split("x"))
            rows = {}
            for label, backend in (("off", None), ("cpu", "CPU"), ("auto", "AUTO")):
                cfg = json.dumps({"size": [w, h], "out": os.path.join(home, "out_"), "glint": backend})
                log = blender([blend, "--addons", "glint", "--python", setup, "-f", "1", "--", cfg])
                rows[label] = parse_log(log)
            off = rows["off"]
            for label in ("cpu", "auto"):
                r = rows[label]
                g = r.get("glint_ms", {})
                comp = r.get("composite_s", 0.0) - off.get("composite_s", 0.0)
                print(f"| {scene} ({ENGINES.get(scene, '?')}) | {w}x{h} | {off.get('total_s', float('nan')):.2f} s | "
                      f"{r.get('total_s', float('nan')):.2f} s ({r.get('backend', '-')}) | "
                      f"{g.get('export', 0):.0f} ms | {g.get('rasterize', 0):.0f} ms | {g.get('trace', 0):.0f} ms | "
                      f"{g.get('images', 0):.0f} ms | {comp * 1000:.0f} ms |", flush=True)
    print()
    print("| triangles | export | rasterize (CPU) | image |")
    print("|---|---|---|---|")
    for n in args.triangles.split(","):
        log = blender([os.path.join(args.samples, "mirror_floor.blend"), "--addons", "glint", "--python", bench,
                       "--", n])
        line = next((l for l in log.splitlines() if l.startswith("EXPORT")), None)
        if line is None:
            print(f"| {n} | failed | | |")
            print(log[-2000:], file=sys.stderr)
            continue
        d = json.loads(line[6:])
        print(f"| {d['triangles']} | {d['export_ms']:.0f} ms | {d['rasterize_cpu_ms']:.0f} ms | "
              f"{d['size'][0]}x{d['size'][1]} |", flush=True)
    shutil.rmtree(home, ignore_errors=True)


if __name__ == "__main__":
    main()
