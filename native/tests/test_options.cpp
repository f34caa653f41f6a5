#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <cstdlib>
#include <limits>
#include <string>

#include "glint/errors.h"
#include "glint/marches.h"
#include "glint/options.h"
#include "glint/projection.h"

using namespace glint;

namespace {
std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InvalidArgument& e) {
    return e.argument();
  }
  return "";
}
}  // namespace

TEST(Options, DefaultsAreTheSeedChapters) {
  TraceOptions o;
  EXPECT_EQ(o.max_distance, 15.0f);
  EXPECT_EQ(o.resolution, 0.3f);
  EXPECT_EQ(o.steps, 10);
  EXPECT_EQ(o.thickness, 0.5f);
  BlurOptions b;
  EXPECT_EQ(2 * b.size + 1, 17);
  EXPECT_NO_THROW(validate(PipelineOptions{}));
}

TEST(Options, OutOfRangeNamesTheArgument) {
  TraceOptions o;
  o.resolution = 1.5f;
  EXPECT_EQ(error_of([&] { validate(o); }), "resolution");
  o = TraceOptions{};
  o.max_distance = -1.0f;
  EXPECT_EQ(error_of([&] { validate(o); }), "max_distance");
  o = TraceOptions{};
  o.thickness = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(error_of([&] { validate(o); }), "thickness");
  o = TraceOptions{};
  o.steps = -1;
  EXPECT_EQ(error_of([&] { validate(o); }), "steps");
  BlurOptions b;
  b.size = -2;
  EXPECT_EQ(error_of([&] { validate(b); }), "blur_size");
  EXPECT_EQ(error_of([] { parse_march("dda"); }), "march");
}

TEST(Projection, RejectsSingularAndNonFinite) {
  Mat4 zero;
  EXPECT_EQ(error_of([&] { validate_projection(zero); }), "projection");
  Mat4 p = perspective(1.0, 1.5, 0.1, 100.0);
  EXPECT_NO_THROW(validate_projection(p));
  p(0, 0) = std::numeric_limits<double>::infinity();
  EXPECT_EQ(error_of([&] { validate_projection(p); }), "projection");
}

TEST(Projection, ExtremeNearFarIsStillValid) {
  EXPECT_NO_THROW(validate_projection(perspective(0.8, 1.0, 1e-4, 1e7)));
  EXPECT_EQ(classify_projection(perspective(0.8, 1.0, 1e-4, 1e7)), ProjectionKind::Perspective);
  EXPECT_EQ(classify_projection(orthographic(2, 1, 0.1, 50)), ProjectionKind::Orthographic);
}

// The enums the core refers to by value name the rows of the registration
// list (native/marches/CMakeLists.txt) and the schema's choices in order.
TEST(Options, EnumeratorsNameTheirRowsAndChoices) {
  EXPECT_STREQ(to_string(March::Seed), "seed");
  EXPECT_STREQ(to_string(March::Linear), "linear");
  EXPECT_STREQ(to_string(March::Hiz), "hiz");
  EXPECT_STREQ(to_string(March::Exact), "exact");
  for (size_t k = 0; k < march_table().size(); ++k)
    EXPECT_EQ(static_cast<size_t>(march_table()[k].id), k) << march_table()[k].name;
  EXPECT_STREQ(to_string(TraceOptions{}.march), schema::march.initial_name);
  EXPECT_STREQ(to_string(TraceOptions{}.blocked), schema::blocked.initial_name);
  EXPECT_STREQ(to_string(PipelineOptions{}.combine), schema::combine.initial_name);
  EXPECT_STREQ(to_string(PipelineOptions{}.weighting), schema::weighting.initial_name);
  EXPECT_STREQ(to_string(PipelineOptions{}.blur_mode), schema::blur.initial_name);
  EXPECT_STREQ(to_string(Combine::Seed), "seed");
  EXPECT_STREQ(to_string(Weighting::Seed), "seed");
  EXPECT_STREQ(to_string(BlurMode::Box), "box");
  EXPECT_STREQ(to_string(Blocked::Occluder), "occluder");
}

// A float option's default as the schema writes it reads back as the same
// float: the double literal rounds to the value a float literal would have.
TEST(Options, SchemaDefaultsAreExactFloats) {
  for (const schema::Option* o : schema::kOptions) {
    if (o->type != schema::Type::Float) continue;
    const std::string text = schema::initial_text(*o);
    EXPECT_EQ(std::strtof(text.c_str(), nullptr), o->initial_float()) << o->name << " " << text;
  }
  for (const schema::Constant& c : schema::kConstants) {
    if (c.type != schema::Type::Float) continue;
    const std::string text = schema::number_text(c.value, c.type);
    EXPECT_EQ(std::strtof(text.c_str(), nullptr), static_cast<float>(c.value)) << c.name << " " << text;
  }
}
