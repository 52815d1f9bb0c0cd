// The stability table: every matrix class of testing/stability_matrices.hpp x every tridiff
// method x {float, double} x a few sizes, solved by tridiff and by LAPACK ?gtsv, with forward
// and backward errors in long double against a long-double reference (refined_reference in
// testing/stability_measure.hpp: the Eigen LU of testing/reference.hpp, refined).
//
//   tridiff_stability_table [--out FILE] [--sizes 16,1000,65537] [--seed S]
//
// Writes JSON (to FILE, else stdout): one row per class, method, thread count, precision and n
// with tridiff's outcome and errors, LAPACK's, their ratios ours / max(LAPACK, eps)
// (lapack_floor in testing/stability_measure.hpp says why eps) and LAPACK's estimate of
// kappa_1(A). Outcomes: solved, refused (NumericalError: not dominant, unsafe for a pivot-free
// method), singular (NumericalError: zero or vanishing pivot; for LAPACK, info > 0), overflow
// (NumericalError: the solution overflowed), inaccurate (NumericalError: the answer failed the
// reductions' backward-error check), error (anything else), nonfinite (a non-finite x
// returned without an exception: a bug). A summary goes to stderr: per class and precision,
// per method, the worst ratio max(forward, backward) over the sizes, and what happened at the
// sizes where tridiff or LAPACK did not solve. About 10 s on 2 cores with the default sizes.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "stability_matrices.hpp"
#include "stability_measure.hpp"

namespace {

using namespace tridiff;
using namespace tridiff::test;

// Thomas and Auto are also run on this many threads: at n >= detail::kPartitionedMinRows
// (32768) that is the partitioned method, one part per thread. Fixed, not the core count, so
// the table is the same on every machine (threads beyond the cores just take turns).
constexpr int kPartitionedThreads = 4;

struct Row {
  std::string_view matrix_class;
  Method method;
  int threads;
  const char* precision;
  std::ptrdiff_t n;
  long double condition;
  Measurement ours, lapack;
  long double forward_ratio, backward_ratio;  // NaN unless both solved
};

std::string json_string(std::string_view text) {
  std::string out = "\"";
  for (char ch : text) {
    if (ch == '"' || ch == '\\') {
      out += '\\';
      out += ch;
    } else if (static_cast<unsigned char>(ch) < 0x20) {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\u%04x", ch);
      out += escaped;
    } else {
      out += ch;
    }
  }
  return out + "\"";
}

// JSON has no NaN or infinity: both become null.
std::string json_number(long double value) {
  if (!std::isfinite(value)) return "null";
  char text[40];
  std::snprintf(text, sizeof text, "%.6Le", value);
  return text;
}

// The methods whose single-system path depends on the thread count.
constexpr Method kThreadedMethods[] = {Method::Auto, Method::Thomas};

template <class T>
void run_precision(const char* precision, const std::vector<std::ptrdiff_t>& sizes,
                   std::uint64_t seed, std::vector<Row>& rows) {
  for (const MatrixClass& matrix_class : kStabilityClasses) {
    for (std::ptrdiff_t n : sizes) {
      const System<T> system = matrix_class.make<T>(n, seed + static_cast<std::uint64_t>(n));
      const WideVector<T> reference = refined_reference(system);
      const long double condition = condition_estimate(system);
      const Measurement lapack = measure_lapack(system, reference);
      auto add = [&](Method method, int threads) {
        Row row{matrix_class.name,
                method,
                threads,
                precision,
                n,
                condition,
                measure_tridiff(system, method, reference, threads),
                lapack,
                NAN,
                NAN};
        if (row.ours.outcome == Outcome::Solved && lapack.outcome == Outcome::Solved) {
          row.forward_ratio = ratio_to_lapack<T>(row.ours.forward, lapack.forward);
          row.backward_ratio = ratio_to_lapack<T>(row.ours.backward, lapack.backward);
        }
        rows.push_back(std::move(row));
      };
      for (Method method : kAllMethods) add(method, 1);
      for (Method method : kThreadedMethods) add(method, kPartitionedThreads);
    }
  }
}

void write_json(std::ostream& out, const std::vector<Row>& rows,
                const std::vector<std::ptrdiff_t>& sizes, std::uint64_t seed) {
  out << "{\n  \"seed\": " << seed << ",\n  \"sizes\": [";
  for (std::size_t i = 0; i < sizes.size(); ++i) out << (i ? ", " : "") << sizes[i];
  out << "],\n  \"ratio\": \"tridiff error / max(LAPACK error, eps of the precision)\",\n";
  out << "  \"classes\": [\n";
  const std::size_t classes = std::size(kStabilityClasses);
  for (std::size_t i = 0; i < classes; ++i)
    out << "    {\"name\": " << json_string(kStabilityClasses[i].name)
        << ", \"description\": " << json_string(kStabilityClasses[i].description) << "}"
        << (i + 1 < classes ? ",\n" : "\n");
  out << "  ],\n  \"rows\": [\n";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    out << "    {\"class\": " << json_string(r.matrix_class)
        << ", \"method\": " << json_string(to_string(r.method)) << ", \"threads\": " << r.threads
        << ", \"parts\": " << r.ours.parts << ", \"precision\": " << json_string(r.precision)
        << ", \"n\": " << r.n << ", \"outcome\": " << json_string(to_string(r.ours.outcome))
        << ", \"forward_error\": " << json_number(r.ours.forward)
        << ", \"backward_error\": " << json_number(r.ours.backward)
        << ", \"lapack_outcome\": " << json_string(to_string(r.lapack.outcome))
        << ", \"lapack_info\": " << r.lapack.info
        << ", \"lapack_forward_error\": " << json_number(r.lapack.forward)
        << ", \"lapack_backward_error\": " << json_number(r.lapack.backward)
        << ", \"forward_ratio\": " << json_number(r.forward_ratio)
        << ", \"backward_ratio\": " << json_number(r.backward_ratio)
        << ", \"kappa1_estimate\": " << json_number(r.condition)
        << ", \"message\": " << json_string(r.ours.message) << "}"
        << (i + 1 < rows.size() ? ",\n" : "\n");
  }
  out << "  ]\n}\n";
}

