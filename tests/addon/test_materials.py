"""The material -> specular buffer rule, against hand-computed values."""
import pytest

from glint_addon_helpers import load_logic

m = load_logic("materials")


def test_hardness_511_maps_through_127_75_to_one():
    assert m.shininess_from_hardness(511) == 127.75
    assert m.alpha_from_shininess(127.75) == 1.0
    assert m.alpha_from_shininess(m.shininess_from_hardness(511)) == 1.0


@pytest.mark.parametrize("hardness,shininess", [(1, 0.25), (50, 12.5), (255.5, 63.875), (0, 0.25),
                                                (-5, 0.25), (1000, 127.75), (float("nan"), 0.25)])
def test_hardness_is_clamped_to_blender_internal_range(hardness, shininess):
    assert m.shininess_from_hardness(hardness) == pytest.approx(shininess)


def test_alpha_of_hardness_1_is_1_over_511():
    assert m.alpha_from_shininess(m.shininess_from_hardness(1)) == pytest.approx(1 / 511)


@pytest.mark.parametrize("roughness,hardness", [
    (0.0, float("inf")),  # a mirror
    (0.01, float("inf")),  # alpha 1e-4, below MIRROR_GGX_ALPHA: a mirror
    (0.1, 2 / 0.01 ** 2 - 2),  # 19998: the gloss range
    (0.2, 2 / 0.04 ** 2 - 2),  # 1248: past Blender Internal's 511
    (0.3, 2 / 0.09 ** 2 - 2),  # 244.91...
    (0.5, 30.0),  # alpha 0.25: 2 / 0.0625 - 2
    (0.8, 2 / 0.64 ** 2 - 2),  # 2.8828...
    (1.0, 1.0),  # 0, clamped to the minimum
])
def test_hardness_from_roughness_is_walters_blinn_phong_equivalence(roughness, hardness):
    assert m.hardness_from_roughness(roughness) == pytest.approx(hardness, rel=1e-12)


def test_hardness_from_roughness_is_monotonic():
    values = [m.hardness_from_roughness(r / 100) for r in range(101)]
    assert all(a >= b for a, b in zip(values, values[1:]))


def principled_34(**kw):
    inputs = {"Base Color": (0.8, 0.8, 0.8, 1.0), "Metallic": 0.0, "Specular": 0.5, "Specular Tint": 0.0,
              "Roughness": 0.5, "IOR": 1.45}
    inputs.update(kw)
    return inputs


def principled_4x(**kw):
    inputs = {"Base Color": (0.8, 0.8, 0.8, 1.0), "Metallic": 0.0, "Roughness": 0.5, "IOR": 1.5,
              "Specular IOR Level": 0.5, "Specular Tint": (1.0, 1.0, 1.0, 1.0)}
    inputs.update(kw)
    return inputs


def test_principled_34_default_is_f0_004():
    s = m.principled_specular(principled_34())
    assert s.color == pytest.approx((0.04, 0.04, 0.04))
    assert s.shininess == pytest.approx(30.0 / 4)


def test_principled_34_metal_reflects_base_colour():
    s = m.principled_specular(principled_34(**{"Base Color": (0.9, 0.5, 0.2, 1.0), "Metallic": 1.0,
                                               "Roughness": 0.0}))
    assert s.color == pytest.approx((0.9, 0.5, 0.2))
    assert s.shininess == 127.75
    assert s.alpha == 1.0


def test_principled_34_half_metal_mixes():
    s = m.principled_specular(principled_34(**{"Base Color": (1.0, 0.0, 0.0, 1.0), "Metallic": 0.5,
                                               "Specular": 1.0}))
    # dielectric F0 0.08 (Specular 1), metal F0 = base, half way
    assert s.color == pytest.approx((0.54, 0.04, 0.04))


def test_principled_34_specular_tint_uses_unit_luminance_base():
    s = m.principled_specular(principled_34(**{"Base Color": (0.8, 0.2, 0.2, 1.0), "Specular Tint": 1.0}))
    lum = 0.2126 * 0.8 + 0.7152 * 0.2 + 0.0722 * 0.2
    assert s.color == pytest.approx((0.04 * 0.8 / lum, 0.04 * 0.2 / lum, 0.04 * 0.2 / lum))


def test_principled_34_specular_zero_is_not_reflective():
    s = m.principled_specular(principled_34(Specular=0.0))
    assert s.amount == 0.0


def test_principled_4x_default_matches_34_default():
    s = m.principled_specular(principled_4x())
    assert s.color == pytest.approx((0.04, 0.04, 0.04))  # ((1.5 - 1) / 2.5)^2 * 2 * 0.5
    assert s.shininess == pytest.approx(7.5)


