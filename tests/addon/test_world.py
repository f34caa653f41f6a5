"""Which worlds let S (the engine's specular that a found reflection replaces)
come from the world's colour instead of Eevee's passes (logic/world.py)."""
import pytest

from glint_addon_helpers import load_logic

world = load_logic("world")


def background(color=(0.2, 0.4, 0.8, 1.0), strength=1.0, kind="ShaderNodeBackground"):
    return {"use_nodes": True, "surface": {"kind": kind, "color": color, "strength": strength}}


def test_no_world_is_black():
    assert world.specular_source(None) == (world.SOURCE_WORLD, (0.0, 0.0, 0.0))


def test_world_without_nodes_is_its_colour():
    assert world.specular_source({"use_nodes": False, "color": (0.05, 0.05, 0.05)}) == \
        (world.SOURCE_WORLD, (0.05, 0.05, 0.05))


def test_background_colour_times_strength():
    source, rgb = world.specular_source(background((0.2, 0.4, 0.8, 1.0), 2.5))
    assert source == world.SOURCE_WORLD
    assert rgb == pytest.approx((0.5, 1.0, 2.0))


def test_unlinked_surface_is_black():
    assert world.specular_source({"use_nodes": True, "surface": None}) == (world.SOURCE_WORLD, (0.0, 0.0, 0.0))


@pytest.mark.parametrize("surface", [
    background(color=None),                       # an environment texture or sky into Color
    background(strength=None),                    # a light path trick into Strength
    background(kind="ShaderNodeMixShader"),       # a mix of two backgrounds
    background(kind="ShaderNodeEmission"),
])
def test_anything_linked_needs_the_passes(surface):
    assert world.specular_source(surface) == (world.SOURCE_PASSES, None)


def test_eevee_ssr_needs_the_passes_even_under_a_uniform_world():
    # its reflections stand in the frame where the world's specular would be
    assert world.specular_source(None, engine_ssr=True) == (world.SOURCE_PASSES, None)
    assert world.specular_source(background(), engine_ssr=True) == (world.SOURCE_PASSES, None)


def test_bad_description_names_the_argument():
    with pytest.raises(ValueError, match="world"):
        world.specular_source("sky")
    with pytest.raises(ValueError, match="color"):
        world.specular_source({"use_nodes": False, "color": (1.0, 2.0)})
