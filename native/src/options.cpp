#include "glint/options.h"

#include <cmath>
#include <cstdio>
#include <string>

#include "glint/errors.h"

namespace glint {
namespace {

std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

void require_range(const char* name, double v, double lo, double hi) {
  if (!std::isfinite(v) || v < lo || v > hi) {
    throw InvalidArgument(name, "expected a finite number in [" + num(lo) + ", " + num(hi) +
                                    "], got " + num(v));
  }
}

void require_count(const char* name, int v, double lo, double hi) {
  if (v < lo || v > hi) {
    throw InvalidArgument(name, "expected an integer in [" + std::to_string(static_cast<long long>(lo)) + ", " +
                                    std::to_string(static_cast<long long>(hi)) + "], got " + std::to_string(v));
  }
}

// The index of `name` among a named option's choices; the message lists them
// as `"a" or "b"`.
int parse_choice(const schema::Option& o, const std::string& name) {
  const int k = o.choice_index(name);
  if (k >= 0) return k;
  std::string expected;
  for (int i = 0; o.choices[i]; ++i)
    expected += std::string(i == 0 ? "" : o.choices[i + 1] ? ", " : " or ") + "\"" + o.choices[i] + "\"";
  throw InvalidArgument(o.name, "expected " + expected + ", got \"" + name + "\"");
}

const char* choice_name(const schema::Option& o, int k) { return o.choices[k]; }

}  // namespace

void validate(const TraceOptions& o) {
  require_range(schema::max_distance.name, o.max_distance, schema::max_distance.min, schema::max_distance.max);
  require_range(schema::resolution.name, o.resolution, schema::resolution.min, schema::resolution.max);
  require_range(schema::thickness.name, o.thickness, schema::thickness.min, schema::thickness.max);
  require_count(schema::steps.name, o.steps, schema::steps.min, schema::steps.max);
  require_count(schema::antialias.name, o.antialias, schema::antialias.min, schema::antialias.max);
}

void validate(const BlurOptions& o) {
  require_count(schema::blur_size.name, o.size, schema::blur_size.min, schema::blur_size.max);
  require_range(schema::blur_separation.name, o.separation, schema::blur_separation.min,
                schema::blur_separation.max);
}

void validate(const PipelineOptions& o) {
  validate(o.trace);
  validate(o.blur);
  validate_threads(o.threads);
}

void validate_threads(int threads) {
  if (threads < 0 || threads > kMaxThreads) {
    throw InvalidArgument("threads", "expected 0 (all hardware threads) to " +
                                         std::to_string(kMaxThreads) + ", got " +
                                         std::to_string(threads));
  }
}

Combine parse_combine(const std::string& name) { return static_cast<Combine>(parse_choice(schema::combine, name)); }
const char* to_string(Combine c) { return choice_name(schema::combine, static_cast<int>(c)); }

Weighting parse_weighting(const std::string& name) {
  return static_cast<Weighting>(parse_choice(schema::weighting, name));
}
const char* to_string(Weighting w) { return choice_name(schema::weighting, static_cast<int>(w)); }

BlurMode parse_blur_mode(const std::string& name) { return static_cast<BlurMode>(parse_choice(schema::blur, name)); }
const char* to_string(BlurMode b) { return choice_name(schema::blur, static_cast<int>(b)); }

Blocked parse_blocked(const std::string& name) { return static_cast<Blocked>(parse_choice(schema::blocked, name)); }
const char* to_string(Blocked b) { return choice_name(schema::blocked, static_cast<int>(b)); }

}  // namespace glint
