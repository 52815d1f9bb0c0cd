// The `tridiff` command: depth of field from a colour image and a depth map (or from the
// built-in procedural scene), with any registered method.
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "tridiff/dof/lens.hpp"
#include "tridiff/dof/method.hpp"
#include "tridiff/dof/scene.hpp"
#include "tridiff/image/color.hpp"
#include "tridiff/image/io.hpp"

namespace {

using namespace tridiff;

constexpr const char* kUsage = R"(usage: tridiff dof [options]      depth of field (built-in scene when --color is absent)
       tridiff methods            list the depth-of-field methods
       tridiff --help

input
  --color FILE              colour image (PNG, JPEG, TIFF, OpenEXR, ...)
  --depth FILE              depth map; may be the colour file itself (an EXR with a Z channel)
  --depth-channel NAME      channel holding depth (default: Z, else depth, else the first)
  --depth-convention C      linear (distance, default) | normalized (needs --near, --far) | inverse
  --near M, --far M         planes for the normalized convention, metres
  --color-encoding E        auto (default: 8/16-bit sRGB, float linear) | srgb | linear
  --width W, --height H     size of the built-in scene (default 1920 x 1080)
lens (thin lens, seed 000 eq. 3.2)
  --focus M                 focus distance, metres (default 3.2; built-in scene: 3.95, its sphere)
  --f-number N              aperture f-number (default 2.8; built-in scene: 1.8)
  --focal-length MM         focal length (default 50)
  --sensor-width MM         sensor width the image spans (default 36)
  --max-coc PX              clamp of the circle of confusion diameter (default 64)
artist curve (seed 002 §28.5.3; replaces the lens when any is given)
  --near-start M --near-end M --near-radius PX   near blur: radius at near-start, 0 from near-end
  --far-start M --far-end M --far-radius PX      far blur: 0 up to far-start, radius from far-end
method
  --method NAME             adi (default) | mpad; see `tridiff methods`
  --layers                  blur the near field as its own layer (removes the blocking artifact)
  --in-focus PX             |CoC| below this is sharp and skipped (default 1)
  --no-skip                 process in-focus parts too (reference; same result, slower)
  --threads N               0 = all cores (default)
output
  -o, --output FILE         result image (default tridiff_dof.png)
  --coc-output FILE         CoC map image (default: <output stem>_coc.png)
  --input-output FILE       also write the input colour (useful with the built-in scene)
  --report FILE             the report as JSON as well as on stdout
)";

struct Arguments {
  std::map<std::string, std::string> values;
  std::vector<std::string> flags;
  bool has(const std::string& key) const { return values.count(key) != 0; }
  bool flag(const std::string& key) const {
    for (const auto& f : flags)
      if (f == key) return true;
    return false;
  }
  std::string text(const std::string& key, const std::string& fallback) const {
    auto it = values.find(key);
    return it == values.end() ? fallback : it->second;
  }
  float number(const std::string& key, float fallback) const {
    auto it = values.find(key);
    if (it == values.end()) return fallback;
    char* end = nullptr;
    const float value = std::strtof(it->second.c_str(), &end);
    if (end == it->second.c_str() || *end != '\0' || !std::isfinite(value))
      throw InvalidArgument("--" + key, -1, -1, "'" + it->second + "' is not a number");
    return value;
  }
  int integer(const std::string& key, int fallback) const {
    const float value = number(key, float(fallback));
    if (value != std::floor(value)) throw InvalidArgument("--" + key, -1, -1, "must be an integer");
    return int(value);
  }
};

const std::vector<std::string> kFlags = {"layers", "no-skip", "help"};
const std::vector<std::string> kValued = {
    "color", "depth", "depth-channel", "depth-convention", "near", "far", "color-encoding",
    "width", "height", "focus", "f-number", "focal-length", "sensor-width", "max-coc",
    "near-start", "near-end", "near-radius", "far-start", "far-end", "far-radius", "method",
    "in-focus", "threads", "output", "coc-output", "input-output", "report"};

Arguments parse(int argc, char** argv, int first) {
  Arguments args;
  for (int i = first; i < argc; ++i) {
    std::string key = argv[i];
    if (key == "-o") key = "--output";
    if (key == "-h") key = "--help";
    if (key.rfind("--", 0) != 0) throw InvalidArgument(key, -1, -1, "unexpected argument");
    key = key.substr(2);
    if (std::find(kFlags.begin(), kFlags.end(), key) != kFlags.end()) {
      args.flags.push_back(key);
      continue;
    }
    if (std::find(kValued.begin(), kValued.end(), key) == kValued.end())
      throw InvalidArgument("--" + key, -1, -1, "unknown option (see tridiff --help)");
    if (i + 1 >= argc) throw InvalidArgument("--" + key, -1, -1, "needs a value");
    args.values[key] = argv[++i];
  }
  return args;
}

ColorEncoding parse_encoding(const std::string& text) {
  if (text == "auto") return ColorEncoding::Auto;
  if (text == "srgb") return ColorEncoding::Srgb;
  if (text == "linear") return ColorEncoding::Linear;
  throw InvalidArgument("--color-encoding", -1, -1, "'" + text + "' is not auto, srgb or linear");
}

