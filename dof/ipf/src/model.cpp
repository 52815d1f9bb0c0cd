// The clocked model of the Inverse Post Filter (seed 004 §3): per clock one pixel enters the
// input processing unit, every mask row shifts by one, the pipes between the rows delay a line,
// all n x n execution units run the program against the centre, and the output processing unit
// finishes the pixel leaving the top-left unit. Registers are rings with a moving head, which
// is what a shift register looks like from outside (a value written is read back `length`
// clocks later) without moving every stage in software.
#include "tridiff/ipf/model.hpp"

#include <algorithm>
#include <string>
#include <utility>

#include "tridiff/threads.hpp"

namespace tridiff::ipf {
namespace {

// One stage of the pipe: the input data of fig. 10, the cleared registers, and whether a
// register saturated on the way (for the counts only).
struct Cell {
  PipeData data;
  Accumulators acc;
  bool saturated = false;
};

// A shift register of `length` stages, as a ring with a moving head: a value shifted in leaves
// `length` clocks later (at once when the length is 0). A mask row is one of n execution units'
// registers (at(j), j = n - 1 the newest); a pipe is the rest of a line between two mask rows.
class ShiftRegister {
 public:
  explicit ShiftRegister(std::ptrdiff_t length) : cells_(std::size_t(length)) {}
  std::ptrdiff_t length() const { return std::ptrdiff_t(cells_.size()); }
  Cell& at(int j) {
    std::size_t index = head_ + std::size_t(j);  // no division: this is the inner loop
    if (index >= cells_.size()) index -= cells_.size();
    return cells_[index];
  }
  Cell shift(Cell&& newest) {
    if (cells_.empty()) return std::move(newest);
    Cell leaving = std::move(cells_[head_]);
    cells_[head_] = std::move(newest);
    if (++head_ == cells_.size()) head_ = 0;
    return leaving;
  }

 private:
  std::vector<Cell> cells_;
  std::size_t head_ = 0;
};

// Scan coordinates (u along the line, v the line) to frame coordinates.
struct ScanMap {
  bool columns;
  std::pair<std::ptrdiff_t, std::ptrdiff_t> frame(std::ptrdiff_t u, std::ptrdiff_t v) const {
    return columns ? std::pair{v, u} : std::pair{u, v};
  }
};

struct PartCounts {
  std::ptrdiff_t clocks = 0, reads = 0, writes = 0, updates = 0, shifts = 0, saturated = 0;
};

// Runs one vertical part through a unit clock by clock. Program provides input(x, y) -> Cell,
// execute(centre, position, unit, du, dv) -> whether a register changed, and
// output(cell, x, y).
template <class Program>
PartCounts run_part(const FramePlan& plan, const Part& part, const Program& program) {
  const int n = plan.mask, h = n / 2;
  const std::ptrdiff_t line = plan.line_length(part);
  const ScanMap map{plan.columns};
  std::vector<ShiftRegister> rows(std::size_t(n), ShiftRegister{n});  // k = 0: newest line (bottom)
  std::vector<ShiftRegister> pipes;                                   // between row k and row k + 1
  for (int k = 0; k + 1 < n; ++k) pipes.emplace_back(line - n);

  PartCounts counts;
  counts.clocks = plan.part_clocks(part);
  for (std::ptrdiff_t t = 0; t < counts.clocks; ++t) {
    // Input processing unit: stream element t is column t % line of line t / line, the part's
    // columns framed by h halo columns each side; beyond the frame it is padding.
    Cell incoming;
    const std::ptrdiff_t u = part.first + t % line - h, v = t / line;
    if (u >= 0 && u < plan.scan_width && v < plan.scan_lines) {
      const auto [x, y] = map.frame(u, v);
      incoming = program.input(x, y);
      ++counts.reads;
    }
    // Shift: through each mask row, then its pipe, into the row above.
    for (int k = 0; k < n; ++k) {
      Cell leaving = rows[std::size_t(k)].shift(std::move(incoming));
      if (k + 1 < n) {
        incoming = pipes[std::size_t(k)].shift(std::move(leaving));
        counts.shifts += pipes[std::size_t(k)].length();
      }
    }
    // Execution mask: every unit reads the centre pipe and its own.
    const Cell& centre = rows[std::size_t(h)].at(h);
    if (centre.data.present)
      for (int k = 0; k < n; ++k)
        for (int j = 0; j < n; ++j) {
          Cell& position = rows[std::size_t(k)].at(j);
          if (position.data.present)
            counts.updates += program.execute(centre, position, k * n + j, j - h, h - k);
        }
    // Output processing unit: the top-left unit holds a finished pixel, (n-1) lines and
    // (n-1) pixels after it entered.
    const std::ptrdiff_t done = t - (n - 1) * line - (n - 1);
    if (done < 0) continue;
    const std::ptrdiff_t column = done % line - h, done_line = done / line;
    if (column < 0 || column >= part.count || done_line >= plan.scan_lines) continue;
    const Cell& finished = rows[std::size_t(n - 1)].at(0);
    const auto [x, y] = map.frame(part.first + column, done_line);
    program.output(finished, x, y);
    ++counts.writes;
    counts.saturated += finished.saturated;
  }
  return counts;
}

// Runs every part (each its own unit, so in parallel) and sums what they spent.
template <class Program>
RunCounts run_frame(const FramePlan& plan, const Program& program, int threads) {
  std::vector<PartCounts> parts(plan.parts.size());
  const int team = resolve_threads(threads);
#pragma omp parallel for num_threads(team) schedule(dynamic)
  for (std::size_t p = 0; p < plan.parts.size(); ++p)
    parts[p] = run_part(plan, plan.parts[p], program);

  RunCounts counts;
  counts.plan = plan;
  for (const PartCounts& c : parts) {
    counts.clocks += c.clocks;
    counts.pixel_reads += c.reads;
    counts.pixel_writes += c.writes;
    counts.unit_updates += c.updates;
    counts.register_shifts += c.shifts;
    counts.saturated_pixels += c.saturated;
  }
  counts.pipes = plan.mask - 1;
  counts.pipe_length = plan.max_line_length();
  counts.switch_settings = PipeLayout(plan.register_size).connect(counts.pipe_length);
  return counts;
}

class DofUnits {
 public:
  DofUnits(Image& out, const Image& color, ConstPlane z, ConstPlane coc, const DofProgram& program)
      : out_(out), color_(color), z_(z), coc_(coc), quantizer_(program) {}

