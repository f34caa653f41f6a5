// glint-exr: the screen-space reflection pipeline on a multilayer EXR, for
// batch jobs and for checking the core outside Blender.
//
// Exit status: 0 done, 1 the work failed (unreadable input, missing layer or
// projection, pipeline or write error), 2 the command line is wrong.
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "glint/backend.h"
#include "glint/errors.h"
#include "glint/exr.h"
#include "glint/marches.h"
#include "glint/pipeline.h"
#include "glint/png.h"
#include "glint/presets.h"
#include "glint/schema.h"

namespace {

constexpr double kPi = 3.14159265358979323846;

// The usage text is in three parts: the options of the pipeline between
// them come from glint/schema.h (print_pipeline_options()).
const char* const kUsage = R"(usage: glint-exr [options] INPUT.exr [OUTPUT.exr]

Runs Glint's screen-space reflections on the position, normal, specular and
colour layers of a multilayer EXR and writes every input layer plus the
pipeline's layers (uv, reflection_color, reflection_blur, specular_weight,
reflection, combined) to OUTPUT.exr. Layers are read as glint_core.read_exr does: layer
"position" is channels position.R/G/B/A (or .X/Y/Z/W), Blender's
"ViewLayer.Pass.R" is layer "ViewLayer.Pass". Row 0 is the bottom row.

Input layers:
  --position-layer NAME   view-space position, w = 1 where seen  [position]
  --normal-layer NAME     view-space normal                     [normal]
  --specular-layer NAME   rgb specular colour, a = shininess     [specular]
  --color-layer NAME      base colour (linear)                   [color]
  --back-position-layer NAME  optional: the surface behind each pixel's
                          own, for marches that use true thickness [back_position]
  --specular-base-layer NAME  optional: the renderer's own specular (rgb),
                          replaced where a reflection is found (--combine
                          over only)                             [specular_base]

Projection (default: the input's glintProjection header attribute):
  --projection "P00 P01 ... P33"      16 numbers, rows as printed:
                                      clip = P * (x, y, z, 1)
  --perspective FOV_Y_DEG,NEAR,FAR    aspect = image width / height
  --orthographic HALF_HEIGHT,NEAR,FAR half width = half height * aspect
)";

const char* const kUsageOutput = R"(
Output:
  --png FILE              8-bit sRGB PNG of the combined layer
  --compression METHOD    zip|zips|piz|rle|none                  [zip]
  -h, --help              print this and exit

OUTPUT.exr may be left out when --png is given. Per-stage timings are printed
to stdout. Example:
  glint-exr --perspective 50,0.1,100 --png out.png gbuffer.exr out.exr
)";

// "  --flag METAVAR" padded to the doc column, the doc wrapped at 79 columns.
void print_option(const std::string& flag, const std::string& doc) {
  constexpr size_t kColumn = 26, kWidth = 79;
  std::string line = "  " + flag;
  line += line.size() < kColumn ? std::string(kColumn - line.size(), ' ') : "\n" + std::string(kColumn, ' ');
  size_t used = kColumn;
  std::istringstream words(doc);
  std::string word;
  bool first = true;
  while (words >> word) {
    if (!first && used + 1 + word.size() > kWidth) {
      line += "\n" + std::string(kColumn, ' ');
      used = kColumn;
      first = true;
    }
    if (!first) {
      line += ' ';
      ++used;
    }
    line += word;
    used += word.size();
    first = false;
  }
  std::printf("%s\n", line.c_str());
}