def test_principled_4x_ior_and_level_and_tint():
    s = m.principled_specular(principled_4x(IOR=1.33, **{"Specular IOR Level": 1.0,
                                                         "Specular Tint": (1.0, 0.5, 0.0, 1.0)}))
    f0 = (0.33 / 2.33) ** 2 * 2.0
    assert s.color == pytest.approx((f0, f0 * 0.5, 0.0))


def test_principled_4x_metal():
    s = m.principled_specular(principled_4x(Metallic=1.0, Roughness=0.0,
                                            **{"Base Color": (0.95, 0.64, 0.54, 1.0)}))
    assert s.color == pytest.approx((0.95, 0.64, 0.54))
    assert s.alpha == 1.0


def test_principled_34_rejects_colour_tint():
    with pytest.raises(ValueError, match="Specular Tint"):
        m.principled_specular(principled_34(**{"Specular Tint": (1.0, 1.0, 1.0, 1.0)}))


def test_colour_is_clamped_to_unit_range():
    s = m.principled_specular(principled_34(Metallic=1.0, **{"Base Color": (5.0, -1.0, 0.5, 1.0)}))
    assert s.color == pytest.approx((1.0, 0.0, 0.5))


def test_custom_hardness_overrides_shininess_not_colour():
    desc = {"kind": "principled", "inputs": principled_34(Roughness=1.0)}
    s = m.material_spec(desc, hardness=511)
    assert s.shininess == 127.75 and s.alpha == 1.0
    assert s.color == pytest.approx((0.04, 0.04, 0.04))
    assert m.material_spec(desc, hardness=255).alpha == pytest.approx(255 / 511)


def test_viewport_values_without_nodes():
    s = m.material_spec({"kind": "viewport", "specular_color": (1.0, 1.0, 1.0), "specular_intensity": 0.5,
                         "roughness": 0.4, "metallic": 0.0, "diffuse_color": (0.8, 0.8, 0.8, 1.0)})
    assert s.color == pytest.approx((0.04, 0.04, 0.04))
    assert s.shininess == pytest.approx((2 / 0.16 ** 2 - 2) / 4)
    metal = m.material_spec({"kind": "viewport", "specular_color": (1, 1, 1), "specular_intensity": 0.5,
                             "roughness": 0.0, "metallic": 1.0, "diffuse_color": (0.2, 0.4, 0.6, 1.0)})
    assert metal.color == pytest.approx((0.2, 0.4, 0.6))


def test_other_shaders():
    assert m.evaluate_shader({"kind": "none"}).amount == 0.0
    assert m.evaluate_shader(None).amount == 0.0
    g = m.evaluate_shader({"kind": "glossy", "color": (1.0, 0.5, 0.25, 1.0), "roughness": 0.0})
    assert g.color == pytest.approx((1.0, 0.5, 0.25)) and g.alpha == 1.0
    glass = m.evaluate_shader({"kind": "glass", "ior": 1.5, "roughness": 0.0})
    assert glass.color == pytest.approx((0.04, 0.04, 0.04))
    with pytest.raises(ValueError):
        m.evaluate_shader({"kind": "mystery"})


def test_mix_and_add_shaders():
    mirror = {"kind": "glossy", "color": (1.0, 1.0, 1.0), "roughness": 0.0}
    rough = {"kind": "glossy", "color": (1.0, 1.0, 1.0), "roughness": 1.0}
    mix = m.evaluate_shader({"kind": "mix", "fac": 0.25, "a": mirror, "b": {"kind": "none"}})
    assert mix.color == pytest.approx((0.75, 0.75, 0.75))
    assert mix.shininess == 127.75  # only the mirror reflects
    half = m.evaluate_shader({"kind": "mix", "fac": 0.5, "a": mirror, "b": rough})
    # amount-weighted GGX widths: the mirror's 0 and hardness 1's sqrt(2 / 3)
    width = (2 / 3) ** 0.5 / 2
    assert half.shininess == pytest.approx((2 / width ** 2 - 2) / 4)
    add = m.evaluate_shader({"kind": "add", "a": mirror, "b": mirror})
    assert add.color == pytest.approx((1.0, 1.0, 1.0))  # clamped


def test_row_layout_is_rgb_then_shininess():
    s = m.SpecularSpec((0.1, 0.2, 0.3), 12.0)
    assert s.row() == (0.1, 0.2, 0.3, 12.0)
    assert s.amount == pytest.approx(0.2)


