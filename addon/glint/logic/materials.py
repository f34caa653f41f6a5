"""Material -> specular buffer: the rule Glint writes into the G-buffer.

The book's specular buffer holds ``(specular r, g, b, shininess / 127.75)``, where
shininess is Blender Internal's *hardness* divided by 4 (hardness runs 1..511, so
511 -> 127.75 -> 1.0). Blender 2.8+ has no hardness; this module derives the two
numbers from what a material does have:

* a custom property ``hardness`` on the material (1..511) sets the shininess
  directly, as the book's Blender Internal materials did;
* a Principled BSDF gives the specular colour as its reflectance at normal
  incidence (F0) and the shininess from its roughness (see
  :func:`hardness_from_roughness`);
* other shader nodes have a fixed rule (Glossy = a tinted mirror, Diffuse or
  Emission = no specular ...), Mix and Add shaders combine their inputs;
* a material without nodes, or with a shader this module does not know, uses its
  viewport display values (``specular_color``, ``specular_intensity``,
  ``roughness``, ``metallic``, ``diffuse_color``), read as a Principled BSDF.

Each row also carries the material's diffuse *albedo* (its base colour where it
is not metal), which the rasterizer reports for the back-face layer: a reflected
ray that comes into an object by the side the camera does not see shows that
side in this colour (docs/addon.md, *Hidden sides*).

A shader is described by plain dicts (built in Blender by ``gather.py``), so the
rule is tested here without Blender:

    {"kind": "principled", "inputs": {"Base Color": (r, g, b, a), "Metallic": m, ...}}
    {"kind": "glossy", "color": (r, g, b), "roughness": r}
    {"kind": "specular", "color": (r, g, b), "roughness": r}   # Eevee's Specular BSDF
    {"kind": "glass", "ior": 1.45, "roughness": r}
    {"kind": "diffuse", "color": (r, g, b)}                   # Diffuse BSDF: no specular
    {"kind": "none"}                                          # emission, ...
    {"kind": "mix", "fac": f, "a": <desc>, "b": <desc>}
    {"kind": "add", "a": <desc>, "b": <desc>}
    {"kind": "viewport", "specular_color": ..., "specular_intensity": ...,
     "roughness": ..., "metallic": ..., "diffuse_color": ...}
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping, Optional, Sequence, Tuple

from . import schema, texels

# The book: "511 is exported as 127.75", i.e. shininess = hardness / 4. The
# numbers are the core's (schema.py), so that this mapping and the core's
# inverse (glint::ggx_alpha_of) cannot drift apart.
MIN_HARDNESS = schema.MIN_HARDNESS
MAX_SHININESS = schema.MAX_SHININESS
HARDNESS_TO_SHININESS = 1.0 / schema.HARDNESS_PER_SHININESS
MAX_HARDNESS = schema.HARDNESS_PER_SHININESS * schema.MAX_SHININESS  # 511

# Blender 3.x Principled BSDF: dielectric F0 = 0.08 * Specular (0.5 -> 0.04, IOR 1.5).
PRINCIPLED_3X_F0_PER_SPECULAR = 0.08
# Rec. 709 luminance, which Blender's Principled BSDF uses for its specular tint.
LUMINANCE = (0.2126, 0.7152, 0.0722)

RGB = Tuple[float, float, float]


@dataclass(frozen=True)
class SpecularSpec:
    """One row of the material table handed to the rasterizer."""

    color: RGB  # specular colour, linear, each in [0, 1]
    shininess: float  # the book's units, 0..127.75, above it the gloss range
    albedo: RGB = (0.0, 0.0, 0.0)  # diffuse colour, linear, each in [0, 1]

    @property
    def amount(self) -> float:
        """How strongly the lobe reflects, the mean of its colour in double
        precision: the weight of each lobe where two shaders mix
        (:func:`_combine`). Whether the core traces it is :attr:`reflective`."""
        return (self.color[0] + self.color[1] + self.color[2]) / 3.0

    @property
    def reflective(self) -> bool:
        """Whether the core traces this material's pixels (texels.is_reflective,
        on the colour as the G-buffer holds it)."""
        return bool(texels.is_reflective(self.color))

    @property
    def alpha(self) -> float:
        """The specular buffer's alpha: shininess / 127.75 (above 1: the gloss range)."""
        return alpha_from_shininess(self.shininess)

    def row(self) -> Tuple[float, float, float, float]:
        return (self.color[0], self.color[1], self.color[2], self.shininess)


