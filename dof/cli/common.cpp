// Option parsing and frame loading shared by `tridiff dof` and `tridiff ipf`.
#include "common.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <functional>
#include <sstream>
#include <type_traits>

#include "tridiff/dof/lens.hpp"
#include "tridiff/dof/scene.hpp"
#include "tridiff/image/io.hpp"
#include "tridiff/threads.hpp"

namespace tridiff::cli {

bool Arguments::flag(const std::string& key) const {
  return std::find(flags.begin(), flags.end(), key) != flags.end();
}

std::string Arguments::text(const std::string& key, const std::string& fallback) const {
  auto it = values.find(key);
  return it == values.end() ? fallback : it->second;
}

float Arguments::number(const std::string& key, float fallback) const {
  auto it = values.find(key);
  if (it == values.end()) return fallback;
  char* end = nullptr;
  const float value = std::strtof(it->second.c_str(), &end);
  if (end == it->second.c_str() || *end != '\0' || !std::isfinite(value))
    throw InvalidArgument("--" + key, "'" + it->second + "' is not a number");
  return value;
}

int Arguments::integer(const std::string& key, int fallback) const {
  const float value = number(key, float(fallback));
  if (value != std::floor(value)) throw InvalidArgument("--" + key, "must be an integer");
  // Converting a float beyond int's range is undefined: refuse it first.
  constexpr float kLimit = 2147483648.f;  // 2^31
  if (!(value >= -kLimit && value < kLimit))
    throw InvalidArgument("--" + key, "'" + text(key, "") + "' is out of range");
  return int(value);
}

const std::vector<std::string> kInputOptions = {
    "color",    "depth",          "depth-channel", "depth-convention", "near",
    "far",      "color-encoding", "width",         "height",           "focus",
    "f-number", "focal-length",   "sensor-width",  "max-coc",          "near-start",
    "near-end", "near-radius",    "far-start",     "far-end",          "far-radius",
    "threads",  "max-pixels",     "focus-at",      "focus-range"};

const char* const kInputUsage = R"(input
  --color FILE              colour image (PNG, JPEG, TIFF, OpenEXR, ...)
  --depth FILE              depth map; may be the colour file itself (an EXR with a Z channel)
  --depth-channel NAME      channel holding depth (default: Z, else depth, else the only
                            channel, or the first of a grey image stored as RGB)
  --depth-convention C      linear (distance, default) | normalized (needs --near, --far) | inverse
  --near M, --far M         planes for the normalized convention, metres
  --color-encoding E        auto (default: 8/16-bit sRGB, float linear) | srgb | linear
  --width W, --height H     size of the built-in scene (default 1920 x 1080; not with --color)
  --max-pixels N            larger input images are refused before they are read
                            (default 268435456, 16384 x 16384)
lens (thin lens, seed 000 eq. 3.2; with --color the summary names the values left at
      these defaults, which are not your camera's)
  --focus M                 focus distance, metres (default 3.2; built-in scene: 3.95, its sphere)
  --focus-at X,Y            focus at the depth of pixel (X, Y) (0,0 top left): the median of
                            the valid depths in the 5 x 5 pixels around it, so that a pixel
                            on an edge focuses on its own side (not with --focus)
  --focus-range NEAR,FAR    everything from NEAR to FAR metres is sharp; nearer blurs as if
                            focused at NEAR, farther as if focused at FAR (not with --focus
                            or --focus-at)
  --f-number N              aperture f-number (default 2.8; built-in scene: 1.8)
  --focal-length MM         focal length (default 50)
  --sensor-width MM         sensor width the image spans (default 36)
  --max-coc PX              clamp of the lens's CoC diameter (default 64; the artist
                            curve's radii are its own bound)
artist curve (seed 002 §28.5.3; replaces the lens, so not with the lens options above)
  --near-start M --near-end M --near-radius PX   near blur: radius at near-start, 0 from near-end
  --far-start M --far-end M --far-radius PX      far blur: 0 up to far-start, radius from far-end
                            a region with a radius needs end > start; radius 0 turns it off
)";

Arguments parse(int argc, char** argv, int first, const std::vector<std::string>& flags,
                const std::vector<std::string>& valued) {
  Arguments args;
  for (int i = first; i < argc; ++i) {
    std::string key = argv[i];
    if (key == "-o") key = "--output";
    if (key == "-h") key = "--help";
    if (key.rfind("--", 0) != 0) throw InvalidArgument(key, "unexpected argument");
    key = key.substr(2);
    // Given twice, one of the two would be ignored: refused, whichever it is.
    const std::string alias = key == "output" ? " (-o and --output are one option)"
                              : key == "help" ? " (-h and --help are one option)"
                                              : "";
    if (std::find(flags.begin(), flags.end(), key) != flags.end()) {
      if (args.flag(key)) throw InvalidArgument("--" + key, "is given twice" + alias);
      args.flags.push_back(key);
      continue;
    }
    if (std::find(valued.begin(), valued.end(), key) == valued.end())
      throw InvalidArgument("--" + key, "unknown option (see tridiff --help)");
    if (i + 1 >= argc) throw InvalidArgument("--" + key, "needs a value");
    if (args.has(key))
      throw InvalidArgument("--" + key, "is given twice ('" + args.text(key, "") + "' and '" +
                                            argv[i + 1] + "')" + alias);
    args.values[key] = argv[++i];
  }
  return args;
}

namespace {

ColorEncoding parse_encoding(const std::string& text) {
  if (text == "auto") return ColorEncoding::Auto;
  if (text == "srgb") return ColorEncoding::Srgb;
  if (text == "linear") return ColorEncoding::Linear;
  throw InvalidArgument("--color-encoding", "'" + text + "' is not auto, srgb or linear");
}

DepthConvention parse_convention(const std::string& text) {
  if (text == "linear") return DepthConvention::Linear;
  if (text == "normalized") return DepthConvention::Normalized;
  if (text == "inverse") return DepthConvention::Inverse;
  throw InvalidArgument("--depth-convention",
                        "'" + text + "' is not linear, normalized or inverse");
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// body(), with this process's stderr sent to /dev/null meanwhile: libpng prints its own
// "libpng error: ..." line before OpenImageIO hands the same text to tridiff's message.
template <class Body>
auto with_stderr_muted(Body&& body) {
  std::fflush(stderr);
  struct Restore {
    int saved = ::dup(STDERR_FILENO);
    Restore() {
      const int null = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
      if (saved >= 0 && null >= 0) ::dup2(null, STDERR_FILENO);
      if (null >= 0) ::close(null);
    }
    ~Restore() {
      if (saved < 0) return;
      std::fflush(stderr);
      ::dup2(saved, STDERR_FILENO);
      ::close(saved);
    }
  } restore;
  return body();
}

// Colour and depth from files, or the built-in scene (whose lens replaces the default one).
void load_images(const Arguments& args, int threads, Frame& frame, ThinLens& lens) {
  if (args.has("color")) {
    if (!args.has("depth")) throw InvalidArgument("--depth", "is required with --color");
    const ColorEncoding encoding = parse_encoding(args.text("color-encoding", "auto"));
    frame.color = with_stderr_muted([&] {
                    return read_color(
                        args.text("color", ""),
                        {.encoding = encoding, .max_pixels = max_pixels(args), .threads = threads});
                  }).pixels;
    DepthOptions depth_options;
    depth_options.channel = args.text("depth-channel", "");
    depth_options.convention = parse_convention(args.text("depth-convention", "linear"));
    depth_options.near_plane = args.number("near", 0.f);
    depth_options.far_plane = args.number("far", 0.f);
    depth_options.max_pixels = max_pixels(args);
    frame.depth =
        with_stderr_muted([&] { return read_depth(args.text("depth", ""), depth_options); });
    if (frame.depth.width() != frame.color.width() || frame.depth.height() != frame.color.height())
      throw ImageIoError("tridiff: " + args.text("depth", "") + ": depth is " +
                         std::to_string(frame.depth.width()) + " x " +
                         std::to_string(frame.depth.height()) + " but the colour image " +
                         args.text("color", "") + " is " + std::to_string(frame.color.width()) +
                         " x " + std::to_string(frame.color.height()));
    frame.source = args.text("color", "") + " + " + args.text("depth", "");
    return;
  }
  if (args.has("depth")) throw InvalidArgument("--color", "is required with --depth");
  const int width = args.integer("width", 1920), height = args.integer("height", 1080);
  if (width < 1 || height < 1 || width > 16384 || height > 16384)
    throw InvalidArgument("--width/--height", "must be in [1, 16384]");
  Scene scene = procedural_scene(width, height, threads);
  frame.color = std::move(scene.color);
  frame.depth = std::move(scene.depth);
  lens = scene.lens;
  frame.source = "built-in scene " + std::to_string(width) + " x " + std::to_string(height);
}

std::string kebab(std::string name) {
  std::replace(name.begin(), name.end(), '_', '-');
  return name;
}

std::string snake(std::string name) {
  std::replace(name.begin(), name.end(), '-', '_');
  return name;
}

// with_fields_as_options over the input options (lens, curve, files).
void with_options_named(const std::function<void()>& work) {
  with_fields_as_options(kInputOptions, work);
}

const std::vector<std::string> kLensOptions = {
    "focus", "focus-at", "focus-range", "f-number", "focal-length", "sensor-width", "max-coc"};
// The options that say where the lens focuses: one at most.
const std::vector<std::string> kFocusOptions = {"focus", "focus-at", "focus-range"};
const std::vector<std::string> kCurveOptions = {"near-start", "near-end",    "far-start",
                                                "far-end",    "near-radius", "far-radius"};

// The first of `keys` on the command line, or "".
std::string first_given(const Arguments& args, const std::vector<std::string>& keys) {
  for (const std::string& key : keys)
    if (args.has(key)) return key;
  return "";
}

ArtistCurve artist_curve(const Arguments& args) {
  ArtistCurve c;
  c.near_start_m = args.number("near-start", 0);
  c.near_end_m = args.number("near-end", 0);
  c.near_radius_px = args.number("near-radius", 0);
  c.far_start_m = args.number("far-start", 0);
  c.far_end_m = args.number("far-end", 0);
  c.far_radius_px = args.number("far-radius", 0);
  return c;
}

// The two values of an option written "A,B"; InvalidArgument naming --key otherwise.
std::pair<std::string, std::string> value_pair(const Arguments& args, const std::string& key,
                                               const std::string& form) {
  const std::string text = args.text(key, "");
  const auto comma = text.find(',');
  if (comma == std::string::npos || text.find(',', comma + 1) != std::string::npos)
    throw InvalidArgument("--" + key, "'" + text + "' is not " + form);
  return {text.substr(0, comma), text.substr(comma + 1)};
}

// A value of value_pair as a number, through Arguments' own checks, named --key.
template <class Number>
Number pair_part(const std::string& key, const std::string& part, const std::string& whole,
                 const std::string& form) {
  Arguments one;
  one.values[key] = part;
  try {
    if constexpr (std::is_integral_v<Number>)
      return one.integer(key, 0);
    else
      return one.number(key, 0.f);
  } catch (const InvalidArgument&) {
    throw InvalidArgument("--" + key, "'" + whole + "' is not " + form);
  }
}

struct PixelAt {
  int x = 0, y = 0;
};

PixelAt focus_at(const Arguments& args) {
  const std::string form = "X,Y (a pixel, two whole numbers)";
  const auto [x, y] = value_pair(args, "focus-at", form);
  const std::string whole = args.text("focus-at", "");
  return {pair_part<int>("focus-at", x, whole, form), pair_part<int>("focus-at", y, whole, form)};
}

// --focus-range as the lens's range (validated with the lens).
void apply_focus_range(const Arguments& args, ThinLens& lens) {
  const std::string form = "NEAR,FAR (two distances in metres)";
  const auto [near, far] = value_pair(args, "focus-range", form);
  const std::string whole = args.text("focus-range", "");
  lens.focus_near_m = pair_part<float>("focus-range", near, whole, form);
  lens.focus_far_m = pair_part<float>("focus-range", far, whole, form);
}

// The parts of the lens that the user can give, and how the summary names them.
struct LensPart {
  const char* option;
  const char* name;
};

// The lens as a photographer says it, and which of its values are tridiff's defaults rather
// than the user's (only with --color: the built-in scene's lens is the scene's own).
void describe_lens(const Arguments& args, const ThinLens& lens, const std::string& focus_text,
                   Frame& frame) {
  std::ostringstream text;
  text << lens.focal_length_mm << " mm f/" << lens.f_number << " " << focus_text << ", sensor "
       << lens.sensor_width_mm << " mm";
  frame.lens = text.str();
  if (!args.has("color")) return;
  if (first_given(args, kFocusOptions).empty()) frame.lens_defaults.push_back("focus");
  for (const char* option : {"focal-length", "f-number", "sensor-width"})
    if (!args.has(option)) frame.lens_defaults.push_back(option);
}

// Where the thin lens focuses: --focus, the depth at --focus-at's pixel, or --focus-range; the
// words for the summary.
std::string focus_lens(const Arguments& args, const Frame& frame, ThinLens& lens) {
  std::ostringstream text;
  if (args.has("focus-range")) {
    apply_focus_range(args, lens);
    text << "in focus from " << lens.focus_near_m << " to " << lens.focus_far_m << " m";
    return text.str();
  }
  if (args.has("focus-at")) {
    const PixelAt pixel = focus_at(args);
    with_fields_as_options(
        {"focus-at"},
        [&] { lens.focus_distance_m = focus_depth_at(frame.depth.plane(0), pixel.x, pixel.y); },
        {{"pixel", "focus-at"}, {"depth", "focus-at"}});
    text << "focused at " << lens.focus_distance_m << " m (the depth at pixel (" << pixel.x << ", "
         << pixel.y << "), median of " << kFocusWindow << " x " << kFocusWindow << ")";
    return text.str();
  }
  lens.focus_distance_m = args.number("focus", lens.focus_distance_m);
  text << "focused at " << lens.focus_distance_m << " m";
  return text.str();
}

// The thin lens, or the artist curve when any of its options is given.
void compute_coc(const Arguments& args, int threads, ThinLens lens, Frame& frame) {
  frame.coc.reset(frame.color.width(), frame.color.height(), 1);
  const bool curve = !first_given(args, kCurveOptions).empty();
  std::ostringstream model;
  if (curve) {
    const ArtistCurve c = artist_curve(args);
    with_options_named(
        [&] { coc_artist_curve(frame.coc.plane(0), frame.depth.plane(0), c, threads); });
    model << "artist curve: near " << c.near_start_m << "-" << c.near_end_m << " m radius "
          << c.near_radius_px << " px, far " << c.far_start_m << "-" << c.far_end_m << " m radius "
          << c.far_radius_px << " px";
  } else {
    lens.f_number = args.number("f-number", lens.f_number);
    lens.focal_length_mm = args.number("focal-length", lens.focal_length_mm);
    lens.sensor_width_mm = args.number("sensor-width", lens.sensor_width_mm);
    lens.max_coc_px = args.number("max-coc", lens.max_coc_px);
    const std::string focus_text = focus_lens(args, frame, lens);
    with_fields_as_options(
        kInputOptions,
        [&] { coc_thin_lens(frame.coc.plane(0), frame.depth.plane(0), lens, threads); },
        {{"focus_near", "focus-range"}, {"focus_far", "focus-range"}});
    model << "thin lens: ";
    if (args.has("focus-range"))
      model << "in focus " << lens.focus_near_m << "-" << lens.focus_far_m << " m";
    else
      model << "focus " << lens.focus_distance_m << " m";
    model << ", f/" << lens.f_number << ", " << lens.focal_length_mm << " mm, sensor "
          << lens.sensor_width_mm << " mm, max CoC " << lens.max_coc_px << " px";
    describe_lens(args, lens, focus_text, frame);
  }
  frame.coc_model = model.str();
}

// One way to say where the lens focuses, and its value well formed (a pixel inside the frame is
// checked once the depth is read).
void check_focus_options(const Arguments& args) {
  std::string given;
  for (const std::string& key : kFocusOptions) {
    if (!args.has(key)) continue;
    if (!given.empty())
      throw InvalidArgument(
          "--" + key, "cannot go with --" + given + ": both say where the lens focuses; give one");
    given = key;
  }
  if (args.has("focus-at")) focus_at(args);
  if (args.has("focus-range")) {
    ThinLens lens;
    apply_focus_range(args, lens);
    lens.focal_length_mm = args.number("focal-length", lens.focal_length_mm);
    with_fields_as_options(kInputOptions, [&] { validate(lens); },
                           {{"focus_near", "focus-range"}, {"focus_far", "focus-range"}});
  }
}

}  // namespace

void check_input_options(const Arguments& args) {
  if (args.has("color"))
    for (const char* key : {"width", "height"})
      if (args.has(key))
        throw InvalidArgument("--" + std::string(key),
                              "sizes the built-in scene and cannot be used with --color (the "
                              "image has its own size)");
  check_focus_options(args);
  const std::string curve = first_given(args, kCurveOptions);
  if (curve.empty()) return;
  const std::string lens = first_given(args, kLensOptions);
  if (!lens.empty())
    throw InvalidArgument("--" + lens,
                          "is a thin-lens option, but --" + curve +
                              " chooses the artist curve, which replaces the lens: give one "
                              "or the other");
  with_options_named([&] { validate(artist_curve(args)); });
}

void with_fields_as_options(const std::vector<std::string>& options,
                            const std::function<void()>& work,
                            const std::vector<std::pair<std::string, std::string>>& aliases) {
  try {
    work();
  } catch (const InvalidArgument& error) {
    std::string option = kebab(error.argument());
    for (const auto& [field, alias] : aliases)
      if (error.argument() == field) option = alias;
    if (std::find(options.begin(), options.end(), option) == options.end()) throw;
    // The message may name other fields too ("must be beyond near_start"): as options.
    std::string message = error.message();
    for (const std::string& other : options) {
      const std::string field = snake(other);
      if (field == other) continue;  // one word: the same in prose, left alone
      for (auto at = message.find(field); at != std::string::npos;
           at = message.find(field, at + other.size() + 2))
        message.replace(at, field.size(), "--" + other);
    }
    throw InvalidArgument("--" + option, message);
  }
}

void with_coc_named(const Arguments& args, const std::function<void()>& work) {
  try {
    work();
  } catch (const InvalidArgument& error) {
    // A method refuses the CoC map (too large for it): the map is the one the options made.
    if (error.argument() != "coc") throw;
    if (first_given(args, kCurveOptions).empty())
      throw InvalidArgument("--max-coc",
                            error.message() + " (the lens's CoC, clamped at --max-coc: lower it)");
    std::string options;
    for (const char* key : {"near-radius", "far-radius"})
      if (args.has(key)) options += (options.empty() ? "--" : "/--") + std::string(key);
    if (options.empty()) options = "--near-radius/--far-radius";
    throw InvalidArgument(options, error.message() + " (the artist curve's CoC: lower its radius)");
  }
}

int thread_count(const Arguments& args) {
  const int threads = args.integer("threads", 0);
  with_fields_as_options({"threads"}, [&] { resolve_threads(threads); });
  return threads;
}

std::int64_t max_pixels(const Arguments& args) {
  if (!args.has("max-pixels")) return kDefaultMaxPixels;
  const std::string text = args.text("max-pixels", "");
  char* end = nullptr;
  errno = 0;
  const long long value = std::strtoll(text.c_str(), &end, 10);
  if (end == text.c_str() || *end != '\0' || errno == ERANGE || value < 1)
    throw InvalidArgument("--max-pixels", "'" + text + "' is not a positive whole number");
  return value;
}

void register_inputs(const Arguments& args, OutputFiles& files) {
  if (args.has("color")) files.input("--color", args.text("color", ""));
  if (args.has("depth")) files.input("--depth", args.text("depth", ""));
}

void encode_and_stage(const std::vector<Encoding>& encodings, int threads, OutputFiles& files) {
  const int count = static_cast<int>(encodings.size());
  const int available = resolve_threads(threads);
  const int team = std::max(1, std::min(available, count));
  const int each = std::max(1, available / team);  // threads within one encoding
  if (team == 1) {  // one at a time, each staged before the next is made: one in memory at most
    for (const Encoding& encoding : encodings) files.stage(encoding.label, encoding.encode(each));
    return;
  }
  std::vector<std::vector<unsigned char>> bytes(encodings.size());
  std::vector<std::exception_ptr> errors(encodings.size());
#pragma omp parallel for num_threads(team) schedule(dynamic, 1)
  for (int i = 0; i < count; ++i) {
    try {
      bytes[std::size_t(i)] = encodings[std::size_t(i)].encode(each);
    } catch (...) {
      errors[std::size_t(i)] = std::current_exception();
    }
  }
  for (std::size_t i = 0; i < encodings.size(); ++i) {
    if (errors[i]) std::rethrow_exception(errors[i]);
    files.stage(encodings[i].label, bytes[i]);
  }
}

Frame load_frame(const Arguments& args, int threads) {
  check_input_options(args);  // before any file is read
  Frame frame;
  ThinLens lens;
  const auto load_start = std::chrono::steady_clock::now();
  load_images(args, threads, frame, lens);
  frame.load_seconds = seconds_since(load_start);
  const auto coc_start = std::chrono::steady_clock::now();
  compute_coc(args, threads, lens, frame);
  frame.coc_seconds = seconds_since(coc_start);
  return frame;
}

}  // namespace tridiff::cli
