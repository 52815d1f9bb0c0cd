// The `tridiff` command: depth of field from a colour image and a depth map (or from the
// built-in procedural scene), with any registered method.
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "common.hpp"
#include "lens_character.hpp"
#include "tridiff/dof/method.hpp"
#include "tridiff/dof/views.hpp"
#include "tridiff/image/io.hpp"
#include "tridiff/image/output_files.hpp"

namespace {

using namespace tridiff;

constexpr const char* kUsageHead =
    R"(usage: tridiff dof [options]      depth of field (built-in scene when --color is absent)
       tridiff ipf [options]      the Inverse Post Filter hardware model (tridiff ipf --help)
       tridiff methods            list the depth-of-field methods
       tridiff --help

)";
constexpr const char* kDofUsage = R"(method
  --method NAME             bokeh (default: adi's diffusion for the body, out-of-focus
                            highlights as aperture-shaped sprites); every method: `tridiff
                            methods`; `auto`
                            picks the cheapest whose measured error meets --psnr-budget
  --psnr-budget DB          auto: the least PSNR against the table's references: the thin-lens
                            truth of the ray-traced scenes, scatter on the others (default 30)
  --layers                  blur the near field as its own layer, so that it spreads over what
                            lies behind it (default for the methods that have layers; a method
                            without them refuses --layers)
  --no-layers               the methods with layers without them
  --in-focus PX             |CoC| below this is sharp and skipped (default 1)
  --no-skip                 process in-focus parts too (reference; same result, slower)
  --threads N               0 = all cores (default), at most 1024
output
  -o, --output FILE         result image (default tridiff_dof.png): .png .jpg .tif (16-bit)
                            .exr (half) .hdr (RGBE: RGB, alpha left out); not .pfm (no writer)
  --float                   OpenEXR outputs in 32-bit float, every value kept (default half:
                            11 significant bits, float anyway past half's 65504)
  --view V                  write to --output a picture of what the method sees instead of
                            the result (the method does not run):
                              coc          the signed CoC: blue near, red far, black sharp
                              focal-plane  blue near, green in focus, red far (--in-focus)
                              layers       white: the near layer that --layers blurs apart
                              tiles        the input, the tiles skipped as in focus darkened
  --coc-output FILE         CoC map (default: <output stem>_coc.png): in .exr the signed
                            diameter in pixels, one channel; else a false-colour picture;
                            `none` writes none
  --input-output FILE       also write the input colour (useful with the built-in scene)
  --report FILE             the report as JSON as well as on stdout
)";
constexpr const char* kOutputPolicy = R"(
Outputs are checked before the work and written whole or not at all: each to a new file
beside its target, renamed into place once every output is written; if one fails, none
changes. They must be regular files (or not exist yet): a device (/dev/null), a FIFO, a
socket, a folder, an input file or the file standard output is redirected to is refused.
)";

// The default method: closest to the thin-lens truth of the built-in scenes among the fast ones
// (README, Results).
constexpr std::string_view kDefaultMethod = "bokeh";

const std::vector<std::string> kDofFlags = {"layers", "no-layers", "no-skip", "help", "float"};
const std::vector<std::string> kDofOptions = {"method",     "in-focus",     "psnr-budget", "output",
                                              "coc-output", "input-output", "report",      "view"};

void print_dof_usage() {
  std::fputs(kUsageHead, stdout);
  std::fputs(cli::kInputUsage, stdout);
  std::fputs(kDofUsage, stdout);
  std::fputs(cli::kLensCharacterUsage, stdout);
  std::fputs(kOutputPolicy, stdout);
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

namespace fs = std::filesystem;

// `text` as a JSON string literal.
std::string json_string(const std::string& text) {
  std::string quoted = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') {
      quoted += '\\';
      quoted += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\u%04x", c);
      quoted += escaped;
    } else {
      quoted += c;
    }
  }
  return quoted + "\"";
}

std::string lowercase_extension(const std::string& path) {
  std::string extension = fs::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  return extension;
}

