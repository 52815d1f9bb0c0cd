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
#include "tridiff/threads.hpp"

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
  --mask N                  execution mask N x N, odd, 3 to 511 (default 17; fig. 10's
                            8-bit Radius reaches 255 pixels)
  --parts P                 vertical parts of the frame, 1 to 1024 (default 4)
  --register-size S         stages per pipe as built, at most 65536 (default: min(w, h) +
                            mask - 1, §4)
  --clock-mhz F             core clock, at most 1e5 (default 310)
  --bandwidth-gbs B         memory bandwidth, 1e9 bytes/s, at most 1e5 (default 20)
  --pixels-per-clock K      pixels finished per clock, i.e. units side by side, at most 1024
                            (default 1)
  --cycles-per-pixel C      program clocks per pixel, at most 1024 (default: dof 5, §5;
                            laplacian 1)
  --threads N               0 = all cores (default), at most 1024
  A run the model would spend more than 4e10 execution-unit steps (pixels x mask^2, minutes)
  or 4 GiB of registers on is refused before the built-in scene is rendered (a file: once read).
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

// The bounds of the model's options (kIpfUsage says them). The mask's is the library's
// (ipf::kMaxMask, fig. 10's 8-bit Radius). A part is a unit of its own (§4 splits a frame in
// four), a task for one thread: as many as the library's threads. A register of 2^16 stages
// (17 switches) holds a line of any frame side up to 65536 pixels; §4's unit has 1216. The
// rates are far beyond any hardware: a hundred GHz, a hundred TB/s, a thousand units side by
// side, a program of a thousand clocks per pixel.
constexpr int kMaxParts = kMaxThreads;
constexpr int kMaxRegisterSize = 1 << 16;
constexpr double kMaxClockMhz = 1e5, kMaxBandwidthGbs = 1e5;
constexpr double kMaxPixelsPerClock = 1024, kMaxCyclesPerPixel = 1024;
// The model's own cost on this computer: pixels x mask^2 unit steps, 2 to 4 x 1e8 a second
// per core (measured; less for wide masks). 4e10, a minute or two, lets a 3840 x 2160 frame
// run at mask 65 (3.5e10), the mask the lens's default CoC clamp (64 px, radius 32) needs,
// and 1920 x 1080 at mask 17 is 6e8 (a second); 1920 x 1080 at mask 255 (1.3e11) or
// 16384 x 16384 at mask 17 (7.8e10) are refused. And its registers: 4 GiB.
constexpr double kMaxUnitSteps = 4e10;
constexpr double kMaxRegisterBytes = 4.0 * (1 << 30);

// A positive option value up to `most`, or InvalidArgument naming the option.
double positive(const Arguments& args, const std::string& key, double fallback, double most) {
  const double value = args.number(key, float(fallback));
  if (!(value > 0) || value > most) {
    std::ostringstream text;
    text << "must be > 0 and at most " << most << ", got " << args.text(key, "");
    throw InvalidArgument("--" + key, text.str());
  }
  return value;
}

// ipf::plan_frame names its arguments ("parts", "register_size", "mask"): as the options.
ipf::FramePlan plan_as_options(std::ptrdiff_t width, std::ptrdiff_t height,
                               const ipf::PerformanceInput& hardware) {
  ipf::FramePlan plan;
  with_fields_as_options({"parts", "register-size", "mask"}, [&] {
    plan = ipf::plan_frame(width, height, hardware.mask, hardware.parts, hardware.register_size);
  });
  return plan;
}

// Refuses a run the model would take hours or gigabytes for, naming --mask (the cost grows
// with its square) and what else makes it.
void check_model_cost(std::ptrdiff_t width, std::ptrdiff_t height,
                      const ipf::PerformanceInput& hardware, int threads) {
  const ipf::ModelCost cost = ipf::model_cost(plan_as_options(width, height, hardware), threads);
  std::ostringstream text;
  text << "a " << width << " x " << height << " frame at mask " << hardware.mask << " in "
       << hardware.parts << " part(s) ";
  if (cost.unit_steps > kMaxUnitSteps) {
    text << "is " << cost.unit_steps << " execution-unit steps for the model (pixels x mask^2), "
         << "more than its bound " << kMaxUnitSteps << ": use a smaller --mask or frame";
    throw InvalidArgument("--mask", text.str());
  }
  if (cost.register_bytes > kMaxRegisterBytes) {
    text << "needs " << cost.register_bytes / (1 << 20) << " MiB of model registers, more than "
         << "its bound " << kMaxRegisterBytes / (1 << 20)
         << " MiB: use a smaller --mask, --register-size or --threads";
    throw InvalidArgument("--mask", text.str());
  }
}

ipf::DofRule parse_rule(const std::string& text) {
  if (text == "corrected") return ipf::DofRule::corrected;
  if (text == "printed") return ipf::DofRule::as_printed;
  throw InvalidArgument("--rule", "'" + text + "' is not corrected or printed");
}