// One cell of the summary: the worst max(forward, backward) ratio over the sizes where both
// tridiff and LAPACK solved; then, for the other sizes, what happened: tridiff's outcome, or
// "L:<outcome>" where only LAPACK failed; "@n" unless it happened at every size.
std::string summary_cell(const std::vector<Row>& rows, std::string_view matrix_class, Method method,
                         int threads, std::string_view precision) {
  long double worst = -1;
  std::vector<std::pair<std::string, std::ptrdiff_t>> events;
  std::size_t sizes = 0;
  for (const Row& r : rows) {
    if (r.matrix_class != matrix_class || r.method != method || r.threads != threads ||
        r.precision != precision)
      continue;
    ++sizes;
    if (r.ours.outcome != Outcome::Solved)
      events.emplace_back(to_string(r.ours.outcome), r.n);
    else if (r.lapack.outcome != Outcome::Solved)
      events.emplace_back(std::string("L:") + to_string(r.lapack.outcome), r.n);
    else
      worst = std::max({worst, r.forward_ratio, r.backward_ratio});
  }
  std::string cell;
  if (worst >= 0) {
    char text[16];
    std::snprintf(text, sizeof text, "%.3Lg", worst);
    cell = text;
  }
  const bool everywhere = events.size() == sizes &&
                          std::all_of(events.begin(), events.end(),
                                      [&](const auto& e) { return e.first == events[0].first; });
  if (everywhere && !events.empty()) return events[0].first;
  for (const auto& [what, n] : events)
    cell += (cell.empty() ? "" : " ") + what + "@" + std::to_string(n);
  return cell;
}

void write_summary(std::ostream& out, const std::vector<Row>& rows) {
  out << "Worst ratio max(forward, backward) to LAPACK (floored at eps) over the sizes;\n"
         "outcome@n where tridiff did not solve, L:outcome@n where only LAPACK did not, the\n"
         "outcome alone if at every size. ratio <= 10 is the test's bound for auto.\n"
         "Columns x"
      << kPartitionedThreads << ": on " << kPartitionedThreads
      << " threads (partitioned Thomas at n >= 32768).\n";
  std::vector<std::pair<Method, int>> columns;
  for (Method method : kAllMethods) columns.emplace_back(method, 1);
  for (Method method : kThreadedMethods) columns.emplace_back(method, kPartitionedThreads);
  char line[256];
  std::snprintf(line, sizeof line, "%-27s %-6s", "class", "prec");
  out << line;
  for (const auto& [method, threads] : columns) {
    const std::string name =
        std::string(to_string(method)) + (threads > 1 ? " x" + std::to_string(threads) : "");
    std::snprintf(line, sizeof line, " %-10s", name.c_str());
    out << line;
  }
  out << "\n";
  for (const MatrixClass& matrix_class : kStabilityClasses) {
    for (const char* precision : {"float", "double"}) {
      std::snprintf(line, sizeof line, "%-27s %-6s", std::string(matrix_class.name).c_str(),
                    precision);
      out << line;
      for (const auto& [method, threads] : columns) {
        std::snprintf(line, sizeof line, " %-10s",
                      summary_cell(rows, matrix_class.name, method, threads, precision).c_str());
        out << line;
      }
      out << "\n";
    }
  }
}

std::vector<std::ptrdiff_t> parse_sizes(const std::string& text) {
  std::vector<std::ptrdiff_t> sizes;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    const long long n = std::stoll(item);
    if (n < 1) throw std::invalid_argument("sizes must be >= 1");
    sizes.push_back(static_cast<std::ptrdiff_t>(n));
  }
  return sizes;
}

}  // namespace

int main(int argc, char** argv) {
  std::string out_path;
  std::vector<std::ptrdiff_t> sizes = {16, 1000, 65537};
  std::uint64_t seed = 2024;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string_view arg = argv[i];
      if (arg == "--out" && i + 1 < argc) {
        out_path = argv[++i];
      } else if (arg == "--sizes" && i + 1 < argc) {
        sizes = parse_sizes(argv[++i]);
      } else if (arg == "--seed" && i + 1 < argc) {
        seed = std::stoull(argv[++i]);
      } else {
        std::cerr << "usage: tridiff_stability_table [--out FILE] [--sizes 16,1000,65537] "
                     "[--seed S]\n";
        return 2;
      }
    }
  } catch (const std::exception& error) {
    std::cerr << "tridiff_stability_table: bad argument: " << error.what() << "\n";
    return 2;
  }

  const auto start = std::chrono::steady_clock::now();
  std::vector<Row> rows;
  run_precision<float>("float", sizes, seed, rows);
  run_precision<double>("double", sizes, seed, rows);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  if (out_path.empty()) {
    write_json(std::cout, rows, sizes, seed);
  } else {
    std::ofstream file(out_path);
    write_json(file, rows, sizes, seed);
    if (!file) {
      std::cerr << "tridiff_stability_table: cannot write " << out_path << "\n";
      return 1;
    }
  }
  write_summary(std::cerr, rows);
  std::cerr << rows.size() << " rows in " << seconds << " s\n";
  return 0;
}
