"""Runs inside Blender: applies a test's JSON config to the scene, shared by
driver.py (blender -b) and ui_driver.py (F12 under xvfb-run).

Keys used here: engine, size [w, h], percentage, eevee_samples,
cycles_samples, glint {setting: value} (applied in order, 'enabled' last).
The config's `python` code is run by the drivers themselves, in their own
globals, after this.
"""


def apply(scene, cfg):
    r = scene.render
    if "engine" in cfg:
        engine = cfg["engine"]
        if engine == "BLENDER_EEVEE":  # the tests' name for whatever Eevee this Blender has
            from glint.host import engines
            engine = engines.eevee_id()
        r.engine = engine
    if "size" in cfg:
        r.resolution_x, r.resolution_y = cfg["size"]
    r.resolution_percentage = cfg.get("percentage", 100)
    r.dither_intensity = 0.0
    scene.eevee.taa_render_samples = cfg.get("eevee_samples", 4)
    scene.cycles.samples = cfg.get("cycles_samples", 4)
    scene.cycles.use_denoising = False
    glint_cfg = dict(cfg.get("glint", {}))
    enabled = glint_cfg.pop("enabled", None)
    if hasattr(scene, "glint"):
        for key, value in glint_cfg.items():
            setattr(scene.glint, key, value)
        if enabled is not None:
            scene.glint.enabled = enabled