def test_roughness_survives_the_round_trip_through_the_core(core):
    """The add-on writes shininess from Blender's roughness; the core reads a GGX
    alpha back from the specular buffer's alpha. Above the hardness-1 clamp
    (roughness ~0.90) and the mirror (roughness ~0.016) that alpha must be
    Blender's own, roughness squared: in the book's range (hardness 1..511) and in
    the gloss range past it alike."""
    for r in [0.02 + k * (0.90 - 0.02) / 88 for k in range(89)]:
        shininess = m.shininess_from_roughness(r)
        alpha = core.ggx_alpha(core.shininess_to_alpha(shininess))
        assert alpha == pytest.approx(r * r, rel=1e-5), r  # float32 in the core
        assert m.ggx_alpha_from_shininess(shininess) == pytest.approx(r * r, rel=1e-9), r
    # Roughness 0.2 is glossy now, not a mirror (issue 22's gloss).
    assert core.ggx_alpha(core.shininess_to_alpha(m.shininess_from_roughness(0.2))) == pytest.approx(0.04, rel=1e-5)
    # A mirror is alpha 1 on both sides, and so is the book's hardness 511.
    assert m.alpha_from_shininess(m.shininess_from_roughness(0.0)) == 1.0
    assert core.ggx_alpha(1.0) == 0.0 and m.ggx_alpha_from_shininess(127.75) == 0.0
    # Past 1 the shininess runs on: hardness 1248 for roughness 0.2, so alpha 1248 / 511.
    assert m.alpha_from_shininess(m.shininess_from_roughness(0.2)) == pytest.approx((2 / 0.04 ** 2 - 2) / 511)


def test_the_gloss_range_stays_inside_a_half_float():
    """The glossiest lobe written as one (just above MIRROR_GGX_ALPHA) must keep
    the specular alpha a half-float EXR layer can hold (65504)."""
    r = (m.schema.MIRROR_GGX_ALPHA * 1.0001) ** 0.5
    assert 1.0 < m.alpha_from_shininess(m.shininess_from_roughness(r)) < 65504


def test_glossy_is_every_finite_alpha_but_a_mirrors():
    assert m.is_glossy(0.0) and m.is_glossy(0.5) and m.is_glossy(1.5)
    assert not m.is_glossy(1.0) and not m.is_glossy(float("nan")) and not m.is_glossy(float("inf"))


# -- the albedo a hidden side shows (docs/addon.md, *Hidden sides*)

def test_principled_albedo_is_the_base_colour_neither_metal_nor_transmitted():
    base = (0.8, 0.4, 0.2, 1.0)
    spec = m.principled_specular({"Base Color": base, "Metallic": 0.25, "Transmission": 0.5})
    assert spec.albedo == pytest.approx((0.8 * 0.375, 0.4 * 0.375, 0.2 * 0.375))
    spec4 = m.principled_specular({"Base Color": base, "Specular IOR Level": 0.5, "Transmission Weight": 1.0})
    assert spec4.albedo == (0.0, 0.0, 0.0)  # 4.x names; all transmitted
    assert m.principled_specular({}).albedo == pytest.approx((0.8, 0.8, 0.8))  # Blender's defaults


def test_albedo_of_other_shaders():
    assert m.evaluate_shader({"kind": "diffuse", "color": (0.1, 0.2, 0.3, 1.0)}) == \
        m.SpecularSpec((0.0, 0.0, 0.0), 0.0, (0.1, 0.2, 0.3))
    assert m.evaluate_shader({"kind": "glossy", "color": (1, 1, 1), "roughness": 0.1}).albedo == (0.0, 0.0, 0.0)
    assert m.evaluate_shader({"kind": "specular", "color": (0.04, 0.04, 0.04), "roughness": 0.3,
                              "base_color": (0.5, 0.6, 0.7, 1.0)}).albedo == pytest.approx((0.5, 0.6, 0.7))
    mix = m.evaluate_shader({"kind": "mix", "fac": 0.25, "a": {"kind": "diffuse", "color": (1.0, 0.0, 0.0)},
                             "b": {"kind": "glossy", "color": (1, 1, 1), "roughness": 0.0}})
    assert mix.albedo == pytest.approx((0.75, 0.0, 0.0))
    view = m.evaluate_shader({"kind": "viewport", "diffuse_color": (0.5, 0.5, 1.0, 1.0), "metallic": 0.5})
    assert view.albedo == pytest.approx((0.25, 0.25, 0.5))
    assert m.material_spec({"kind": "diffuse", "color": (0.3, 0.3, 0.3)}, hardness=100).albedo == \
        pytest.approx((0.3, 0.3, 0.3))  # a hardness override keeps it
    assert m.NO_MATERIAL.albedo == (0.8, 0.8, 0.8) and not m.NO_MATERIAL.reflective