// The CoC map as an image: in a float format (OpenEXR) the signed diameter in pixels itself,
// one channel; otherwise the false-colour picture.
Image coc_output_image(const std::string& path, ConstPlane coc) {
  if (lowercase_extension(path) != ".exr") return coc_view(coc);
  Image values(coc.width(), coc.height(), 1);
  for (std::ptrdiff_t y = 0; y < coc.height(); ++y)
    std::copy(coc.row(y), coc.row(y) + coc.width(), values.plane(0).row(y));
  return values;
}

// The lens in use, and the values of it that are tridiff's defaults rather than the user's.
std::string lens_line(const cli::Frame& frame) {
  std::string line = frame.lens;
  if (frame.lens_defaults.empty()) return line;
  line += " (defaults: ";
  for (std::size_t i = 0; i < frame.lens_defaults.size(); ++i)
    line += (i ? ", " : "") + frame.lens_defaults[i];
  return line + "; give them for your camera)";
}

std::string default_coc_path(const std::string& output) {
  std::filesystem::path p(output);
  return (p.parent_path() / (p.stem().string() + "_coc.png")).string();
}

// What a `tridiff dof` command line asks for, checked before any input is read.
struct DofPlan {
  int threads = 0;
  const DofMethod* method = nullptr;
  std::string output, coc_output;  // coc_output empty: not written
  DofOptions settings;
  std::optional<DofView> view;  // a picture of what the method sees instead of its result
  bool float32 = false;         // --float
  OutputFiles files;
};

// What --view writes, for the summary.
const char* view_legend(DofView view) {
  switch (view) {
    case DofView::coc: return "coc: the signed CoC, blue near, red far, black sharp";
    case DofView::focal_plane: return "focal-plane: blue near, green in focus, red far";
    case DofView::layers: return "layers: white the near layer, black the background";
    case DofView::tiles: return "tiles: the input, the tiles skipped as in focus darkened";
  }
  return "";
}

// --float asks for 32-bit OpenEXR: refused when no output is OpenEXR, where it would do nothing.
void check_float_applies(const cli::Arguments& args, const DofPlan& plan) {
  if (!plan.float32) return;
  for (const std::string& path :
       {plan.output, plan.coc_output, args.text("input-output", std::string())})
    if (lowercase_extension(path) == ".exr") return;
  throw InvalidArgument("--float", "no output is OpenEXR (.exr), the one format it applies to");
}

DofPlan plan_dof(const cli::Arguments& args) {
  DofPlan plan;
  plan.threads = cli::thread_count(args);
  plan.method = &find_dof_method(args.text("method", std::string(kDefaultMethod)));
  plan.settings.threads = plan.threads;
  // Layers are on by default where a method has them: against the thin-lens truth they gain
  // 0.6-1.0 dB on the built-in scenes for adi and bokeh (README, Results).
  if (args.flag("layers") && args.flag("no-layers"))
    throw InvalidArgument("--no-layers", "contradicts --layers");
  plan.settings.layers =
      args.flag("layers") || (!args.flag("no-layers") && plan.method->honours_layers);
  plan.settings.skip_in_focus = !args.flag("no-skip");
  plan.settings.in_focus_coc_px = args.number("in-focus", 1.f);
  plan.settings.error_budget_psnr = args.number("psnr-budget", 30.f);
  if (args.has("view"))
    cli::with_fields_as_options({"view"},
                                [&] { plan.view = dof_view_named(args.text("view", "")); });
  plan.float32 = args.flag("float");
  plan.output = args.text("output", "tridiff_dof.png");
  plan.coc_output = args.text("coc-output", default_coc_path(plan.output));
  if (plan.coc_output == "none") plan.coc_output.clear();
  cli::register_inputs(args, plan.files);
  cli::plan_lens_character(args, plan.settings, plan.files);
  const auto claim_image = [&](const std::string& option, const std::string& path) {
    try {
      check_image_path(path);              // a format that can be written
    } catch (const ImageIoError& error) {  // "tridiff: PATH: ..." with the option named
      const std::string message = error.what(), prefix = "tridiff: ";
      throw ImageIoError(prefix + option + ": " +
                         (message.rfind(prefix, 0) == 0 ? message.substr(prefix.size()) : message));
    }
    plan.files.claim(option, path);
  };
  claim_image("--output", plan.output);
  if (!plan.coc_output.empty()) claim_image("--coc-output", plan.coc_output);
  if (args.has("input-output")) claim_image("--input-output", args.text("input-output", ""));
  if (args.has("report")) plan.files.claim("--report", args.text("report", ""));
  check_float_applies(args, plan);
  return plan;
}