DepthConvention parse_convention(const std::string& text) {
  if (text == "linear") return DepthConvention::Linear;
  if (text == "normalized") return DepthConvention::Normalized;
  if (text == "inverse") return DepthConvention::Inverse;
  throw InvalidArgument("--depth-convention", -1, -1,
                        "'" + text + "' is not linear, normalized or inverse");
}

// A false-colour view of the CoC: red for the far field, blue for the near field, black where
// sharp; full brightness at the largest |CoC| of the frame.
Image coc_picture(ConstPlane coc) {
  float largest = 1e-6f;
  for (std::ptrdiff_t y = 0; y < coc.height(); ++y)
    for (std::ptrdiff_t x = 0; x < coc.width(); ++x) largest = std::max(largest, std::abs(coc(x, y)));
  Image picture(coc.width(), coc.height(), 3);
  for (std::ptrdiff_t y = 0; y < coc.height(); ++y)
    for (std::ptrdiff_t x = 0; x < coc.width(); ++x) {
      const float v = coc(x, y) / largest;
      picture(x, y, 0) = std::max(v, 0.f);
      picture(x, y, 1) = 0.25f * std::abs(v);
      picture(x, y, 2) = std::max(-v, 0.f);
    }
  return picture;
}

// A progress bar on stderr, only when stderr is a terminal.
std::function<void(double)> progress_bar() {
  if (!isatty(STDERR_FILENO)) return {};
  return [last = -1](double done) mutable {
    const int percent = int(done * 100);
    if (percent == last) return;
    last = percent;
    const int filled = percent * 30 / 100;
    std::fprintf(stderr, "\r[%s%s] %3d%%", std::string(filled, '#').c_str(),
                 std::string(30 - filled, ' ').c_str(), percent);
    if (percent >= 100) std::fprintf(stderr, "\n");
  };
}

void write_text_atomically(const std::string& path, const std::string& text) {
  const std::string temporary = path + ".tmp-" + std::to_string(getpid());
  {
    std::ofstream out(temporary);
    out << text;
    if (!out.flush()) {
      std::filesystem::remove(temporary);
      throw ImageIoError("tridiff: " + path + ": cannot write the report");
    }
  }
  std::filesystem::rename(temporary, path);
}

std::string default_coc_path(const std::string& output) {
  std::filesystem::path p(output);
  return (p.parent_path() / (p.stem().string() + "_coc.png")).string();
}

