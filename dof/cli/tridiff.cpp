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
#include <sstream>
#include <string>
#include <vector>

#include "common.hpp"
#include "tridiff/dof/method.hpp"
#include "tridiff/image/io.hpp"

namespace {

using namespace tridiff;

constexpr const char* kUsageHead = R"(usage: tridiff dof [options]      depth of field (built-in scene when --color is absent)
       tridiff ipf [options]      the Inverse Post Filter hardware model (tridiff ipf --help)
       tridiff methods            list the depth-of-field methods
       tridiff --help

)";
constexpr const char* kDofUsage = R"(method
  --method NAME             adi (default); every method: `tridiff methods`; `auto` picks the
                            cheapest whose measured error meets --psnr-budget
  --psnr-budget DB          auto: the least PSNR against the scatter reference (default 30)
  --layers                  blur the near field as its own layer (removes the blocking artifact)
  --in-focus PX             |CoC| below this is sharp and skipped (default 1)
  --no-skip                 process in-focus parts too (reference; same result, slower)
  --threads N               0 = all cores (default)
output
  -o, --output FILE         result image (default tridiff_dof.png)
  --coc-output FILE         CoC map (default: <output stem>_coc.png): in .exr the signed
                            diameter in pixels, one channel; else a false-colour picture
  --input-output FILE       also write the input colour (useful with the built-in scene)
  --report FILE             the report as JSON as well as on stdout
)";

const std::vector<std::string> kDofFlags = {"layers", "no-skip", "help"};
const std::vector<std::string> kDofOptions = {"method", "in-focus", "psnr-budget", "output",
                                              "coc-output", "input-output", "report"};

void print_dof_usage() {
  std::fputs(kUsageHead, stdout);
  std::fputs(cli::kInputUsage, stdout);
  std::fputs(kDofUsage, stdout);
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

namespace fs = std::filesystem;

// The files of one run, written whole or not at all as a set: each is written to a temporary
// file beside its target, and only once every one is written are they renamed into place
// (a rename within a folder needs no space and does not fail half-way). A run that fails
// before commit() leaves no new file behind.
class OutputFiles {
 public:
  OutputFiles() = default;
  OutputFiles(const OutputFiles&) = delete;
  OutputFiles& operator=(const OutputFiles&) = delete;
  ~OutputFiles() {
    std::error_code ignored;
    for (const Staged& file : files_)
      if (!file.committed) fs::remove(file.temporary, ignored);
  }

  // Claims `path` for `option` before any work is done: refuses a path another option
  // already claimed, a folder, a folder that does not exist or cannot be written.
  void claim(const std::string& option, const std::string& path, bool image = true) {
    if (path.empty()) throw InvalidArgument(option, -1, -1, "is empty");
    std::error_code error;
    if (fs::is_directory(path, error))
      throw InvalidArgument(option, -1, -1, "'" + path + "' is a folder");
    const fs::path target = fs::weakly_canonical(fs::absolute(path), error);
    for (const Staged& file : files_)
      if (file.target == target)
        throw InvalidArgument(option, -1, -1, "'" + path + "' is also the " + file.option + " file");
    const fs::path folder = target.parent_path();
    if (!fs::is_directory(folder, error))
      throw InvalidArgument(option, -1, -1, "'" + path + "': the folder " + folder.string() +
                                                " does not exist");
    if (image) check_image_path(path);  // a format OpenImageIO can write
    // The extension stays last: OpenImageIO picks the format from it.
    const fs::path temporary = folder / ("." + target.stem().string() + ".partial-" +
                                         std::to_string(getpid()) + target.extension().string());
    // Writable now, not found out after the work (and nothing created that an interrupted
    // run would leave behind).
    if (access(folder.c_str(), W_OK) != 0)
      throw InvalidArgument(option, -1, -1, "'" + path + "': cannot write in " + folder.string());
    files_.push_back({option, path, target, temporary, false});
  }

  void write_image(const std::string& option, const Image& image,
                   ColorEncoding encoding = ColorEncoding::Auto) {
    const Staged& file = find(option);
    try {
      tridiff::write_image(file.temporary.string(), image, encoding);
    } catch (const ImageIoError& error) {
      // Name the file the user asked for, not the temporary one.
      std::string message = error.what();
      const std::string temporary = file.temporary.string();
      for (auto at = message.find(temporary); at != std::string::npos;
           at = message.find(temporary, at + file.path.size()))
        message.replace(at, temporary.size(), file.path);
      throw ImageIoError(message);
    }
  }

  void write_text(const std::string& option, const std::string& text) {
    const Staged& file = find(option);
    std::ofstream out(file.temporary);
    out << text;
    if (!out.flush()) throw ImageIoError("tridiff: " + file.path + ": cannot write");
  }

  void commit() {
    for (Staged& file : files_) {
      std::error_code error;
      fs::rename(file.temporary, file.target, error);
      if (error)
        throw ImageIoError("tridiff: " + file.path + ": cannot replace the file (" +
                           error.message() + ")");
      file.committed = true;
    }
  }

 private:
  struct Staged {
    std::string option, path;  // as given
    fs::path target, temporary;
    bool committed;
  };
  const Staged& find(const std::string& option) const {
    for (const Staged& file : files_)
      if (file.option == option) return file;
    throw std::logic_error("OutputFiles: " + option + " was not claimed");
  }
  std::vector<Staged> files_;
};

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

// The CoC map as an image: in a float format (OpenEXR) the signed diameter in pixels itself,
// one channel; otherwise the false-colour picture.
Image coc_output_image(const std::string& path, ConstPlane coc) {
  std::string extension = fs::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return char(std::tolower(c)); });
  if (extension != ".exr") return coc_picture(coc);
  Image values(coc.width(), coc.height(), 1);
  for (std::ptrdiff_t y = 0; y < coc.height(); ++y)
    std::copy(coc.row(y), coc.row(y) + coc.width(), values.plane(0).row(y));
  return values;
}

