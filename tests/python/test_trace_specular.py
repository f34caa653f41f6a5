"""trace(..., specular=): pixels that do not reflect are not traced, and the
surfaces they show keep their normals for the rays that hit them.

The add-on used to zero the normals of non-reflective pixels to skip them; a
diffuse object's texels then had no plane and every hit on them was located
only to its texel (the hiz march's confidence 0.5), halving its reflections."""
import numpy as np
import pytest

import analytic as A
import glint_core


@pytest.fixture(scope="module")
def floor():
    # A mirror floor under diffuse objects (RED, GREEN, BLUE reflect nothing).
    gb = A.render(A.mirror_floor_scene(), 160, 120)
    return gb, A.mirror_hits(A.mirror_floor_scene(), gb, 15.0, incident="view")


@pytest.mark.parametrize("backend", ["cpu", "gl"])
def test_skipped_pixels_report_nothing_and_hits_stay_certain(floor, backend, request):
    if backend == "gl":
        request.getfixturevalue("gl")
    gb, exact = floor
    # One ray per pixel: antialiased outlines look at the neighbours' surfaces, which
    # without the specular buffer include the ones that do not reflect.
    kw = dict(glint_core.presets()["balanced"], backend=backend, antialias=0)
    spec = gb["specular"]
    reflective = spec[..., :3].mean(-1) > 0
    uv = glint_core.trace(gb["position"], gb["normal"], gb["projection"].astype(np.float32), specular=spec, **kw)
    assert not uv[~reflective].any(), "a pixel that does not reflect was traced"
    full = glint_core.trace(gb["position"], gb["normal"], gb["projection"].astype(np.float32), **kw)
    assert np.array_equal(uv[reflective], full[reflective]), "skipping changed a traced pixel"
    # Hits inside the objects' images (away from outlines and the screen's edge) are
    # located on their texel's plane: full confidence.
    hit = (uv[..., 2] > 0) & exact["visible"]
    h, w = hit.shape
    inner = np.zeros_like(hit)
    inner[12:-12, 12:-12] = True
    assert (uv[hit & inner, 2] == 1.0).mean() > 0.9
    zeroed = np.where(reflective[..., None], gb["normal"], 0).astype(np.float32)
    old = glint_core.trace(gb["position"], zeroed, gb["projection"].astype(np.float32), **kw)
    assert (old[hit & inner, 2] == 1.0).mean() < 0.5  # what the add-on did before


def test_specular_of_another_size_is_named(floor):
    gb, _ = floor
    with pytest.raises(ValueError, match="specular"):
        glint_core.trace(gb["position"], gb["normal"], gb["projection"].astype(np.float32),
                         specular=gb["specular"][:-1])
