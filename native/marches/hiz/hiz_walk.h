// The hiz march's walk through the pyramid (docs/hiz.md, "The walk").
// march_hiz.cpp makes each ray and tests the level-0 texels the walk stops
// at; the walk is the part in between, where a ray spends nearly all of its
// steps. One ray is a chain of ~25 dependent steps of a few dozen
// instructions each, which leaves a core mostly waiting on the chain; rays
// are independent, so on AVX2 one chain of vector steps walks eight of them,
// each in its own lane, and two such chains run side by side
// (hiz_walk_avx2.cpp), with the scalar walk's answers bit for bit.
// hiz_walk.glsl is the same walk on GL.
#pragma once

namespace glint::cpu {

// What the walk reads of one ray (march_hiz.cpp's Ray, which explains each
// term), and where it is: t just past the origin's own texel, with num(t) and
// b(t) there.
struct WalkRay {
  float f0[2], d[2], inv[2], nudge[2];
  float a0z, daz, b0, db;
  float t_end;
  float t, nt, bt;
};

// The pyramid as the walk reads it: level l is max(1, width >> l) by
// max(1, height >> l) cells (OpenGL's mip rule, as HizPyramid), two floats
// (nearest, farthest) per cell, level after level.
struct WalkPyramid {
  int levels = 0, width = 0, height = 0;
  const float* range = nullptr;
  const int* offset = nullptr;  // first cell of each level; all cells fit an int
  // What the caller's texel test reads first, per texel in rows of `width`:
  // `floats[k]` floats of texel (x, y) at texel[k] + (y * width + x) *
  // floats[k]. The walk asks for both rows of a cell's texels as it goes
  // down to them, so that they are on their way by the time a test reads
  // them (the buffers are far bigger than the caches). Loads only.
  const float* texel[2] = {nullptr, nullptr};
  int floats[2] = {0, 0};
};

// The caller's side of a walk: its queue of pixels and its texel test, both
// scalar, behind plain function pointers (the AVX2 walk is built with its
// own flags in its own file, and shares no inline code with the rest of the
// library).
struct WalkHost {
  void* ctx = nullptr;
  // The next ray of the queue into `lane`; false when the queue is empty.
  // Pixels of the queue that have no ray (or need none) are answered here.
  bool (*start)(void* ctx, int lane, WalkRay& ray) = nullptr;
  // The ray in `lane` overlaps level-0 texel (i, j) between fractions ta and
  // tb: true when it walks on past the texel, false when it ended there (the
  // caller wrote its answer). A ray that runs out of steps or leaves the
  // screen ends without a call: its answer is the miss `start` wrote.
  bool (*texel)(void* ctx, int lane, int i, int j, float ta, float tb) = nullptr;
};

// The most rays a walk keeps at once (the AVX2 walk's two groups of eight
// lanes): the caller keeps this many rays' state.
constexpr int kWalkLanes = 16;

// The walks: one ray at a time (hiz_walk.cpp), which every machine runs, and
// sixteen at once in AVX2 registers (hiz_walk_avx2.cpp), built on x86-64 and
// run where the CPU has AVX2. Their answers are the same bit for bit.
enum class WalkIsa { Scalar, Avx2 };
bool hiz_walk_available(WalkIsa isa);
// The walk hiz_walk() uses: the fastest available one.
WalkIsa hiz_walk_default();

// Walks every ray `host` starts, at most `budget` steps each, with the
// default walk (or `isa`, which must be available).
void hiz_walk(const WalkPyramid& pyr, const WalkHost& host, int budget);
void hiz_walk(const WalkPyramid& pyr, const WalkHost& host, int budget, WalkIsa isa);

void hiz_walk_scalar(const WalkPyramid& pyr, const WalkHost& host, int budget);
void hiz_walk_avx2(const WalkPyramid& pyr, const WalkHost& host, int budget);

}  // namespace glint::cpu