NO_SPECULAR = SpecularSpec((0.0, 0.0, 0.0), 0.0)
# An object without a material: Blender shades it a plain grey (0.8) dielectric
# in every engine, which Glint treats as not reflective.
NO_MATERIAL = SpecularSpec((0.0, 0.0, 0.0), 0.0, (0.8, 0.8, 0.8))


def _clamp(v: float, lo: float, hi: float) -> float:
    if not math.isfinite(v):
        return lo
    return lo if v < lo else hi if v > hi else v


def _rgb(value, default: RGB = (0.0, 0.0, 0.0)) -> RGB:
    """An RGB triple from a float, an RGB(A) sequence or None."""
    if value is None:
        return default
    if isinstance(value, (int, float)):
        v = float(value)
        return (v, v, v)
    seq = list(value)
    if len(seq) >= 3:
        return (float(seq[0]), float(seq[1]), float(seq[2]))
    raise ValueError(f"expected a colour (3 or 4 numbers), got {value!r}")


def _clamp_rgb(c: Sequence[float]) -> RGB:
    return (_clamp(c[0], 0.0, 1.0), _clamp(c[1], 0.0, 1.0), _clamp(c[2], 0.0, 1.0))


def _mix(a: RGB, b: RGB, t: float) -> RGB:
    return (a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t)


def shininess_from_hardness(hardness: float) -> float:
    """Blender Internal hardness (clamped to 1..511) to the book's shininess (/ 4)."""
    return _clamp(float(hardness), MIN_HARDNESS, MAX_HARDNESS) * HARDNESS_TO_SHININESS


def alpha_from_shininess(shininess: float) -> float:
    """The specular buffer's alpha: shininess / 127.75, 0 below 0, 1 (a mirror)
    for +inf; above 1 the gloss range (glint_core.shininess_to_alpha)."""
    a = float(shininess) / MAX_SHININESS
    if not a > 0.0:
        return 0.0
    return a if math.isfinite(a) else 1.0


def hardness_from_roughness(roughness: float) -> float:
    """Blender roughness -> a Blinn-Phong exponent, at least Blender Internal's 1.

    Hardness was the exponent of a Blinn-Phong lobe. The usual equivalence between
    a Blinn-Phong exponent ``n`` and a microfacet width ``alpha`` (Walter et al.
    2007, "Microfacet models for refraction", eq. 30) is ``n = 2 / alpha^2 - 2``,
    and Blender's BSDFs square the user's roughness: ``alpha = roughness^2``.
    Roughness 1 gives 0, raised to the minimum hardness 1. Exponents above 511
    (roughness below ~0.25) are past Blender Internal's range: the gloss range
    (:func:`shininess_from_roughness`); a lobe narrower than MIRROR_GGX_ALPHA is a
    mirror, ``inf``.
    """
    r = _clamp(float(roughness), 0.0, 1.0)
    alpha = r * r
    if alpha <= schema.MIRROR_GGX_ALPHA:
        return math.inf
    return max(2.0 / (alpha * alpha) - 2.0, MIN_HARDNESS)


def shininess_from_roughness(roughness: float) -> float:
    """Roughness -> shininess. Hardness up to 511 is the book's; past it (roughness
    below ~0.25) the shininess goes on growing, hardness / 4, so the specular
    buffer's alpha passes 1 (the gloss range, docs/conventions.md) and the core's
    cone blurs the reflection as the lobe is wide; a mirror is 127.75 (alpha 1).
    Exactly 511 lands on the mirror; the next float of roughness below does not."""
    hardness = hardness_from_roughness(roughness)
    if math.isinf(hardness):
        return MAX_SHININESS
    if hardness > MAX_HARDNESS:
        return hardness * HARDNESS_TO_SHININESS
    return shininess_from_hardness(hardness)


def is_glossy(alpha: float) -> bool:
    """Whether the core's cone blurs a pixel with this specular alpha: it has a
    lobe (glint::is_glossy): every finite alpha but a mirror's 1."""
    return math.isfinite(alpha) and alpha != 1.0