// Every option of the pipeline the command line takes, from the schema:
// meaning, unit, limits or names, default.
void print_pipeline_options() {
  namespace s = glint::schema;
  std::printf("\nPipeline (defaults in brackets):\n");
  for (const s::Option* o : s::kOptions) {
    if (o == &s::memory_limit_mb) continue;  // no flag: the environment's limit applies
    std::string flag = std::string("--") + o->name;
    std::replace(flag.begin(), flag.end(), '_', '-');
    std::string doc = o->doc;
    if (o->type == s::Type::Name) {
      std::string names;
      for (int k = 0; o->choices && o->choices[k]; ++k) names += (k ? "|" : "") + std::string(o->choices[k]);
      flag += names.empty() ? " NAME" : " " + names;
    } else {
      flag += o->type == s::Type::Int ? " N" : " F";
      doc += std::string("; ") + (*o->unit ? std::string(o->unit) + " " : "") + "in [" +
             s::number_text(o->min, o->type) + ", " + s::number_text(o->max, o->type) + "]";
    }
    print_option(flag, doc + " [" + s::initial_text(*o) + "]");
  }
  print_option("--preset NAME", "a preset's trace options (below); flags after it override them");
  std::printf("  The seed's look: --weighting seed --blur box --combine seed.\n");
}

// The marches and presets, and what each option means, from the core's tables.
void print_marches() {
  std::printf("\nMarches (--march):\n");
  for (const glint::MarchInfo& m : glint::march_table()) {
    std::printf("  %-8s %s\n", m.name, m.description);
    for (const glint::MarchKnob& k : m.knobs) {
      std::string flag = k.option;  // keyword names; flags spell _ as -
      std::replace(flag.begin(), flag.end(), '_', '-');
      std::printf("             --%s: %s\n", flag.c_str(), k.meaning);
    }
  }
  std::printf("\nPresets (--preset):\n");
  for (const glint::Preset& p : glint::presets())
    std::printf("  %-9s --march %s --steps %d --resolution %g --antialias %d --thickness %g --max-distance %g\n"
                "            %s\n",
                p.name, glint::to_string(p.trace.march), p.trace.steps, p.trace.resolution, p.trace.antialias,
                p.trace.thickness, p.trace.max_distance, p.description);
}

// A bad command line: message for stderr, exit status 2.
struct UsageError {
  std::string message;
};

struct Args {
  std::string input, output, png;
  std::string position_layer = "position", normal_layer = "normal", specular_layer = "specular",
              color_layer = "color", back_layer = "back_position",
              specular_base_layer = "specular_base";
  bool back_layer_given = false;  // --back-position-layer named it: it must be there
  bool specular_base_given = false;
  std::optional<glint::Mat4> projection;  // from --projection
  std::optional<std::vector<double>> perspective, orthographic;
  glint::PipelineOptions opt;
  std::string backend = glint::schema::backend.initial_name;
  std::string compression = "zip";
};

double parse_double(const std::string& flag, const std::string& text) {
  const char* s = text.c_str();
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(s, &end);
  if (end == s || *end != '\0' || errno == ERANGE || !std::isfinite(v))
    throw UsageError{flag + ": expected a finite number, got \"" + text + "\""};
  return v;
}

int parse_int(const std::string& flag, const std::string& text) {
  const char* s = text.c_str();
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(s, &end, 10);
  if (end == s || *end != '\0' || errno == ERANGE || v < -2147483647L || v > 2147483647L)
    throw UsageError{flag + ": expected an integer, got \"" + text + "\""};
  return static_cast<int>(v);
}

// Numbers separated by commas and/or white space.
std::vector<double> parse_list(const std::string& flag, const std::string& text, size_t count) {
  std::string spaced = text;
  for (char& c : spaced)
    if (c == ',') c = ' ';
  std::istringstream in(spaced);
  std::vector<double> out;
  std::string token;
  while (in >> token) out.push_back(parse_double(flag, token));
  if (out.size() != count)
    throw UsageError{flag + ": expected " + std::to_string(count) + " numbers, got " +
                     std::to_string(out.size()) + " in \"" + text + "\""};
  return out;
}

