// `tridiff ipf`: runs a frame through the clocked model of seed 004's Inverse Post Filter and
// prints what the hardware would spend on it — configuration, clocks, memory traffic, time.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <sstream>
#include <string>

#include "common.hpp"
#include "tridiff/image/io.hpp"
#include "tridiff/ipf/model.hpp"
#include "tridiff/ipf/performance.hpp"

namespace tridiff::cli {

const char* const kIpfUsage =
    R"(usage: tridiff ipf [options]      the Inverse Post Filter hardware model (seed 004)

program
  --program P               dof (fig. 11, default) | laplacian (fig. 9 with fig. 8's mask)
  --rule R                  dof: corrected (default) | printed (fig. 11's second test as printed)
  --in-focus PX             dof: |CoC| below this gets radius 0 (default 1)
  --area-weight-bits B      dof: AreaWeight register width (default 8, fig. 10)
  --color-weight-bits B     dof: ColorWeight accumulator width (default 8, fig. 10; wider is
                            headroom against saturation, Color widens with it)
  --check                   also run the software `ipf` method / direct convolution and compare
hardware
  --mask N                  execution mask N x N, odd >= 3 (default 17)
  --parts P                 vertical parts of the frame (default 4)
  --register-size S         stages per pipe as built (default: min(w, h) + mask - 1, §4)
  --clock-mhz F             core clock (default 310)
  --bandwidth-gbs B         memory bandwidth, 1e9 bytes/s (default 20)
  --pixels-per-clock K      pixels finished per clock, i.e. units side by side (default 1)
  --cycles-per-pixel C      program clocks per pixel (default: dof 5, §5; laplacian 1)
  --threads N               0 = all cores (default)
output
  -o, --output FILE         result image (default tridiff_ipf.png)

)";

const std::vector<std::string> kIpfFlags = {"help", "check"};
const std::vector<std::string> kIpfValued = [] {
  std::vector<std::string> valued = kInputOptions;
  for (const char* key : {"program", "rule", "in-focus", "area-weight-bits", "color-weight-bits",
                          "mask", "parts", "register-size", "clock-mhz", "bandwidth-gbs",
                          "pixels-per-clock", "cycles-per-pixel", "output"})
    valued.emplace_back(key);
  return valued;
}();

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// A positive option value, or InvalidArgument naming the option.
double positive(const Arguments& args, const std::string& key, double fallback) {
  const double value = args.number(key, float(fallback));
  if (!(value > 0)) throw InvalidArgument("--" + key, -1, -1, "must be > 0");
  return value;
}

ipf::DofRule parse_rule(const std::string& text) {
  if (text == "corrected") return ipf::DofRule::corrected;
  if (text == "printed") return ipf::DofRule::as_printed;
  throw InvalidArgument("--rule", -1, -1, "'" + text + "' is not corrected or printed");
}

// ipf::validate names the program's fields; the user typed options.
void validate_as_options(const ipf::DofProgram& program) {
  try {
    ipf::validate(program);
  } catch (const InvalidArgument& error) {
    std::string option = error.argument() == "in_focus_coc_px" ? "in-focus" : error.argument();
    std::replace(option.begin(), option.end(), '_', '-');
    const std::string message = error.what();
    throw InvalidArgument("--" + option, -1, -1, message.substr(message.rfind(": ") + 2));
  }
}

std::string stage_list(const ipf::PipeLayout& layout) {
  std::ostringstream text;
  for (std::ptrdiff_t stage : layout.stages()) text << (text.tellp() ? " " : "") << stage;
  return text.str();
}

std::string switch_list(const std::vector<bool>& on) {
  std::string text;
  for (bool s : on) text += s ? '1' : '0';
  return text;
}

// The direct sum of fig. 9 at every pixel (the reference the model must equal).
Image direct_mask_filter(const Image& color, const ipf::MaskKernel& kernel) {
  Image out(color.width(), color.height(), color.channels());
  const int h = kernel.size / 2;
  const bool normalise = ipf::kernel_normalises(kernel);
  for (int c = 0; c < color.channels(); ++c)
    for (std::ptrdiff_t y = 0; y < color.height(); ++y)
      for (std::ptrdiff_t x = 0; x < color.width(); ++x) {
        std::int32_t sum = 0, weight = 0;
        for (int dy = -h; dy <= h; ++dy)
          for (int dx = -h; dx <= h; ++dx) {
            const std::ptrdiff_t cx = x - dx, cy = y - dy;
            if (cx < 0 || cy < 0 || cx >= color.width() || cy >= color.height()) continue;
            sum += kernel.at(dx, dy) * ipf::quantize_color(color(cx, cy, c));
            weight += kernel.at(dx, dy);
          }
        out(x, y, c) = ipf::color_value(ipf::mask_output(sum, weight, normalise));
      }
  return out;
}

std::ptrdiff_t differing_values(const Image& a, const Image& b) {
  std::ptrdiff_t differ = 0;
  for (int c = 0; c < a.channels(); ++c)
    for (std::ptrdiff_t y = 0; y < a.height(); ++y)
      for (std::ptrdiff_t x = 0; x < a.width(); ++x) differ += a(x, y, c) != b(x, y, c);
  return differ;
}

}  // namespace

int run_ipf(const Arguments& args) {
  const auto start = std::chrono::steady_clock::now();
  const int threads = args.integer("threads", 0);
  const std::string program_name = args.text("program", "dof");
  if (program_name != "dof" && program_name != "laplacian")
    throw InvalidArgument("--program", -1, -1, "'" + program_name + "' is not dof or laplacian");
  const bool dof = program_name == "dof";
  const int mask = args.integer("mask", 17);
  if (mask < 3 || mask % 2 == 0)
    throw InvalidArgument("--mask", -1, -1, "must be odd and >= 3, got " + std::to_string(mask));
  const int parts = args.integer("parts", 4);
  if (parts < 1)
    throw InvalidArgument("--parts", -1, -1, "must be >= 1, got " + std::to_string(parts));
  const int register_stages = args.integer("register-size", 0);
  if (register_stages < 0) throw InvalidArgument("--register-size", -1, -1, "must be >= 0");
  ipf::PerformanceInput hardware;
  hardware.mask = mask;
  hardware.parts = parts;
  hardware.register_size = register_stages;
  hardware.clock_hz = positive(args, "clock-mhz", 310) * 1e6;
  hardware.bandwidth_bytes_per_s = positive(args, "bandwidth-gbs", 20) * 1e9;
  hardware.pixels_per_clock = positive(args, "pixels-per-clock", 1);
  hardware.cycles_per_pixel = positive(args, "cycles-per-pixel", dof ? 5 : 1);
  hardware.read_bytes_per_pixel = dof ? 8 : 4;  // colour + z; the mask filter reads colour only
  ipf::DofProgram program;
  program.mask = mask;
  program.rule = parse_rule(args.text("rule", "corrected"));
  program.in_focus_coc_px = args.number("in-focus", 1.f);
  program.area_weight_bits = args.integer("area-weight-bits", 8);
  program.color_weight_bits = args.integer("color-weight-bits", 8);
  if (dof) validate_as_options(program);

  const Frame frame = load_frame(args, threads);
  hardware.width = frame.color.width();
  hardware.height = frame.color.height();
  const ipf::Performance perf = ipf::estimate(hardware);  // also checks the plan fits

  ipf::ModelOptions options{parts, register_stages, threads};
  Image result;
  const auto model_start = std::chrono::steady_clock::now();
  const ipf::RunCounts counts =
      dof ? ipf::run_dof_model(result, frame.color, frame.depth.plane(0), frame.coc.plane(0),
                               program, options)
          : ipf::run_mask_model(result, frame.color, ipf::laplacian_kernel(mask), options);
  const double model_seconds = seconds_since(model_start);

  std::string check;
  if (args.flag("check")) {
    Image reference;
    if (dof)
      ipf_dof(reference, frame.color, frame.depth.plane(0), frame.coc.plane(0), program, threads);
    else
      reference = direct_mask_filter(frame.color, ipf::laplacian_kernel(mask));
    const std::ptrdiff_t differ = differing_values(result, reference);
    check = (dof ? "software ipf method: " : "direct convolution: ") +
            (differ ? std::to_string(differ) + " values differ" : std::string("identical"));
  }

  const std::string output = args.text("output", "tridiff_ipf.png");
  write_image(output, result);

  const ipf::FramePlan& plan = perf.plan;
  const ipf::PipeLayout layout(plan.register_size);
  const double pixels = double(perf.pixels);
  std::ostringstream text;
  text << "tridiff ipf: " << frame.source << "\n"
       << "  program   " << (dof ? "dof (fig. 11, " : "laplacian (fig. 9 with fig. 8's mask")
       << (dof ? (program.rule == ipf::DofRule::corrected ? "corrected rule" : "rule as printed")
               : std::string())
       << (dof ? ", AreaWeight " + std::to_string(program.area_weight_bits) + " bit, ColorWeight " +
                     std::to_string(program.color_weight_bits) + " bit), " + frame.coc_model
               : std::string(")"))
       << "\n"
       << "  mask      " << mask << " x " << mask << " execution units, " << counts.pipes
       << " pipes\n"
       << "  register  " << plan.register_size << " stages per pipe as built, " << layout.switches()
       << " switches (stages " << stage_list(layout) << ")\n"
       << "  parts     " << parts << " along " << (plan.columns ? "columns" : "rows") << ", line "
       << counts.pipe_length << " stages (connected " << switch_list(counts.switch_settings)
       << "), " << plan.mask - 1 << " x " << counts.pipe_length << " = "
       << (plan.mask - 1) * counts.pipe_length << " register stages in use\n"
       << "  clocks    " << perf.clocks_per_frame << " pipe steps per frame for " << perf.pixels
       << " pixels (overhead " << perf.overhead_steps << ", "
       << 100.0 * double(perf.overhead_steps) / pixels << " %); split costs " << perf.split_overhead
       << " (seed 004 §4 formula: " << ipf::paper_split_overhead(plan.scan_width, mask, parts)
       << ")\n"
       << "  fixed     a register fixed at " << plan.register_size << " stages would waste "
       << perf.fixed_register_waste << " steps\n"
       << "  memory    " << perf.pixel_reads << " pixels read, " << perf.pixel_writes
       << " written, " << perf.bytes / 1e6 << " MB (" << perf.bytes / 1048576.0
       << " MiB): " << perf.memory_seconds * 1e3 << " ms at "
       << hardware.bandwidth_bytes_per_s / 1e9 << " GB/s\n"
       << "  compute   " << hardware.cycles_per_pixel << " cycles/pixel, "
       << hardware.pixels_per_clock << " pixel(s)/clock at " << hardware.clock_hz / 1e6
       << " MHz: " << perf.compute_seconds * 1e3 << " ms (pixels alone "
       << perf.ideal_compute_seconds * 1e3 << " ms); " << perf.pixels_per_clock_for(5e-3)
       << " pixels/clock for 5 ms\n"
       << "  frame     " << perf.frame_seconds * 1e3 << " ms, "
       << (perf.memory_bound ? "memory" : "compute") << "-bound\n"
       << "  model     " << counts.clocks << " clocks run ("
       << (counts.clocks == perf.clocks_per_frame ? "= the estimate" : "DIFFERS from the estimate")
       << "), " << counts.unit_updates << " unit updates, " << counts.saturated_pixels
       << " pixels saturated a register, " << model_seconds * 1e3 << " ms\n";
  if (!check.empty()) text << "  check     " << check << "\n";
  text << "  wrote     " << output << " (total " << seconds_since(start) * 1e3 << " ms)\n";
  std::fputs(text.str().c_str(), stdout);
  return 0;
}

}  // namespace tridiff::cli