def _luminance(c: RGB) -> float:
    return LUMINANCE[0] * c[0] + LUMINANCE[1] * c[1] + LUMINANCE[2] * c[2]


def _tint_colour(base: RGB) -> RGB:
    """The Principled BSDF's tint: the base colour at unit luminance (white if black)."""
    lum = _luminance(base)
    if lum <= 0.0:
        return (1.0, 1.0, 1.0)
    return (base[0] / lum, base[1] / lum, base[2] / lum)


def f0_from_ior(ior: float) -> float:
    """Fresnel reflectance at normal incidence of a dielectric with index ``ior``."""
    ior = _clamp(float(ior), 1.0, 1e6)
    return ((ior - 1.0) / (ior + 1.0)) ** 2


def principled_specular(inputs: Mapping[str, object]) -> SpecularSpec:
    """The Principled BSDF rule, for Blender 3.x's and 4.x's input names.

    Colour = F0, the reflectance at normal incidence, mixed by Metallic between
    the dielectric F0 and the base colour (a metal reflects its base colour):

    * 3.x (``Specular``, ``Specular Tint`` a float): dielectric F0 =
      0.08 * Specular * mix(white, base colour at unit luminance, Specular Tint);
    * 4.x (``Specular IOR Level``, ``Specular Tint`` a colour, ``IOR``):
      dielectric F0 = F0(IOR) * 2 * Specular IOR Level * Specular Tint.

    Shininess comes from Roughness through :func:`hardness_from_roughness`.
    The colour is not weakened by roughness: the blur spreads rough reflections,
    the specular amount says how much light the surface reflects.
    """
    base = _clamp_rgb(_rgb(inputs.get("Base Color"), (0.8, 0.8, 0.8)))
    metallic = _clamp(float(inputs.get("Metallic", 0.0)), 0.0, 1.0)
    roughness = _clamp(float(inputs.get("Roughness", 0.5)), 0.0, 1.0)
    if "Specular IOR Level" in inputs:  # Blender 4.x
        level = max(float(inputs.get("Specular IOR Level", 0.5)), 0.0)
        tint = _rgb(inputs.get("Specular Tint"), (1.0, 1.0, 1.0))
        f0 = f0_from_ior(float(inputs.get("IOR", 1.5))) * 2.0 * level
        dielectric = (f0 * tint[0], f0 * tint[1], f0 * tint[2])
    else:  # Blender 3.x
        specular = max(float(inputs.get("Specular", 0.5)), 0.0)
        tint_amount = inputs.get("Specular Tint", 0.0)
        if not isinstance(tint_amount, (int, float)):
            raise ValueError("Specular Tint: expected a float in Blender 3.x's Principled BSDF")
        f0 = PRINCIPLED_3X_F0_PER_SPECULAR * specular
        tinted = _mix((1.0, 1.0, 1.0), _tint_colour(base), _clamp(float(tint_amount), 0.0, 1.0))
        dielectric = (f0 * tinted[0], f0 * tinted[1], f0 * tinted[2])
    color = _clamp_rgb(_mix(dielectric, base, metallic))
    # What is neither metal nor transmitted is diffuse (3.x: Transmission, 4.x: Transmission Weight).
    transmission = _clamp(float(inputs.get("Transmission Weight", inputs.get("Transmission", 0.0))), 0.0, 1.0)
    diffuse = (1.0 - metallic) * (1.0 - transmission)
    albedo = (base[0] * diffuse, base[1] * diffuse, base[2] * diffuse)
    return SpecularSpec(color, shininess_from_roughness(roughness), albedo)


def viewport_specular(desc: Mapping[str, object]) -> SpecularSpec:
    """A material without nodes: its viewport display values read as a 3.x Principled."""
    spec_colour = _rgb(desc.get("specular_color"), (1.0, 1.0, 1.0))
    intensity = max(float(desc.get("specular_intensity", 0.5)), 0.0)
    base = _clamp_rgb(_rgb(desc.get("diffuse_color"), (0.8, 0.8, 0.8)))
    metallic = _clamp(float(desc.get("metallic", 0.0)), 0.0, 1.0)
    f0 = PRINCIPLED_3X_F0_PER_SPECULAR * intensity
    dielectric = (f0 * spec_colour[0], f0 * spec_colour[1], f0 * spec_colour[2])
    color = _clamp_rgb(_mix(dielectric, base, metallic))
    albedo = (base[0] * (1.0 - metallic), base[1] * (1.0 - metallic), base[2] * (1.0 - metallic))
    return SpecularSpec(color, shininess_from_roughness(float(desc.get("roughness", 0.4))), albedo)