Args parse_args(int argc, char** argv, bool& help) {
  Args a;
  std::vector<std::string> positional;
  bool options_done = false;
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    if (options_done || arg.size() < 2 || arg[0] != '-') {
      positional.push_back(arg);
      continue;
    }
    if (arg == "--") {
      options_done = true;
      continue;
    }
    if (arg == "-h" || arg == "--help") {
      help = true;
      return a;
    }
    std::string flag = arg, value;
    bool has_value = false;
    if (const size_t eq = arg.find('='); arg.rfind("--", 0) == 0 && eq != std::string::npos) {
      flag = arg.substr(0, eq);
      value = arg.substr(eq + 1);
      has_value = true;
    }
    auto next = [&]() -> std::string {
      if (has_value) return value;
      if (i + 1 >= argc) throw UsageError{flag + ": expected a value"};
      return argv[++i];
    };
    if (flag == "--position-layer") a.position_layer = next();
    else if (flag == "--normal-layer") a.normal_layer = next();
    else if (flag == "--specular-layer") a.specular_layer = next();
    else if (flag == "--back-position-layer") {
      a.back_layer = next();
      a.back_layer_given = true;
    }
    else if (flag == "--color-layer") a.color_layer = next();
    else if (flag == "--specular-base-layer") {
      a.specular_base_layer = next();
      a.specular_base_given = true;
    }
    else if (flag == "--projection") {
      const auto v = parse_list(flag, next(), 16);
      glint::Mat4 m;
      for (int k = 0; k < 16; ++k) m.m[k] = v[k];
      a.projection = m;
    } else if (flag == "--perspective") a.perspective = parse_list(flag, next(), 3);
    else if (flag == "--orthographic") a.orthographic = parse_list(flag, next(), 3);
    else if (flag == "--max-distance") a.opt.trace.max_distance = static_cast<float>(parse_double(flag, next()));
    else if (flag == "--resolution") a.opt.trace.resolution = static_cast<float>(parse_double(flag, next()));
    else if (flag == "--steps") a.opt.trace.steps = parse_int(flag, next());
    else if (flag == "--antialias") a.opt.trace.antialias = parse_int(flag, next());
    else if (flag == "--thickness") a.opt.trace.thickness = static_cast<float>(parse_double(flag, next()));
    else if (flag == "--preset") {
      const std::string v = next();
      try {
        a.opt.trace = glint::preset(v.c_str()).trace;  // later flags still override it
      } catch (const glint::InvalidArgument& e) {
        throw UsageError{flag + ": " + std::string(e.what()).substr(std::string(e.what()).find(": ") + 2)};
      }
    } else if (flag == "--march") {
      const std::string v = next();
      try {
        a.opt.trace.march = glint::parse_march(v);
      } catch (const glint::InvalidArgument&) {
        throw UsageError{flag + ": expected one of " + glint::march_names() + ", got \"" + v + "\""};
      }
      if (glint::march_info(a.opt.trace.march).needs_mesh)
        throw UsageError{flag + " " + v + ": that march needs the scene's triangles, which an EXR does not hold"};
    } else if (flag == "--blur-size") a.opt.blur.size = parse_int(flag, next());
    else if (flag == "--blur-separation") a.opt.blur.separation = static_cast<float>(parse_double(flag, next()));
    else if (flag == "--weighting" || flag == "--blur" || flag == "--blocked" || flag == "--combine") {
      const std::string v = next();
      try {
        if (flag == "--weighting") a.opt.weighting = glint::parse_weighting(v);
        else if (flag == "--blur") a.opt.blur_mode = glint::parse_blur_mode(v);
        else if (flag == "--combine") a.opt.combine = glint::parse_combine(v);
        else a.opt.trace.blocked = glint::parse_blocked(v);
      } catch (const glint::InvalidArgument& e) {
        throw UsageError{flag + ": " + std::string(e.what()).substr(std::string(e.what()).find(": ") + 2)};
      }
    } else if (flag == "--backend") {
      a.backend = next();
      if (glint::schema::backend.choice_index(a.backend) < 0)
        throw UsageError{flag + ": expected cpu, gl or auto, got \"" + a.backend + "\""};
    } else if (flag == "--threads") a.opt.threads = parse_int(flag, next());
    else if (flag == "--png") a.png = next();
    else if (flag == "--compression") a.compression = next();
    else throw UsageError{"unknown option \"" + flag + "\" (see --help)"};
  }

  if (positional.empty()) throw UsageError{"missing INPUT.exr (see --help)"};
  if (positional.size() > 2)
    throw UsageError{"expected INPUT.exr [OUTPUT.exr], got " + std::to_string(positional.size()) +
                     " file names"};
  a.input = positional[0];
  if (positional.size() == 2) a.output = positional[1];
  if (a.output.empty() && a.png.empty())
    throw UsageError{"nothing to write: give OUTPUT.exr and/or --png FILE"};
  if (!a.output.empty() && a.output == a.input)
    throw UsageError{"OUTPUT.exr is the input file; refusing to overwrite it"};
  const int sources = (a.projection ? 1 : 0) + (a.perspective ? 1 : 0) + (a.orthographic ? 1 : 0);
  if (sources > 1)
    throw UsageError{"--projection, --perspective and --orthographic exclude each other"};
  if (a.compression != "zip" && a.compression != "zips" && a.compression != "piz" &&
      a.compression != "rle" && a.compression != "none")
    throw UsageError{"--compression: expected zip, zips, piz, rle or none, got \"" + a.compression + "\""};

  // Range checks by the core, reported under the flag's name.
  try {
    glint::validate(a.opt);
    if (a.projection) glint::validate_projection(*a.projection);
  } catch (const glint::InvalidArgument& e) {
    std::string flag = "--" + e.argument();
    for (char& c : flag)
      if (c == '_') c = '-';
    std::string msg = e.what();
    msg = msg.substr(std::min(msg.size(), e.argument().size() + 2));
    throw UsageError{flag + ": " + msg};
  }
  if (a.perspective) {
    const auto& p = *a.perspective;
    if (!(p[0] > 0.0 && p[0] < 180.0))
      throw UsageError{"--perspective: expected a vertical field of view in (0, 180) degrees"};
    if (!(p[1] > 0.0 && p[2] > p[1]))
      throw UsageError{"--perspective: expected 0 < NEAR < FAR"};
  }
  if (a.orthographic) {
    const auto& o = *a.orthographic;
    if (!(o[0] > 0.0)) throw UsageError{"--orthographic: expected HALF_HEIGHT > 0"};
    if (!(o[2] > o[1])) throw UsageError{"--orthographic: expected NEAR < FAR"};
  }
  return a;
}

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

