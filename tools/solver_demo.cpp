// Solves a built-in batch — one implicit diffusion step on every row and then every column of
// a 4096 x 4096 float field — and prints the error against a double-precision solve of the
// same systems, and the speed in systems and bytes per second.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "tridiff/solvers.hpp"

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Largest |x - reference| / max|reference| over `systems` rows, reference in double.
double row_error(const std::vector<float>& beta, const std::vector<float>& rhs,
                 const std::vector<float>& x, std::ptrdiff_t n, std::ptrdiff_t systems) {
  std::vector<double> beta_d(beta.begin(), beta.begin() + n * systems);
  std::vector<double> rhs_d(rhs.begin(), rhs.begin() + n * systems);
  std::vector<double> ref(n * systems);
  tridiff::SolveOptions options;
  options.method = tridiff::Method::Pivoting;  // a different algorithm as the yardstick
  tridiff::solve_diffusion(beta_d.data(), rhs_d.data(), ref.data(),
                           tridiff::BatchLayout::rows(n, systems, n), options);
  double worst = 0, scale = 0;
  for (std::ptrdiff_t i = 0; i < n * systems; ++i) {
    worst = std::max(worst, std::abs(double(x[i]) - ref[i]));
    scale = std::max(scale, std::abs(ref[i]));
  }
  return worst / scale;
}

}  // namespace

int main() {
  const std::ptrdiff_t n = 4096;
  std::mt19937 random(42);
  std::uniform_real_distribution<float> conductance(0.1f, 10.f), value(0.f, 1.f);
  std::vector<float> beta(n * n), field(n * n), x(n * n);
  for (auto& b : beta) b = conductance(random);
  for (auto& v : field) v = value(random);

  std::printf("tridiff solver demo: implicit diffusion step, %td x %td float, beta in [0.1, 10]\n",
              n, n);
  const auto rows = tridiff::BatchLayout::rows(n, n, n);
  const auto columns = tridiff::BatchLayout::columns(n, n, n);
  for (int repeat = 0; repeat < 3; ++repeat) {
    auto start = std::chrono::steady_clock::now();
    tridiff::solve_diffusion(beta.data(), field.data(), x.data(), rows);
    const double row_time = seconds_since(start);
    start = std::chrono::steady_clock::now();
    tridiff::solve_diffusion(beta.data(), x.data(), x.data(), columns);
    const double column_time = seconds_since(start);
    const double bytes = 3.0 * sizeof(float) * n * n;  // beta and rhs read, x written
    if (repeat == 2)
      std::printf("rows:    %7.2f ms  %6.1f GB/s\ncolumns: %7.2f ms  %6.1f GB/s\n", row_time * 1e3,
                  bytes / row_time * 1e-9, column_time * 1e3, bytes / column_time * 1e-9);
  }
  tridiff::solve_diffusion(beta.data(), field.data(), x.data(), rows);
  std::printf("relative error of the row solve against double precision (64 rows): %.2e\n",
              row_error(beta, field, x, n, 64));
  return 0;
}