int run_dof(const Arguments& args) {
  const auto start = std::chrono::steady_clock::now();
  auto seconds = [](auto from) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - from).count();
  };
  const int threads = args.integer("threads", 0);
  const DofMethod& method = find_dof_method(args.text("method", "adi"));  // fail before work

  // Input: files, or the built-in scene.
  Image color, depth;
  ThinLens lens;
  std::string source;
  const auto load_start = std::chrono::steady_clock::now();
  if (args.has("color")) {
    if (!args.has("depth")) throw InvalidArgument("--depth", -1, -1, "is required with --color");
    color = read_color(args.text("color", ""), parse_encoding(args.text("color-encoding", "auto"))).pixels;
    DepthOptions depth_options;
    depth_options.channel = args.text("depth-channel", "");
    depth_options.convention = parse_convention(args.text("depth-convention", "linear"));
    depth_options.near_plane = args.number("near", 0.f);
    depth_options.far_plane = args.number("far", 0.f);
    depth = read_depth(args.text("depth", ""), depth_options);
    if (depth.width() != color.width() || depth.height() != color.height())
      throw ImageIoError("tridiff: " + args.text("depth", "") + ": depth is " +
                         std::to_string(depth.width()) + " x " + std::to_string(depth.height()) +
                         " but the colour image " + args.text("color", "") + " is " +
                         std::to_string(color.width()) + " x " + std::to_string(color.height()));
    source = args.text("color", "") + " + " + args.text("depth", "");
  } else {
    if (args.has("depth")) throw InvalidArgument("--color", -1, -1, "is required with --depth");
    const int width = args.integer("width", 1920), height = args.integer("height", 1080);
    if (width < 1 || height < 1 || width > 16384 || height > 16384)
      throw InvalidArgument("--width/--height", -1, -1, "must be in [1, 16384]");
    Scene scene = procedural_scene(width, height, threads);
    color = std::move(scene.color);
    depth = std::move(scene.depth);
    lens = scene.lens;
    source = "built-in scene " + std::to_string(width) + " x " + std::to_string(height);
  }
  const double load_seconds = seconds(load_start);

  // CoC: the thin lens, or the artist curve when any of its options is given.
  const auto coc_start = std::chrono::steady_clock::now();
  Image coc(color.width(), color.height(), 1);
  const bool curve = args.has("near-start") || args.has("near-end") || args.has("near-radius") ||
                     args.has("far-start") || args.has("far-end") || args.has("far-radius");
  std::ostringstream model;
  if (curve) {
    ArtistCurve c;
    c.near_start_m = args.number("near-start", 0);
    c.near_end_m = args.number("near-end", 0);
    c.near_radius_px = args.number("near-radius", 0);
    c.far_start_m = args.number("far-start", 0);
    c.far_end_m = args.number("far-end", 0);
    c.far_radius_px = args.number("far-radius", 0);
    coc_artist_curve(coc.plane(0), depth.plane(0), c, threads);
    model << "artist curve: near " << c.near_start_m << "-" << c.near_end_m << " m radius "
          << c.near_radius_px << " px, far " << c.far_start_m << "-" << c.far_end_m
          << " m radius " << c.far_radius_px << " px";
  } else {
    lens.focus_distance_m = args.number("focus", lens.focus_distance_m);
    lens.f_number = args.number("f-number", lens.f_number);
    lens.focal_length_mm = args.number("focal-length", lens.focal_length_mm);
    lens.sensor_width_mm = args.number("sensor-width", lens.sensor_width_mm);
    lens.max_coc_px = args.number("max-coc", lens.max_coc_px);
    coc_thin_lens(coc.plane(0), depth.plane(0), lens, threads);
    model << "thin lens: focus " << lens.focus_distance_m << " m, f/" << lens.f_number << ", "
          << lens.focal_length_mm << " mm, sensor " << lens.sensor_width_mm << " mm, max CoC "
          << lens.max_coc_px << " px";
  }
  const double coc_seconds = seconds(coc_start);

  DofSettings settings;
  settings.threads = threads;
  settings.layers = args.flag("layers");
  settings.skip_in_focus = !args.flag("no-skip");
  settings.in_focus_coc_px = args.number("in-focus", 1.f);
  settings.progress = progress_bar();
  DofReport report;
  Image result;
  const auto method_start = std::chrono::steady_clock::now();
  method.run(result, color, coc.plane(0), settings, report);
  const double method_seconds = seconds(method_start);

  const std::string output = args.text("output", "tridiff_dof.png");
  const std::string coc_output = args.text("coc-output", default_coc_path(output));
  const auto write_start = std::chrono::steady_clock::now();
  write_image(output, result);
  write_image(coc_output, coc_picture(coc.plane(0)), ColorEncoding::Linear);
  if (args.has("input-output")) write_image(args.text("input-output", ""), color);
  const double write_seconds = seconds(write_start);

  std::ostringstream text, json;
  text << "tridiff dof: " << source << "\n"
       << "  method   " << method.name << (report.layered ? " (layered)" : "") << "\n"
       << "  coc      " << model.str() << "\n"
       << "  skipped  " << 100.0 * report.skipped_fraction << " % of the per-pixel work\n";
  if (report.explicit_steps) text << "  steps    " << report.explicit_steps << " explicit steps\n";
  text << "  time     input " << load_seconds * 1e3 << " ms, coc " << coc_seconds * 1e3 << " ms, ";
  for (const DofStage& stage : report.stages) text << stage.name << " " << stage.seconds * 1e3 << " ms, ";
  text << "write " << write_seconds * 1e3 << " ms, total " << seconds(start) * 1e3 << " ms\n"
       << "  wrote    " << output << ", " << coc_output << "\n";
  std::fputs(text.str().c_str(), stdout);

  if (args.has("report")) {
    json << "{\n  \"source\": \"" << source << "\",\n  \"method\": \"" << method.name
         << "\",\n  \"layered\": " << (report.layered ? "true" : "false")
         << ",\n  \"coc_model\": \"" << model.str() << "\",\n  \"skipped_fraction\": "
         << report.skipped_fraction << ",\n  \"explicit_steps\": " << report.explicit_steps
         << ",\n  \"seconds\": {\"input\": " << load_seconds << ", \"coc\": " << coc_seconds;
    for (const DofStage& stage : report.stages) json << ", \"" << stage.name << "\": " << stage.seconds;
    json << ", \"method\": " << method_seconds << ", \"write\": " << write_seconds << "}\n}\n";
    write_text_atomically(args.text("report", ""), json.str());
  }
  return 0;
}

int list_methods() {
  std::printf("%-8s %-10s %-10s %-36s %s\n", "name", "near blur", "any size", "cost", "summary");
  for (const DofMethod& m : dof_methods())
    std::printf("%-8.*s %-10s %-10s %-36.*s %.*s\n", int(m.name.size()), m.name.data(),
                m.blurs_foreground ? "yes" : "layers", m.unbounded_blur ? "yes" : "no",
                int(m.cost.size()), m.cost.data(), int(m.summary.size()), m.summary.data());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const std::string command = argc > 1 ? argv[1] : "--help";
    if (command == "--help" || command == "-h" || command == "help") {
      std::fputs(kUsage, stdout);
      return argc > 1 ? 0 : 2;
    }
    if (command == "methods") return list_methods();
    if (command != "dof")
      throw InvalidArgument(command, -1, -1, "unknown command (expected dof or methods)");
    const Arguments args = parse(argc, argv, 2);
    if (args.flag("help")) {
      std::fputs(kUsage, stdout);
      return 0;
    }
    return run_dof(args);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "%s\n", error.what());
    return 1;
  }
}