def ggx_alpha_from_shininess(shininess: float) -> float:
    """The GGX width the core reads from a shininess (glint::ggx_alpha_of, in
    double precision): 0 for a mirror, sqrt(2 / (hardness + 2)) otherwise."""
    a = alpha_from_shininess(shininess)
    if a == 1.0:
        return 0.0
    return math.sqrt(2.0 / (a * MAX_HARDNESS + 2.0))


def _combine(a: SpecularSpec, wa: float, b: SpecularSpec, wb: float) -> SpecularSpec:
    """Weighted sum of two lobes; their GGX widths averaged by each lobe's
    reflected amount (in width, not shininess, which runs the other way past a
    mirror's 127.75 in the gloss range). The albedos add with the same weights."""
    color = _clamp_rgb(tuple(a.color[i] * wa + b.color[i] * wb for i in range(3)))
    albedo = _clamp_rgb(tuple(a.albedo[i] * wa + b.albedo[i] * wb for i in range(3)))
    ka, kb = a.amount * wa, b.amount * wb
    if ka + kb <= 0.0:
        return SpecularSpec(color, 0.0, albedo)
    if kb <= 0.0 or a.shininess == b.shininess:  # one lobe, kept exactly
        return SpecularSpec(color, a.shininess, albedo)
    if ka <= 0.0:
        return SpecularSpec(color, b.shininess, albedo)
    width = (ggx_alpha_from_shininess(a.shininess) * ka + ggx_alpha_from_shininess(b.shininess) * kb) / (ka + kb)
    return SpecularSpec(color, shininess_from_roughness(math.sqrt(width)), albedo)


_MAX_DEPTH = 32  # node graphs are DAGs, but a hand-made description could loop


def evaluate_shader(desc: Optional[Mapping[str, object]], _depth: int = 0) -> SpecularSpec:
    """The specular spec of a shader description (see the module docstring)."""
    if desc is None or _depth > _MAX_DEPTH:
        return NO_SPECULAR
    kind = desc.get("kind")
    if kind == "principled":
        return principled_specular(desc.get("inputs", {}))
    if kind in ("glossy", "specular", "anisotropic"):
        color = _clamp_rgb(_rgb(desc.get("color"), (1.0, 1.0, 1.0)))
        albedo = _clamp_rgb(_rgb(desc.get("base_color"), (0.0, 0.0, 0.0)))  # Eevee's Specular BSDF has one
        return SpecularSpec(color, shininess_from_roughness(float(desc.get("roughness", 0.5))), albedo)
    if kind == "diffuse":
        return SpecularSpec((0.0, 0.0, 0.0), 0.0, _clamp_rgb(_rgb(desc.get("color"), (0.8, 0.8, 0.8))))
    if kind == "glass":
        f0 = f0_from_ior(float(desc.get("ior", 1.45)))
        return SpecularSpec((f0, f0, f0), shininess_from_roughness(float(desc.get("roughness", 0.0))))
    if kind == "viewport":
        return viewport_specular(desc)
    if kind == "mix":
        fac = _clamp(float(desc.get("fac", 0.5)), 0.0, 1.0)
        a = evaluate_shader(desc.get("a"), _depth + 1)
        b = evaluate_shader(desc.get("b"), _depth + 1)
        return _combine(a, 1.0 - fac, b, fac)
    if kind == "add":
        a = evaluate_shader(desc.get("a"), _depth + 1)
        b = evaluate_shader(desc.get("b"), _depth + 1)
        return _combine(a, 1.0, b, 1.0)
    if kind == "none":
        return NO_SPECULAR
    raise ValueError(f"unknown shader kind {kind!r}")


def material_spec(desc: Optional[Mapping[str, object]], hardness: Optional[float] = None) -> SpecularSpec:
    """The full rule: the shader's spec, with a custom ``hardness`` overriding shininess."""
    spec = evaluate_shader(desc)
    if hardness is not None:
        spec = SpecularSpec(spec.color, shininess_from_hardness(float(hardness)), spec.albedo)
    return spec
