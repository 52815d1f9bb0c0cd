// The `auto` method and the method table behind it (auto.hpp).
#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

#include "tridiff/dof/auto.hpp"
#include "tridiff/dof/tiles.hpp"
#include "frame.hpp"
#include "stage_clock.hpp"

namespace tridiff {
namespace dof_detail {
extern const char* const kBuiltinMethodTable;  // method_table.cpp, generated from the CSV
}  // namespace dof_detail

namespace {

constexpr std::string_view kHeader =
    "method,scene,width,height,threads,max_radius,has_near,work_fraction,seconds,psnr,ssim,"
    "reference";

std::vector<std::string_view> split(std::string_view line, char separator) {
  std::vector<std::string_view> fields;
  for (std::size_t start = 0;;) {
    const std::size_t end = line.find(separator, start);
    fields.push_back(line.substr(start, end - start));
    if (end == std::string_view::npos) return fields;
    start = end + 1;
  }
}

[[noreturn]] void bad_line(std::ptrdiff_t line, const std::string& what) {
  throw InvalidArgument("table", line, -1, "line " + std::to_string(line) + ": " + what);
}

double number(std::string_view field, std::ptrdiff_t line, const char* column) {
  if (field == "inf") return std::numeric_limits<double>::infinity();
  double value = 0;
  const auto [end, error] = std::from_chars(field.data(), field.data() + field.size(), value);
  if (error != std::errc() || end != field.data() + field.size() || !std::isfinite(value))
    bad_line(line, std::string(column) + " '" + std::string(field) + "' is not a number");
  return value;
}

std::string format_number(double value) {
  if (std::isinf(value)) return "inf";
  std::ostringstream out;
  out.precision(6);
  out << value;
  return out.str();
}

}  // namespace

std::vector<MethodTableRow> parse_method_table(std::string_view csv) {
  std::vector<MethodTableRow> rows;
  std::ptrdiff_t line_number = 0;
  bool header_seen = false;
  for (std::string_view line : split(csv, '\n')) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line.empty() || line.front() == '#') continue;
    if (!header_seen) {
      if (line != kHeader)
        bad_line(line_number, "the header must be '" + std::string(kHeader) + "'");
      header_seen = true;
      continue;
    }
    const std::vector<std::string_view> f = split(line, ',');
    if (f.size() != 12)
      bad_line(line_number, "has " + std::to_string(f.size()) + " columns, expected 12");
    MethodTableRow row;
    row.method = std::string(f[0]);
    row.scene = std::string(f[1]);
    row.width = std::ptrdiff_t(number(f[2], line_number, "width"));
    row.height = std::ptrdiff_t(number(f[3], line_number, "height"));
    row.threads = int(number(f[4], line_number, "threads"));
    row.max_radius = float(number(f[5], line_number, "max_radius"));
    if (f[6] != "0" && f[6] != "1") bad_line(line_number, "has_near must be 0 or 1");
    row.has_near = f[6] == "1";
    row.work_fraction = number(f[7], line_number, "work_fraction");
    row.seconds = number(f[8], line_number, "seconds");
    row.psnr = number(f[9], line_number, "psnr");
    row.ssim = number(f[10], line_number, "ssim");
    row.reference = std::string(f[11]);
    if (row.reference != "truth" && row.reference != "scatter")
      bad_line(line_number, "reference must be 'truth' or 'scatter'");
    if (row.method.empty() || row.width < 1 || row.height < 1 || row.seconds < 0 ||
        row.work_fraction < 0 || row.work_fraction > 1)
      bad_line(line_number, "empty method, size below 1, negative time or work outside [0, 1]");
    rows.push_back(std::move(row));
  }
  if (!header_seen) bad_line(line_number, "no header line");
  return rows;
}

std::string format_method_table(std::span<const MethodTableRow> rows) {
  std::string csv = std::string(kHeader) + "\n";
  for (const MethodTableRow& r : rows)
    csv += r.method + "," + r.scene + "," + std::to_string(r.width) + "," +
           std::to_string(r.height) + "," + std::to_string(r.threads) + "," +
           format_number(r.max_radius) + "," + (r.has_near ? "1" : "0") + "," +
           format_number(r.work_fraction) + "," + format_number(r.seconds) + "," +
           format_number(r.psnr) + "," + format_number(r.ssim) + "," + r.reference + "\n";
  return csv;
}

std::span<const MethodTableRow> builtin_method_table() {
  static const std::vector<MethodTableRow> table =
      parse_method_table(dof_detail::kBuiltinMethodTable);
  return table;
}