int run_dof(const cli::Arguments& args) {
  const auto start = std::chrono::steady_clock::now();
  auto seconds = [](auto from) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - from).count();
  };
  DofPlan plan = plan_dof(args);  // every option and output path checked before the work
  const DofMethod& method = *plan.method;
  OutputFiles& outputs = plan.files;

  cli::load_aperture_image(args, plan.settings, plan.threads);
  cli::Frame frame = cli::load_frame(args, plan.threads);
  const Image& color = frame.color;
  const Image& coc = frame.coc;
  const std::string& source = frame.source;
  const double load_seconds = frame.load_seconds, coc_seconds = frame.coc_seconds;

  DofOptions settings = plan.settings;
  settings.progress = progress_bar();
  DofReport report;
  // A method that works in place (adi) blurs the frame where it lies: the tiles in focus are
  // not even copied. The input is kept apart only when it is written out as well.
  const bool in_place = method.in_place && !args.has("input-output");
  Image separate_result;
  Image& result = in_place ? frame.color : separate_result;
  const auto method_start = std::chrono::steady_clock::now();
  Image view_picture;
  if (plan.view)
    view_picture = dof_view(*plan.view, color, coc.plane(0), settings);
  else
    cli::with_coc_named(args, [&] {
      cli::with_lens_character_named(
          [&] { report = depth_of_field(result, color, coc.plane(0), method, settings); });
    });
  const double method_seconds = seconds(method_start);

  const auto write_start = std::chrono::steady_clock::now();
  // The colour outputs' options, with the threads encode_and_stage gives each.
  const auto write = [&](int threads) {
    return WriteOptions{.threads = threads, .float32 = plan.float32};
  };
  std::vector<cli::Encoding> encodings;
  encodings.push_back({"--output", [&](int threads) {
                         return encode_image(plan.output, plan.view ? view_picture : result,
                                             write(threads));
                       }});
  if (!plan.coc_output.empty())
    encodings.push_back(
        {"--coc-output", [&](int threads) {
           return encode_image(
               plan.coc_output, coc_output_image(plan.coc_output, coc.plane(0)),
               {.encoding = ColorEncoding::Linear, .threads = threads, .float32 = plan.float32});
         }});
  if (args.has("input-output"))
    encodings.push_back({"--input-output", [&](int threads) {
                           return encode_image(args.text("input-output", ""), color,
                                               write(threads));
                         }});
  cli::encode_and_stage(encodings, plan.threads, outputs);
  const double write_seconds = seconds(write_start);

  std::ostringstream text, json;
  text << "tridiff dof: " << source << "\n";
  if (plan.view)
    text << "  view     " << view_legend(*plan.view) << " (no depth of field computed)\n";
  else
    text << "  method   " << method.name
         << (report.chosen_method.empty() ? "" : " -> " + report.chosen_method)
         << (report.layered ? " (layered)" : "") << "\n";
  text << "  coc      " << frame.coc_model << "\n";
  if (args.has("color") && !frame.lens.empty()) text << "  lens     " << lens_line(frame) << "\n";
  if (!plan.view)
    text << "  skipped  " << 100.0 * report.skipped_fraction << " % of the per-pixel work\n";
  if (report.explicit_steps) text << "  steps    " << report.explicit_steps << " explicit steps\n";
  text << "  time     input " << load_seconds * 1e3 << " ms, coc " << coc_seconds * 1e3 << " ms, ";
  for (const DofStage& stage : report.stages)
    text << stage.name << " " << stage.seconds * 1e3 << " ms, ";
  text << "write " << write_seconds * 1e3 << " ms, total " << seconds(start) * 1e3 << " ms\n"
       << "  wrote    " << plan.output << (plan.coc_output.empty() ? "" : ", " + plan.coc_output)
       << "\n";
  if (!report.notes.empty()) text << "  notes    " << report.notes << "\n";

  if (args.has("report")) {
    json << "{\n  \"source\": " << json_string(source)
         << ",\n  \"method\": " << json_string(std::string(method.name))
         << ",\n  \"chosen_method\": " << json_string(report.chosen_method)
         << ",\n  \"layered\": " << (report.layered ? "true" : "false")
         << ",\n  \"view\": " << json_string(args.text("view", ""))
         << ",\n  \"coc_model\": " << json_string(frame.coc_model)
         << ",\n  \"lens\": " << json_string(frame.lens) << ",\n  \"lens_defaults\": [";
    for (std::size_t i = 0; i < frame.lens_defaults.size(); ++i)
      json << (i ? ", " : "") << json_string(frame.lens_defaults[i]);
    json << "]"
         << ",\n  \"skipped_fraction\": " << report.skipped_fraction
         << ",\n  \"explicit_steps\": " << report.explicit_steps
         << ",\n  \"seconds\": {\"input\": " << load_seconds << ", \"coc\": " << coc_seconds;
    for (const DofStage& stage : report.stages)
      json << ", " << json_string(stage.name) << ": " << stage.seconds;
    json << ", \"method\": " << method_seconds << ", \"write\": " << write_seconds << "}\n}\n";
    outputs.stage("--report", json.str());
  }
  outputs.commit();
  std::fputs(text.str().c_str(), stdout);
  return 0;
}