// ipf::validate names the program's fields; the user typed options.
void validate_as_options(const ipf::DofProgram& program) {
  with_fields_as_options(kIpfValued, [&] { ipf::validate(program); },
                         {{"in_focus_coc_px", "in-focus"}});
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

// What an `ipf` command line asks for, checked before any input is read.
struct IpfPlan {
  int threads = 0;
  std::string output;
  OutputFiles files;
  bool dof = true;
  int mask = 17, parts = 4, register_stages = 0;
  ipf::PerformanceInput hardware;
  ipf::DofProgram program;
};

IpfPlan plan_ipf(const Arguments& args) {
  IpfPlan plan;
  plan.threads = thread_count(args);
  // The output checked before the model runs (it may run for long), written whole or not at all.
  plan.output = args.text("output", "tridiff_ipf.png");
  register_inputs(args, plan.files);
  check_image_path(plan.output);
  plan.files.claim("--output", plan.output);
  const std::string program_name = args.text("program", "dof");
  if (program_name != "dof" && program_name != "laplacian")
    throw InvalidArgument("--program", "'" + program_name + "' is not dof or laplacian");
  plan.dof = program_name == "dof";
  const int mask = plan.mask = args.integer("mask", 17);
  if (mask < 3 || mask % 2 == 0 || mask > ipf::kMaxMask)
    throw InvalidArgument("--mask", "must be odd and in [3, " + std::to_string(ipf::kMaxMask) +
                                        "] (fig. 10's 8-bit Radius reaches 255 pixels), got " +
                                        std::to_string(mask));
  const int parts = plan.parts = args.integer("parts", 4);
  if (parts < 1 || parts > kMaxParts)
    throw InvalidArgument("--parts", "must be in [1, " + std::to_string(kMaxParts) + "], got " +
                                         std::to_string(parts));
  const int register_stages = plan.register_stages = args.integer("register-size", 0);
  if (register_stages < 0 || register_stages > kMaxRegisterSize)
    throw InvalidArgument("--register-size", "must be in [0, " + std::to_string(kMaxRegisterSize) +
                                                 "] (0: sized for the frame), got " +
                                                 std::to_string(register_stages));
  const bool dof = plan.dof;
  if (!dof)
    for (const char* key : {"rule", "in-focus", "area-weight-bits", "color-weight-bits"})
      if (args.has(key))
        throw InvalidArgument("--" + std::string(key),
                              "applies to --program dof only, not laplacian");
  ipf::PerformanceInput& hardware = plan.hardware;
  hardware.mask = mask;
  hardware.parts = parts;
  hardware.register_size = register_stages;
  hardware.clock_hz = positive(args, "clock-mhz", 310, kMaxClockMhz) * 1e6;
  hardware.bandwidth_bytes_per_s = positive(args, "bandwidth-gbs", 20, kMaxBandwidthGbs) * 1e9;
  hardware.pixels_per_clock = positive(args, "pixels-per-clock", 1, kMaxPixelsPerClock);
  hardware.cycles_per_pixel = positive(args, "cycles-per-pixel", dof ? 5 : 1, kMaxCyclesPerPixel);
  hardware.read_bytes_per_pixel = dof ? 8 : 4;  // colour + z; the mask filter reads colour only
  ipf::DofProgram& program = plan.program;
  program.mask = mask;
  program.rule = parse_rule(args.text("rule", "corrected"));
  program.in_focus_coc_px = args.number("in-focus", 1.f);
  program.area_weight_bits = args.integer("area-weight-bits", 8);
  program.color_weight_bits = args.integer("color-weight-bits", 8);
  if (dof) validate_as_options(program);
  // The built-in scene's size is known before it is rendered; a file's once it is read.
  if (!args.has("color")) {
    const int width = args.integer("width", 1920), height = args.integer("height", 1080);
    if (width >= 1 && height >= 1 && width <= 16384 && height <= 16384)  // else load_frame says
      check_model_cost(width, height, hardware, plan.threads);
  }
  return plan;
}

}  // namespace

void check_ipf(const Arguments& args) {
  plan_ipf(args);
  check_input_options(args);
}

int run_ipf(const Arguments& args) {
  const auto start = std::chrono::steady_clock::now();
  IpfPlan checked = plan_ipf(args);  // every option and the output checked before the work
  const int threads = checked.threads, mask = checked.mask, parts = checked.parts;
  const int register_stages = checked.register_stages;
  const bool dof = checked.dof;
  const std::string& output = checked.output;
  OutputFiles& files = checked.files;
  ipf::PerformanceInput& hardware = checked.hardware;
  const ipf::DofProgram& program = checked.program;

  const Frame frame = load_frame(args, threads);
  hardware.width = frame.color.width();
  hardware.height = frame.color.height();
  check_model_cost(hardware.width, hardware.height, hardware, threads);
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

  files.stage("--output", encode_image(output, result, {.threads = threads}));
  files.commit();

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