namespace {

struct Candidate {
  const DofMethod* method = nullptr;
  double predicted_seconds = 0, expected_psnr = 0;
  const MethodTableRow *cost_row = nullptr, *error_row = nullptr;
};

// The prediction for one method from its rows (see auto.hpp), or no method if it has none.
Candidate predict(const DofMethod& method, std::span<const MethodTableRow> table,
                  const TileMap& tiles) {
  Candidate best{&method};
  std::vector<const MethodTableRow*> like, all;
  for (const MethodTableRow& row : table)
    if (row.method == method.name) {
      all.push_back(&row);
      if (row.has_near == tiles.has_near()) like.push_back(&row);
    }
  if (all.empty()) return {};
  if (like.empty()) like = all;
  auto log_radius = [](double r) { return std::log(std::max(r, 0.5) + 1); };
  const double radius = tiles.max_radius();
  best.error_row =
      *std::min_element(like.begin(), like.end(), [](auto a, auto b) { return a->psnr < b->psnr; });
  best.cost_row = *std::min_element(like.begin(), like.end(), [&](auto a, auto b) {
    return std::abs(log_radius(a->max_radius) - log_radius(radius)) <
           std::abs(log_radius(b->max_radius) - log_radius(radius));
  });
  best.expected_psnr = best.error_row->psnr;
  const MethodTableRow& c = *best.cost_row;
  const double row_worked = std::max(c.work_fraction * double(c.width * c.height), 1.0);
  const double frame_worked = tiles.work_fraction() * double(tiles.width() * tiles.height());
  double scale = frame_worked / row_worked;
  if (!method.unbounded_blur) {
    const double ratio = std::max<double>(radius, 1) / std::max<double>(c.max_radius, 1);
    scale *= ratio * ratio;
  }
  best.predicted_seconds = c.seconds * scale;
  return best;
}

std::string describe(const Candidate& c) {
  std::ostringstream out;
  out.precision(3);
  out << c.method->name << " (" << c.predicted_seconds * 1e3 << " ms from its '"
      << c.cost_row->scene << "' row, PSNR " << c.expected_psnr << " dB against "
      << c.error_row->reference << " on '" << c.error_row->scene << "')";
  return out.str();
}

}  // namespace

MethodChoice choose_dof_method(ConstPlane coc, const DofOptions& settings,
                               std::span<const MethodTableRow> table) {
  const TileMap tiles(coc, sharp_below_px(settings.in_focus_coc_px), TileMap::kDefaultTile, 0,
                      settings.threads);
  return choose_dof_method(tiles, settings, table);
}

MethodChoice choose_dof_method(const TileMap& tiles, const DofOptions& settings,
                               std::span<const MethodTableRow> table) {
  std::vector<Candidate> candidates;
  std::string missing;
  for (const DofMethod& method : dof_methods()) {
    if (method.name == "auto" || !honours_options(method, settings)) continue;
    const Candidate c = predict(method, table, tiles);
    if (c.method)
      candidates.push_back(c);
    else
      missing += (missing.empty() ? "" : ", ") + std::string(method.name);
  }
  if (candidates.empty() && missing.empty())
    throw InvalidArgument("method",
                          "auto: no method honours the options asked for (layers, "
                          "aperture shape, highlights) together");
  if (candidates.empty()) throw InvalidArgument("table", "has no row for any method");
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    return a.predicted_seconds < b.predicted_seconds;
  });
  const double budget = settings.error_budget_psnr;
  auto meets = [&](const Candidate& c) { return c.expected_psnr >= budget; };
  auto chosen = std::find_if(candidates.begin(), candidates.end(), meets);
  const bool met = chosen != candidates.end();
  if (!met)
    chosen = std::max_element(candidates.begin(), candidates.end(),
                              [](auto& a, auto& b) { return a.expected_psnr < b.expected_psnr; });

  std::ostringstream reason;
  reason.precision(3);
  reason << "auto: frame " << tiles.width() << " x " << tiles.height() << ", "
         << 100 * tiles.work_fraction() << " % out-of-focus work, largest radius "
         << tiles.max_radius() << " px, " << (tiles.has_near() ? "a" : "no") << " near field; "
         << "budget PSNR >= " << budget << " dB. Chose " << describe(*chosen)
         << (met ? ", the cheapest within the budget." : ": no method meets the budget; the best.");
  int listed = 0;
  for (const Candidate& c : candidates)
    if (&c != &*chosen && listed++ < 3)
      reason << (listed == 1 ? " Others: " : "; ") << describe(c)
             << (meets(c) ? "" : " over budget");
  if (!missing.empty()) reason << ". Not in the table: " << missing;
  return {std::string(chosen->method->name), chosen->predicted_seconds, chosen->expected_psnr, met,
          reason.str()};
}

namespace dof_detail {

// The frame is checked and classified once (DofFrame): the choice reads its tiles, and the
// chosen method is run on the same frame.
void run_auto(Image& out, const DofFrame& frame, const DofOptions& settings, DofReport& report) {
  const auto start = StageClock::now();
  const MethodChoice choice = choose_dof_method(frame.tiles(), settings, builtin_method_table());
  const double choose_seconds = seconds_since(start);
  run_on_frame(find_dof_method(choice.method), out, frame, settings, report);
  report.stages.insert(report.stages.begin(), DofStage{"choose", choose_seconds});
  report.chosen_method = choice.method;
  report.notes = choice.reason + (report.notes.empty() ? "" : "\n" + report.notes);
}

}  // namespace dof_detail
}  // namespace tridiff