int list_methods() {
  std::printf("%-8s %-10s %-10s %-36s %s\n", "name", "near blur", "any size", "cost", "summary");
  for (const DofMethod& m : dof_methods())
    std::printf("%-8.*s %-10s %-10s %-36.*s %.*s\n", int(m.name.size()), m.name.data(),
                m.blurs_foreground ? "yes"
                : m.honours_layers ? "layers"
                                   : "no",
                m.unbounded_blur ? "yes" : "no", int(m.cost.size()), m.cost.data(),
                int(m.summary.size()), m.summary.data());
  return 0;
}

// The options of `tridiff dof`: the input and lens options, then its own.
std::vector<std::string> dof_valued_options() {
  std::vector<std::string> valued = cli::kInputOptions;
  valued.insert(valued.end(), kDofOptions.begin(), kDofOptions.end());
  valued.insert(valued.end(), cli::kLensCharacterOptions.begin(), cli::kLensCharacterOptions.end());
  return valued;
}

// `tridiff methods` and `tridiff --help` take nothing after them.
void refuse_arguments_after(int argc, char** argv) {
  if (argc > 2)
    throw InvalidArgument(argv[2], std::string("unexpected argument after '") + argv[1] + "'");
}

}  // namespace

namespace tridiff::cli {

CommandLine parse_command_line(int argc, char** argv) {
  if (argc < 2) throw InvalidArgument("command", "missing (dof, ipf, methods or --help)");
  CommandLine line{argv[1], {}};
  if (line.command == "-h" || line.command == "help") line.command = "--help";
  if (line.command == "--help" || line.command == "methods") {
    refuse_arguments_after(argc, argv);
  } else if (line.command == "ipf") {
    line.args = parse(argc, argv, 2, kIpfFlags, kIpfValued);
  } else if (line.command == "dof") {
    line.args = parse(argc, argv, 2, kDofFlags, dof_valued_options());
  } else {
    throw InvalidArgument(line.command, "unknown command (expected dof, ipf or methods)");
  }
  return line;
}

void check_command_line(int argc, char** argv) {
  const CommandLine line = parse_command_line(argc, argv);
  if (line.args.flag("help")) return;
  if (line.command == "dof") {
    plan_dof(line.args);
    check_input_options(line.args);
  }
  if (line.command == "ipf") check_ipf(line.args);
}

int run_command_line(int argc, char** argv) {
  if (argc < 2) {  // a bare `tridiff`: how to use it, as an error
    std::fputs(kUsageHead, stderr);
    return 2;
  }
  const CommandLine line = parse_command_line(argc, argv);
  if (line.command == "--help" || (line.command == "dof" && line.args.flag("help"))) {
    print_dof_usage();
    return 0;
  }
  if (line.command == "methods") return list_methods();
  if (line.command == "ipf") {
    if (line.args.flag("help")) {
      std::fputs(kIpfUsage, stdout);
      std::fputs(kInputUsage, stdout);
      std::fputs(kOutputPolicy, stdout);
      return 0;
    }
    return run_ipf(line.args);
  }
  return run_dof(line.args);
}

}  // namespace tridiff::cli