std::string default_coc_path(const std::string& output) {
  std::filesystem::path p(output);
  return (p.parent_path() / (p.stem().string() + "_coc.png")).string();
}

int run_dof(const cli::Arguments& args) {
  const auto start = std::chrono::steady_clock::now();
  auto seconds = [](auto from) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - from).count();
  };
  const int threads = args.integer("threads", 0);
  const DofMethod& method = find_dof_method(args.text("method", "adi"));  // fail before work
  const std::string output = args.text("output", "tridiff_dof.png");
  const std::string coc_output = args.text("coc-output", default_coc_path(output));
  OutputFiles outputs;  // every path checked before the work
  outputs.claim("--output", output);
  outputs.claim("--coc-output", coc_output);
  if (args.has("input-output")) outputs.claim("--input-output", args.text("input-output", ""));
  if (args.has("report")) outputs.claim("--report", args.text("report", ""), false);

  cli::Frame frame = cli::load_frame(args, threads);
  const Image& color = frame.color;
  const Image& coc = frame.coc;
  const std::string& source = frame.source;
  const double load_seconds = frame.load_seconds, coc_seconds = frame.coc_seconds;

  DofSettings settings;
  settings.threads = threads;
  settings.layers = args.flag("layers");
  settings.skip_in_focus = !args.flag("no-skip");
  settings.in_focus_coc_px = args.number("in-focus", 1.f);
  settings.error_budget_psnr = args.number("psnr-budget", 30.f);
  settings.progress = progress_bar();
  DofReport report;
  // A method that works in place (adi) blurs the frame where it lies: the tiles in focus are
  // not even copied. The input is kept apart only when it is written out as well.
  const bool in_place = method.in_place && !args.has("input-output");
  Image separate_result;
  Image& result = in_place ? frame.color : separate_result;
  const auto method_start = std::chrono::steady_clock::now();
  method.run(result, color, coc.plane(0), settings, report);
  const double method_seconds = seconds(method_start);

  const auto write_start = std::chrono::steady_clock::now();
  outputs.write_image("--output", result);
  outputs.write_image("--coc-output", coc_output_image(coc_output, coc.plane(0)),
                      ColorEncoding::Linear);
  if (args.has("input-output")) outputs.write_image("--input-output", color);
  const double write_seconds = seconds(write_start);

  std::ostringstream text, json;
  text << "tridiff dof: " << source << "\n"
       << "  method   " << method.name
       << (report.chosen_method.empty() ? "" : " -> " + report.chosen_method)
       << (report.layered ? " (layered)" : "") << "\n"
       << "  coc      " << frame.coc_model << "\n"
       << "  skipped  " << 100.0 * report.skipped_fraction << " % of the per-pixel work\n";
  if (report.explicit_steps) text << "  steps    " << report.explicit_steps << " explicit steps\n";
  text << "  time     input " << load_seconds * 1e3 << " ms, coc " << coc_seconds * 1e3 << " ms, ";
  for (const DofStage& stage : report.stages) text << stage.name << " " << stage.seconds * 1e3 << " ms, ";
  text << "write " << write_seconds * 1e3 << " ms, total " << seconds(start) * 1e3 << " ms\n"
       << "  wrote    " << output << ", " << coc_output << "\n";
  if (!report.notes.empty()) text << "  notes    " << report.notes << "\n";

  if (args.has("report")) {
    json << "{\n  \"source\": " << json_string(source)
         << ",\n  \"method\": " << json_string(std::string(method.name))
         << ",\n  \"chosen_method\": " << json_string(report.chosen_method)
         << ",\n  \"layered\": " << (report.layered ? "true" : "false")
         << ",\n  \"coc_model\": " << json_string(frame.coc_model) << ",\n  \"skipped_fraction\": "
         << report.skipped_fraction << ",\n  \"explicit_steps\": " << report.explicit_steps
         << ",\n  \"seconds\": {\"input\": " << load_seconds << ", \"coc\": " << coc_seconds;
    for (const DofStage& stage : report.stages)
      json << ", " << json_string(stage.name) << ": " << stage.seconds;
    json << ", \"method\": " << method_seconds << ", \"write\": " << write_seconds << "}\n}\n";
    outputs.write_text("--report", json.str());
  }
  outputs.commit();
  std::fputs(text.str().c_str(), stdout);
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
      print_dof_usage();
      return argc > 1 ? 0 : 2;
    }
    if (command == "methods") return list_methods();
    if (command == "ipf") {
      const cli::Arguments args = cli::parse(argc, argv, 2, cli::kIpfFlags, cli::kIpfValued);
      if (args.flag("help")) {
        std::fputs(cli::kIpfUsage, stdout);
        std::fputs(cli::kInputUsage, stdout);
        return 0;
      }
      return cli::run_ipf(args);
    }
    if (command != "dof")
      throw InvalidArgument(command, -1, -1, "unknown command (expected dof, ipf or methods)");
    std::vector<std::string> valued = cli::kInputOptions;
    valued.insert(valued.end(), kDofOptions.begin(), kDofOptions.end());
    const cli::Arguments args = cli::parse(argc, argv, 2, kDofFlags, valued);
    if (args.flag("help")) {
      print_dof_usage();
      return 0;
    }
    return run_dof(args);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "%s\n", error.what());
    return 1;
  }
}