  Cell input(std::ptrdiff_t x, std::ptrdiff_t y) const {
    float lanes[kMaxLanes] = {};
    for (int c = 0; c < color_.channels(); ++c) lanes[c] = color_(x, y, c);
    Cell cell;
    cell.data = quantizer_.pipe_data(lanes, color_.channels(), z_(x, y), coc_(x, y), x, y);
    return cell;
  }
  bool execute(const Cell& centre, Cell& position, int, int du, int dv) const {
    const std::int32_t weight =
        dof_weight(centre.data, position.data, du * du + dv * dv, quantizer_.program().rule);
    if (!weight) return false;
    position.saturated |= dof_accumulate(position.acc, centre.data, weight, color_.channels(),
                                         quantizer_.program().color_weight_bits);
    return true;
  }
  void output(const Cell& cell, std::ptrdiff_t x, std::ptrdiff_t y) const {
    for (int c = 0; c < color_.channels(); ++c)
      out_(x, y, c) = color_value(dof_output(cell.acc.color[c], cell.acc.weight));
  }

 private:
  Image& out_;
  const Image& color_;
  ConstPlane z_, coc_;
  DofQuantizer quantizer_;
};

class MaskUnits {
 public:
  MaskUnits(Image& out, const Image& color, const MaskKernel& kernel, bool columns)
      : out_(out), color_(color), normalise_(kernel_normalises(kernel)) {
    // Each unit's constant memory: the weight of its position relative to the centre, in frame
    // coordinates (a column scan sees the mask transposed).
    const int n = kernel.size, h = n / 2;
    for (int k = 0; k < n; ++k)
      for (int j = 0; j < n; ++j) {
        const int du = j - h, dv = h - k;
        unit_weights_.push_back(columns ? kernel.at(dv, du) : kernel.at(du, dv));
      }
  }

  Cell input(std::ptrdiff_t x, std::ptrdiff_t y) const {
    Cell cell;
    cell.data.present = true;
    for (int c = 0; c < color_.channels(); ++c)
      cell.data.color[c] = quantize_color(color_(x, y, c));
    return cell;
  }
  bool execute(const Cell& centre, Cell& position, int unit, int, int) const {
    const int weight = unit_weights_[std::size_t(unit)];
    if (!weight) return false;
    for (int c = 0; c < color_.channels(); ++c)
      position.acc.color[c] += centre.data.color[c] * weight;
    position.acc.weight += weight;
    return true;
  }
  void output(const Cell& cell, std::ptrdiff_t x, std::ptrdiff_t y) const {
    for (int c = 0; c < color_.channels(); ++c)
      out_(x, y, c) = color_value(mask_output(cell.acc.color[c], cell.acc.weight, normalise_));
  }

 private:
  Image& out_;
  const Image& color_;
  bool normalise_;
  std::vector<int> unit_weights_;
};

void require_lanes(const Image& color) {
  if (color.empty()) throw InvalidArgument("color", "is empty");
  if (color.channels() > kMaxLanes)
    throw InvalidArgument("color", "has " + std::to_string(color.channels()) +
                                       " channels; the IPF pipe carries at most 4");
}

}  // namespace

ModelCost model_cost(const FramePlan& plan, int threads) {
  const int team = resolve_threads(threads);
  const double n = plan.mask;
  ModelCost cost;
  double largest_part = 0;
  for (const Part& part : plan.parts) {
    cost.unit_steps += double(part.count) * double(plan.scan_lines) * n * n;
    // run_part's registers: n mask rows of n stages, n - 1 pipes of the rest of a line.
    const double cells = n * n + (n - 1) * double(plan.line_length(part) - plan.mask);
    largest_part = std::max(largest_part, cells * double(sizeof(Cell)));
  }
  const std::size_t at_once = std::min(plan.parts.size(), std::size_t(team));
  cost.register_bytes = double(at_once) * largest_part;
  return cost;
}

RunCounts run_dof_model(Image& out, const Image& color, ConstPlane z, ConstPlane coc,
                        const DofProgram& program, const ModelOptions& options) {
  validate(program);
  require_lanes(color);
  require_size(color, z.width(), z.height(), "color (against z)");
  require_size(color, coc.width(), coc.height(), "color (against coc)");
  const FramePlan plan =
      plan_frame(color.width(), color.height(), program.mask, options.parts, options.register_size);
  out.reset(color.width(), color.height(), color.channels());
  return run_frame(plan, DofUnits(out, color, z, coc, program), options.threads);
}

RunCounts run_mask_model(Image& out, const Image& color, const MaskKernel& kernel,
                         const ModelOptions& options) {
  validate(kernel);
  require_lanes(color);
  const FramePlan plan =
      plan_frame(color.width(), color.height(), kernel.size, options.parts, options.register_size);
  out.reset(color.width(), color.height(), color.channels());
  return run_frame(plan, MaskUnits(out, color, kernel, plan.columns), options.threads);
}

}  // namespace tridiff::ipf
