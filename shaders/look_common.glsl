// Material helpers of the physically based look, the GLSL twins of
// glint::roughness_of, ggx_alpha_of and cone_tan
// (native/include/glint/material.h), in their operation order. Needs
// common.glsl (and so schema.glsl).

float look_roughness(vec4 s) { return 1.0 - clamp01(finite_f(s.a) ? s.a : 1.0); }

// GGX alpha from the shininess alpha: hardness = shininess alpha * 511,
// alpha = sqrt(2 / (hardness + 2)); shininess alpha 1 (the 511 clamp) = mirror,
// above 1 the gloss range (hardness past 511).
float look_ggx_alpha(vec4 s) {
  float r = look_roughness(s);
  precise float hardness;
  if (r > 0.0) {
    hardness = (1.0 - r) * (HARDNESS_PER_SHININESS * MAX_SHININESS);
  } else {
    if (!(s.a > 1.0) || !finite_f(s.a)) return 0.0;
    hardness = s.a * (HARDNESS_PER_SHININESS * MAX_SHININESS);
  }
  precise float q = 2.0 / (hardness + 2.0);
  return sqrt(q);
}

float look_cone_tan(float alpha) {
  precise float d = 1.0 - alpha * alpha;
  precise float t = 2.0 * alpha;
  precise float dm = d * MAX_CONE_TAN;
  return dm > t ? t / d : MAX_CONE_TAN;
}