std::string number(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

const glint::Image& layer(const glint::ExrFile& f, const std::string& path, const std::string& name,
                          const char* flag) {
  auto it = f.layers.find(name);
  if (it != f.layers.end()) return it->second;
  std::string have;
  for (const auto& [n, img] : f.layers) have += (have.empty() ? "\"" : ", \"") + n + "\"";
  throw glint::Error("\"" + path + "\" has no layer \"" + name + "\" (it has " + have +
                     "); choose one with " + flag);
}

int run(const Args& a) {
  glint::set_exr_threads(a.opt.threads);
  auto t0 = Clock::now();
  glint::ExrFile in = glint::read_exr(a.input);
  const double read_ms = ms_since(t0);
  for (const auto& ch : in.skipped_channels)
    std::fprintf(stderr, "glint-exr: note: channel \"%s\" is not an R/G/B/A or X/Y/Z/W channel; "
                 "it is not read or copied\n", ch.c_str());

  glint::PipelineInputs pin;
  pin.position = layer(in, a.input, a.position_layer, "--position-layer");
  pin.normal = layer(in, a.input, a.normal_layer, "--normal-layer");
  pin.specular = layer(in, a.input, a.specular_layer, "--specular-layer");
  pin.color = layer(in, a.input, a.color_layer, "--color-layer");
  // The back-face layer is optional: used where the file has it.
  if (a.back_layer_given || in.layers.count(a.back_layer))
    pin.back_position = layer(in, a.input, a.back_layer, "--back-position-layer");
  // Found by name it is used where it can be ("over"); named by the flag it must be.
  if (a.specular_base_given ||
      (in.layers.count(a.specular_base_layer) && a.opt.combine == glint::Combine::Over))
    pin.specular_base = layer(in, a.input, a.specular_base_layer, "--specular-base-layer");
  const int w = pin.position.width, h = pin.position.height;
  const double aspect = static_cast<double>(w) / h;

  if (a.projection) {
    pin.projection = *a.projection;
  } else if (a.perspective) {
    const auto& p = *a.perspective;
    pin.projection = glint::perspective(p[0] * kPi / 180.0, aspect, p[1], p[2]);
  } else if (a.orthographic) {
    const auto& o = *a.orthographic;
    pin.projection = glint::orthographic(o[0] * aspect, o[0], o[1], o[2]);
  } else if (in.projection) {
    pin.projection = *in.projection;
  } else {
    throw glint::Error("\"" + a.input + "\" has no " + glint::kExrProjectionAttribute +
                       " header attribute; give --projection, --perspective or --orthographic");
  }

  auto backend = glint::get_backend(a.backend, a.opt.threads);
  t0 = Clock::now();
  glint::PipelineResult res = glint::run_pipeline(*backend, pin, a.opt);
  const double pipeline_ms = ms_since(t0);

  std::printf("glint-exr: %s, %dx%d, backend %s, %zu reflective pixels (%zu rough)\n",
              a.input.c_str(), w, h, backend->name().c_str(), res.reflective_pixels,
              res.rough_pixels);
  std::printf("  %-18s %10.3f ms\n", "read", read_ms);
  for (const auto& t : res.timings)
    std::printf("  %-18s %10.3f ms%s\n", t.stage.c_str(), t.milliseconds,
                t.skipped ? "  (skipped)" : "");
  std::printf("  %-18s %10.3f ms\n", "pipeline total", pipeline_ms);

  if (!a.output.empty()) {
    std::map<std::string, glint::Image> out = std::move(in.layers);
    for (const auto& name : glint::pipeline_layer_names()) {
      if (out.count(name))
        std::fprintf(stderr, "glint-exr: note: input layer \"%s\" is replaced by the pipeline's\n",
                     name.c_str());
      out[name] = std::move(res.layers.at(name));
    }
    glint::ExrWriteOptions wo;
    wo.projection = pin.projection;
    wo.compression = a.compression;
    const auto& o = a.opt;
    wo.options = "max_distance=" + number(o.trace.max_distance) +
                 " resolution=" + number(o.trace.resolution) +
                 " steps=" + std::to_string(o.trace.steps) +
                 " thickness=" + number(o.trace.thickness) +
                 " march=" + glint::to_string(o.trace.march) +
                 " antialias=" + std::to_string(o.trace.antialias) +
                 " blocked=" + glint::to_string(o.trace.blocked) +
                 " weighting=" + glint::to_string(o.weighting) +
                 " blur=" + glint::to_string(o.blur_mode) +
                 " blur_size=" + std::to_string(o.blur.size) +
                 " blur_separation=" + number(o.blur.separation) +
                 " combine=" + glint::to_string(o.combine) + " backend=" + backend->name();
    t0 = Clock::now();
    glint::write_exr(a.output, out, wo);
    std::printf("  %-18s %10.3f ms\n", "write exr", ms_since(t0));
    if (!a.png.empty()) {
      t0 = Clock::now();
      glint::write_png_srgb(a.png, out.at("combined"));
      std::printf("  %-18s %10.3f ms\n", "write png", ms_since(t0));
    }
    std::printf("wrote %s (%zu layers)\n", a.output.c_str(), out.size());
  } else {
    t0 = Clock::now();
    glint::write_png_srgb(a.png, res.layers.at("combined"));
    std::printf("  %-18s %10.3f ms\n", "write png", ms_since(t0));
  }
  if (!a.png.empty()) std::printf("wrote %s\n", a.png.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  try {
    bool help = false;
    args = parse_args(argc, argv, help);
    if (help) {
      std::fputs(kUsage, stdout);
      print_pipeline_options();
      std::fputs(kUsageOutput, stdout);
      print_marches();
      return 0;
    }
  } catch (const UsageError& e) {
    std::fprintf(stderr, "glint-exr: %s\n", e.message.c_str());
    return 2;
  }
  try {
    return run(args);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "glint-exr: error: %s\n", e.what());
    return 1;
  }
}
