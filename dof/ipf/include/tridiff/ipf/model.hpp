// A software model of seed 004's Inverse Post Filter hardware: the input processing unit, the
// shift-register array of configurable pipes, the n x n execution mask and the output processing
// unit, clocked one pixel per clock over a frame split into vertical parts (§3, §4). It runs the
// mask filter of fig. 9 and the depth of field of fig. 11 and counts what the hardware spends.
#pragma once

#include <cstddef>
#include <vector>

#include "tridiff/dof/ipf.hpp"
#include "tridiff/image/image.hpp"

namespace tridiff::ipf {

// One configurable pipe (§3.1.2, fig. 5): stages of 1, 2, 4, ... registers, each one switch, and
// a last stage trimmed to size - 2^floor(log2 size) + 1 (§4), so that the stages sum to `size`
// and every length 0..size is some set of connected stages.
class PipeLayout {
 public:
  explicit PipeLayout(std::ptrdiff_t size);

  std::ptrdiff_t size() const { return size_; }
  const std::vector<std::ptrdiff_t>& stages() const { return stages_; }  // lengths, ascending
  std::ptrdiff_t last_stage() const { return stages_.back(); }
  int switches() const { return int(stages_.size()); }  // one per stage
  // Which stages to connect for a pipe of `length` (InvalidArgument "length" beyond size()).
  std::vector<bool> connect(std::ptrdiff_t length) const;

 private:
  std::ptrdiff_t size_;
  std::vector<std::ptrdiff_t> stages_;
};

// §4: the pipe a hardware unit needs for render targets up to width x height:
// min(width, height) + mask - 1 (a line runs along the shorter side).
std::ptrdiff_t register_size(std::ptrdiff_t max_width, std::ptrdiff_t max_height, int mask);

// How a frame goes through the unit. The scan runs along rows (the memory order of a render
// buffer), the frame split into `parts` vertical strips; a strip's line is its width plus
// mask - 1 halo columns, read again from the neighbours (or padding at the frame border).
// When that line does not fit the register, the scan runs along columns instead (horizontal
// strips) — which is how §4 fits 1600 x 1200 into 1216 stages.
struct Part {
  std::ptrdiff_t first = 0, count = 0;  // columns of the scanned frame
};
struct FramePlan {
  bool columns = false;           // scan along columns (the frame is traversed transposed)
  std::ptrdiff_t scan_width = 0;  // length of a frame line in scan order
  std::ptrdiff_t scan_lines = 0;  // number of frame lines in scan order
  int mask = 0;
  std::vector<Part> parts;
  std::ptrdiff_t register_size = 0;  // stages of each pipe as built
  std::ptrdiff_t line_length(const Part& part) const { return part.count + mask - 1; }
  std::ptrdiff_t max_line_length() const;
  // Clocks one part takes: its lines plus mask - 1 lines and mask - 1 clocks of fill/drain.
  std::ptrdiff_t part_clocks(const Part& part) const;
};
// register_size 0: sized for this frame by register_size(width, height, mask). InvalidArgument
// ("parts", "mask", "register_size") when the frame cannot be run.
FramePlan plan_frame(std::ptrdiff_t width, std::ptrdiff_t height, int mask, int parts,
                     std::ptrdiff_t register_size = 0);

// What running `plan` through the clocked model costs this computer, known before the run (a
// budget for callers: the model's work grows with the mask's square). unit_steps: the units
// run against each pixel at the centre (pixels x mask^2, the model's inner loop; the clocks
// of padding skip it); register_bytes: the registers of the parts that run at once on
// `threads` threads (0: all cores).
struct ModelCost {
  double unit_steps = 0;
  double register_bytes = 0;
};
ModelCost model_cost(const FramePlan& plan, int threads = 0);

// What a run spent, counted by the clocked model.
struct RunCounts {
  FramePlan plan;
  std::ptrdiff_t clocks = 0;           // pipe clocks, one pixel (stream element) each, all parts
  std::ptrdiff_t pixel_reads = 0;      // pixels fetched from video memory (halo columns again)
  std::ptrdiff_t pixel_writes = 0;     // pixels written back
  std::ptrdiff_t unit_updates = 0;     // execution-unit steps that changed a register
  std::ptrdiff_t register_shifts = 0;  // stage-to-stage moves of pipe data in the delay lines
  std::ptrdiff_t saturated_pixels = 0;
  int pipes = 0;                      // mask - 1 (§3.1.2)
  std::ptrdiff_t pipe_length = 0;     // longest configured pipe (stages), <= register_size
  std::vector<bool> switch_settings;  // of that pipe
};

struct ModelOptions {
  int parts = 1;
  std::ptrdiff_t register_size = 0;  // 0: sized for the frame (register_size())
  int threads = 0;                   // parts run on separate threads (separate units)
};

// The DOF program (fig. 11) clocked through the model. z orders depth (smaller = nearer).
// Produces exactly ipf_dof's output.
RunCounts run_dof_model(Image& out, const Image& color, ConstPlane z, ConstPlane coc,
                        const DofProgram& program, const ModelOptions& options = {});

// The mask filter program (fig. 9) clocked through the model: out = codes / 255 (signed for
// zero-sum kernels), the kernel's size the mask's.
RunCounts run_mask_model(Image& out, const Image& color, const MaskKernel& kernel,
                         const ModelOptions& options = {});

}  // namespace tridiff::ipf
