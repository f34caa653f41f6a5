// The CPU side of the physically based look: the specular weight and the cone
// blur (Backend::specular_weight, Backend::cone_blur; docs/look-core.md).
#pragma once
#include "glint/image.h"
#include "glint/material.h"
#include "glint/projection.h"

namespace glint::cpu {

Image specular_weight(const Image& position, const Image& normal, const Image& specular,
                      const Mat4& projection, int threads);

Image cone_blur(const Image& color, const Image& uv, const Image& specular, const MirrorScale* mirror,
                int threads);

}  // namespace glint::cpu
