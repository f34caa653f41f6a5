// The camera projection, as Blender's Object.calc_matrix_camera gives it.
#pragma once
#include <array>

namespace glint {

// A 4x4 matrix in row-major order, rows as printed: clip = m * (x, y, z, 1).
// Kept in double so that validation and near-plane clipping do not lose the
// digits a 1e-4 / 1e7 near/far pair needs; stages copy it to float.
struct Mat4 {
  std::array<double, 16> m{};
  double operator()(int row, int col) const { return m[row * 4 + col]; }
  double& operator()(int row, int col) { return m[row * 4 + col]; }
};

enum class ProjectionKind {
  Perspective,   // last row (0, 0, -1, 0): clip.w is the view distance
  Orthographic,  // last row (0, 0, 0, 1): clip.w is 1
  General,       // any other invertible matrix: depth interpolates as 1/w
};

// Throws InvalidArgument("projection", ...) for a non-finite or singular matrix.
void validate_projection(const Mat4& p);
ProjectionKind classify_projection(const Mat4& p);
// Where the camera looks from, for the incident direction of each pixel:
// the homogeneous point e with rows 0, 1 and 3 of P e = 0 (it projects to no
// pixel). Origin: a perspective camera at the view-space origin, whose rays
// are normalize(position) as in the seed. Point: normalize(position - eye).
// Direction: parallel rays along `eye` (orthographic), pointing into the scene.
enum class EyeKind { Origin, Point, Direction };
struct CameraEye {
  EyeKind kind = EyeKind::Origin;
  float eye[3] = {0.0f, 0.0f, 0.0f};
};
CameraEye camera_eye(const Mat4& projection);
// The incident direction toward view point p, unnormalised, by the eye's kind
// (what the march's read_origin() normalises).
inline void incident_toward(const CameraEye& eye, const float* p, float d[3]) {
  if (eye.kind == EyeKind::Origin) {
    d[0] = p[0], d[1] = p[1], d[2] = p[2];
  } else if (eye.kind == EyeKind::Point) {
    d[0] = p[0] - eye.eye[0], d[1] = p[1] - eye.eye[1], d[2] = p[2] - eye.eye[2];
  } else {
    d[0] = eye.eye[0], d[1] = eye.eye[1], d[2] = eye.eye[2];
  }
}

// The inverse of a matrix validate_projection() accepts.
Mat4 inverse(const Mat4& p);

// Convenience builders, mostly for tests and the command-line tool.
// fov_y in radians; aspect = width / height; near/far > 0 in view units.
Mat4 perspective(double fov_y, double aspect, double near, double far);
Mat4 orthographic(double half_width, double half_height, double near, double far);

}  // namespace glint
