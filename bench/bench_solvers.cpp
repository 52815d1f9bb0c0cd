// Speed of every tridiff method against its peer and its limit, all measured in this one binary
// so that the ratios between them are meaningful (absolute times drift between runs):
//   - tridiff::solve (general form: sub, diag, super, rhs -> x) and tridiff::solve_diffusion
//     (beta, rhs -> x), every Method, float and double, four shapes, 1 and 2 threads;
//   - the peer: LAPACK ?gtsv called once per system, the loop over systems split by OpenMP;
//   - the limit: STREAM-like copy and triad on float arrays far larger than the caches.
//
// Names: BM_solvers_<method>/<scalar>/<form>/<shape>/threads:<t>/real_time, where <method> is
// auto, thomas, cr, pcr, cr-pcr, pivoting (the library's names) or lapack_gtsv; <form> is diffusion, general, or
// general_unchecked (Thomas without the dominance check); <shape> is <layout>:<systems>x<n>:
// rows:4096x4096, columns:4096x4096, single:1x16777216, rows:1048576x16, and for the lines of a
// 256^3 grid along x, y and z (diffusion form, Thomas) grid-x:65536x256 and so on. For example
//   BM_solvers_thomas/float/diffusion/columns:4096x4096/threads:2/real_time
//   BM_solvers_lapack_gtsv/float/general/rows:4096x4096/threads:2/real_time
//   BM_solvers_stream_triad/float/array:67108864/threads:2/real_time
//   BM_solvers_stream_columns/float/lanes:64/threads:2/real_time  (the triad in the column
//     solve's order, 4096 x 4096: the ceiling of that access pattern)
//
// Counters (all rates use wall-clock time):
//   bytes_per_second    the arrays the method must move at least, each once (general form:
//                       sub, diag, super, rhs read and x written = 5 arrays; diffusion form:
//                       beta, rhs read and x written = 3 arrays; the LAPACK peer solves the
//                       general form and is counted as 5 arrays). STREAM counting: no
//                       write-allocate traffic.
//   systems_per_second, unknowns_per_second
//   triad_ratio         bytes_per_second / the STREAM triad bandwidth at the same thread count,
//                       measured once per thread count in this process (best of a few runs).
//   triad_bytes_per_second  that triad bandwidth, so every JSON record is self-contained.
// After the timed loop every result is checked (normwise backward error of a few systems);
// a benchmark whose solution is wrong reports an error instead of a time.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <initializer_list>
#include <limits>
#include <map>
#include <memory>
#include <new>
#include <random>
#include <string>
#include <vector>

#include <omp.h>

#include "lapack.hpp"
#include "tridiff/solvers.hpp"

namespace {

using std::ptrdiff_t;
using tridiff::BatchLayout;
using tridiff::Method;

// ---------------------------------------------------------------------------------------------
// Memory

// `size` scalars on a 64-byte boundary, allocated once and never resized.
template <class T>
class Array {
 public:
  explicit Array(ptrdiff_t size) : size_(size) {
    const std::size_t bytes = (static_cast<std::size_t>(size) * sizeof(T) + 63) / 64 * 64;
    data_.reset(static_cast<T*>(std::aligned_alloc(64, bytes)));
    if (!data_) throw std::bad_alloc();
  }
  T* data() const { return data_.get(); }
  ptrdiff_t size() const { return size_; }
  T& operator[](ptrdiff_t i) const { return data_.get()[i]; }

 private:
  struct Free {
    void operator()(T* p) const { std::free(p); }
  };
  std::unique_ptr<T, Free> data_;
  ptrdiff_t size_;
};

// ---------------------------------------------------------------------------------------------
// The limit: STREAM copy and triad

// 2^26 floats = 256 MiB per array, three arrays: far beyond every cache.
constexpr ptrdiff_t kStreamElements = ptrdiff_t(1) << 26;

struct StreamArrays {
  Array<float> a{kStreamElements}, b{kStreamElements}, c{kStreamElements};
  StreamArrays() {
    // Touch every page now so that no page fault lands in a timed region.
    std::fill_n(a.data(), kStreamElements, 1.0f);
    std::fill_n(b.data(), kStreamElements, 2.0f);
    std::fill_n(c.data(), kStreamElements, 0.5f);
  }
};

StreamArrays& stream_arrays() {
  static StreamArrays arrays;
  return arrays;
}

void stream_copy(const float* from, float* to, ptrdiff_t n, int threads) {
#pragma omp parallel for simd num_threads(threads) schedule(static)
  for (ptrdiff_t i = 0; i < n; ++i) to[i] = from[i];
}

void stream_triad(float* a, const float* b, const float* c, float s, ptrdiff_t n, int threads) {
#pragma omp parallel for simd num_threads(threads) schedule(static)
  for (ptrdiff_t i = 0; i < n; ++i) a[i] = b[i] + s * c[i];
}

// The triad in the order the lane kernels walk an image column: chunks of `lanes` columns of
// a side x side array, each chunk down all its rows, the chunks shared by the threads. With
// 64 float lanes (the column solve's chunk: 256 bytes a row, rows 16 KiB apart at side 4096)
// it is the most that access pattern moves; wider chunks show what the short runs cost.
void stream_triad_columns(float* a, const float* b, const float* c, float s, ptrdiff_t side,
                          ptrdiff_t lanes, int threads) {
#pragma omp parallel for num_threads(threads) schedule(static)
  for (ptrdiff_t first = 0; first < side; first += lanes)
    for (ptrdiff_t i = 0; i < side; ++i) {
      const ptrdiff_t row = i * side + first;
#pragma omp simd
      for (ptrdiff_t l = 0; l < lanes; ++l) a[row + l] = b[row + l] + s * c[row + l];
    }
}

// STREAM counting: copy reads one array and writes one, triad reads two and writes one.
constexpr double kCopyBytes = 2.0 * sizeof(float) * kStreamElements;
constexpr double kTriadBytes = 3.0 * sizeof(float) * kStreamElements;

// The triad bandwidth at `threads` threads, measured the first time it is asked for and kept
// for the rest of the process: the best of at least 10 runs spread over at least half a second,
// as STREAM reports the best (on a shared machine, noise only ever makes a run slower).
double triad_bytes_per_second(int threads) {
  static std::map<int, double> measured;
  if (auto found = measured.find(threads); found != measured.end()) return found->second;
  StreamArrays& s = stream_arrays();
  double best = std::numeric_limits<double>::max();
  const double begin = omp_get_wtime();
  for (int run = 0; run < 10 || omp_get_wtime() - begin < 0.5; ++run) {
    const double start = omp_get_wtime();
    stream_triad(s.a.data(), s.b.data(), s.c.data(), 3.0f, kStreamElements, threads);
    best = std::min(best, omp_get_wtime() - start);
  }
  return measured[threads] = kTriadBytes / best;
}

// Sets the rate counters of a benchmark that moved `bytes` per iteration, solving `systems`
// systems of `unknowns` unknowns in all.
void set_counters(benchmark::State& state, double bytes, double systems, double unknowns,
                  int threads) {
  using benchmark::Counter;
  const double iterations = static_cast<double>(state.iterations());
  const double triad = triad_bytes_per_second(threads);
  state.counters["bytes_per_second"] = Counter(iterations * bytes, Counter::kIsRate);
  // A rate too (bytes per second / triad bytes per second), hence the "/s" on the console.
  state.counters["triad_ratio"] = Counter(iterations * bytes / triad, Counter::kIsRate);
  state.counters["triad_bytes_per_second"] = Counter(triad);
  if (systems > 0) {
    state.counters["systems_per_second"] = Counter(iterations * systems, Counter::kIsRate);
    state.counters["unknowns_per_second"] = Counter(iterations * unknowns, Counter::kIsRate);
  }
}

void bm_stream_copy(benchmark::State& state, int threads) {
  StreamArrays& s = stream_arrays();
  triad_bytes_per_second(threads);  // measured before timing, not in the middle of it
  for (auto _ : state) {
    stream_copy(s.a.data(), s.b.data(), kStreamElements, threads);
    benchmark::ClobberMemory();
  }
  set_counters(state, kCopyBytes, 0, 0, threads);
}

void bm_stream_triad(benchmark::State& state, int threads) {
  StreamArrays& s = stream_arrays();
  triad_bytes_per_second(threads);
  for (auto _ : state) {
    stream_triad(s.a.data(), s.b.data(), s.c.data(), 3.0f, kStreamElements, threads);
    benchmark::ClobberMemory();
  }
  set_counters(state, kTriadBytes, 0, 0, threads);
}

// The column-order triad on the first 4096 x 4096 floats of the STREAM arrays.
constexpr ptrdiff_t kColumnSide = 4096;
static_assert(kColumnSide * kColumnSide <= kStreamElements);

void bm_stream_columns(benchmark::State& state, ptrdiff_t lanes, int threads) {
  StreamArrays& s = stream_arrays();
  triad_bytes_per_second(threads);
  for (auto _ : state) {
    stream_triad_columns(s.a.data(), s.b.data(), s.c.data(), 3.0f, kColumnSide, lanes, threads);
    benchmark::ClobberMemory();
  }
  set_counters(state, 3.0 * sizeof(float) * kColumnSide * kColumnSide, 0, 0, threads);
}

// ---------------------------------------------------------------------------------------------
// The problems

// Every shape holds 2^24 unknowns, so one set of arrays per scalar type serves them all.
constexpr ptrdiff_t kElements = ptrdiff_t(1) << 24;

enum class Shape { Rows, Columns, Single, Tiny };
constexpr Shape kShapes[] = {Shape::Rows, Shape::Columns, Shape::Single, Shape::Tiny};

BatchLayout layout_of(Shape shape) {
  switch (shape) {
    case Shape::Rows: return BatchLayout::rows(4096, 4096, 4096);        // image rows
    case Shape::Columns: return BatchLayout::columns(4096, 4096, 4096);  // image columns
    case Shape::Single: return BatchLayout::single(kElements);           // one long system
    case Shape::Tiny: return BatchLayout::rows(16, kElements / 16, 16);  // many tiny systems
  }
  return {};
}

std::string name_of(Shape shape) {
  const BatchLayout layout = layout_of(shape);
  const char* kind = shape == Shape::Columns  ? "columns"
                     : shape == Shape::Single ? "single"
                                              : "rows";
  return std::string(kind) + ":" + std::to_string(layout.count) + "x" + std::to_string(layout.n);
}

// One implicit diffusion step (the ANCHORS.md matrix): beta random in [0.1, 10], rhs random
// in [0, 1]; in the general form a_i = -beta_{i-1}, c_i = -beta_i, b_i = 1 + beta_{i-1} + beta_i
// with insulated ends (beta_{-1} = beta_{n-1} = 0): strictly diagonally dominant.
// beta, rhs and x serve every shape of one scalar type.
template <class T>
struct Problem {
  Array<T> beta{kElements}, rhs{kElements}, x{kElements};

  Problem() {
    std::mt19937 random(42);
    std::uniform_real_distribution<double> conductance(0.1, 10.0), value(0.0, 1.0);
    for (ptrdiff_t i = 0; i < kElements; ++i) beta[i] = static_cast<T>(conductance(random));
    for (ptrdiff_t i = 0; i < kElements; ++i) rhs[i] = static_cast<T>(value(random));
    std::fill_n(x.data(), kElements, T(0));
  }

  // The coefficients of row i of system s: its neighbours are along the system, which is a
  // memory row or a memory column depending on the layout.
  T left(const BatchLayout& layout, ptrdiff_t s, ptrdiff_t i) const {
    return i > 0 ? beta[layout.offset(s, i - 1)] : T(0);
  }
  T right(const BatchLayout& layout, ptrdiff_t s, ptrdiff_t i) const {
    return i + 1 < layout.n ? beta[layout.offset(s, i)] : T(0);
  }
};

template <class T>
Problem<T>& problem() {
  static Problem<T> instance;
  return instance;
}

// The same matrix in the general form, laid out for one shape.
template <class T>
struct Diagonals {
  Array<T> sub{kElements}, diag{kElements}, super{kElements};

  Diagonals(const Problem<T>& p, const BatchLayout& layout) {
    for (ptrdiff_t s = 0; s < layout.count; ++s)
      for (ptrdiff_t i = 0; i < layout.n; ++i) {
        const ptrdiff_t o = layout.offset(s, i);
        const T left = p.left(layout, s, i), right = p.right(layout, s, i);
        sub[o] = -left;
        diag[o] = 1 + left + right;
        super[o] = -right;
      }
  }
};

// Built on first use and kept for the whole process (0.75 GiB per shape in double), so that
// benchmarks can run in any order, interleaved, without rebuilding them.
template <class T>
const Diagonals<T>& diagonals(Shape shape) {
  static std::map<Shape, std::unique_ptr<Diagonals<T>>> built;
  auto& entry = built[shape];
  if (!entry) entry = std::make_unique<Diagonals<T>>(problem<T>(), layout_of(shape));
  return *entry;
}

// Largest normwise backward error |Ax - d|_i / (|A||x| + |d|)_i over the rows of three
// systems (all rows of a single system): catches a broken kernel, not a rounding difference.
template <class T>
double backward_error(const Problem<T>& p, const BatchLayout& layout) {
  double worst = 0;
  for (ptrdiff_t s : {ptrdiff_t(0), layout.count / 2, layout.count - 1})
    for (ptrdiff_t i = 0; i < layout.n; ++i) {
      const ptrdiff_t o = layout.offset(s, i);
      const double left = p.left(layout, s, i), right = p.right(layout, s, i);
      const double x_left = i > 0 ? double(p.x[layout.offset(s, i - 1)]) : 0;
      const double x_right = i + 1 < layout.n ? double(p.x[layout.offset(s, i + 1)]) : 0;
      const double terms[] = {-left * x_left, (1 + left + right) * double(p.x[o]), -right * x_right,
                              -double(p.rhs[o])};
      double residual = 0, scale = 0;
      for (double term : terms) {
        residual += term;
        scale += std::abs(term);
      }
      worst = std::max(worst, std::abs(residual) / std::max(scale, 1e-300));
    }
  return worst;
}

// Marks the benchmark failed if the last solution in p.x is wrong.
template <class T>
void check_solution(benchmark::State& state, const Problem<T>& p, const BatchLayout& layout) {
  const double tolerance = 1000 * std::numeric_limits<T>::epsilon();
  const double error = backward_error(p, layout);
  if (!(error <= tolerance))
    state.SkipWithError(("wrong solution: backward error " + std::to_string(error)).c_str());
}

// ---------------------------------------------------------------------------------------------
// tridiff

// The three ways of calling tridiff that are measured.
enum class Form {
  Diffusion,         // solve_diffusion(beta, rhs, x): 3 arrays
  General,           // solve(sub, diag, super, rhs, x) with the default options: 5 arrays
  GeneralUnchecked,  // the same with check_dominance cleared (pivot-free methods only): the
                     // cost of the solve alone, for a caller who knows the matrix is dominant
};

const char* name_of(Form form) {
  switch (form) {
    case Form::Diffusion: return "diffusion";
    case Form::General: return "general";
    case Form::GeneralUnchecked: return "general_unchecked";
  }
  return "unknown";
}

template <class T>
void bm_tridiff(benchmark::State& state, Method method, Form form, Shape shape, int threads) {
  Problem<T>& p = problem<T>();
  const BatchLayout layout = layout_of(shape);
  const Diagonals<T>* m = form == Form::Diffusion ? nullptr : &diagonals<T>(shape);
  tridiff::SolveOptions options;
  options.method = method;
  options.threads = threads;
  options.check_dominance = form != Form::GeneralUnchecked;
  triad_bytes_per_second(threads);  // measured before timing, not in the middle of it
  try {
    for (auto _ : state) {
      if (m == nullptr)
        tridiff::solve_diffusion(p.beta.data(), p.rhs.data(), p.x.data(), layout, options);
      else
        tridiff::solve(m->sub.data(), m->diag.data(), m->super.data(), p.rhs.data(), p.x.data(),
                       layout, options);
      benchmark::ClobberMemory();
    }
  } catch (const std::exception& error) {
    state.SkipWithError(error.what());
    return;
  }
  check_solution(state, p, layout);
  const double arrays = form == Form::Diffusion ? 3 : 5;
  set_counters(state, arrays * sizeof(T) * kElements, double(layout.count), double(kElements),
               threads);
}

// ---------------------------------------------------------------------------------------------
// The peer: LAPACK ?gtsv (partial pivoting), once per system

int gtsv(int n, float* dl, float* d, float* du, float* b) {
  const int nrhs = 1;
  int info = 0;
  sgtsv_(&n, &nrhs, dl, d, du, b, &n, &info);
  return info;
}

int gtsv(int n, double* dl, double* d, double* du, double* b) {
  const int nrhs = 1;
  int info = 0;
  dgtsv_(&n, &nrhs, dl, d, du, b, &n, &info);
  return info;
}

// ?gtsv overwrites its three diagonals (with the LU factors) and its right-hand side (with the
// solution), so the inputs are copied first. How, per layout:
//  - rows (contiguous systems of n = 4096 or 16): each system's diagonals are copied into a
//    per-thread scratch and its rhs into x, and ?gtsv solves in x. The copy is inside the timed
//    region, part of the peer's cost as it is for a user who keeps the matrix. It touches only
//    cache (the scratch is reused), so it adds no memory traffic; copying the whole batch
//    outside the timed region instead would make ?gtsv write the overwritten diagonals back to
//    memory (8 arrays moved instead of 5), so the per-system copy is the faster choice for it.
//  - columns: ?gtsv needs contiguous systems, so each thread gathers a block of columns one
//    cache line wide (16 float or 8 double columns, so every line read is used whole) into its
//    scratch, solves them there and scatters the solutions into x. That transpose is timed: it
//    is what a user with column data must do.
//  - single (one system of 2^24, far larger than the caches): the diagonals are copied into the
//    scratch and rhs into x with the timer paused; ?gtsv pays only for its own passes.
template <class T>
struct GtsvScratch {
  std::vector<Array<T>> per_thread;
  GtsvScratch(int threads, ptrdiff_t size) {
    for (int t = 0; t < threads; ++t) per_thread.emplace_back(size);
  }
  T* of_this_thread() const { return per_thread[omp_get_thread_num()].data(); }
};

// Solves contiguous systems (rows layout) one by one; returns the number that failed.
template <class T>
int gtsv_rows(const Diagonals<T>& m, const T* rhs, T* x, const BatchLayout& layout,
              const GtsvScratch<T>& scratch, int threads) {
  const ptrdiff_t n = layout.n;
  int failures = 0;
#pragma omp parallel num_threads(threads) reduction(+ : failures)
  {
    T* dl = scratch.of_this_thread();
    T* d = dl + n;
    T* du = d + n;
#pragma omp for schedule(static)
    for (ptrdiff_t s = 0; s < layout.count; ++s) {
      const ptrdiff_t o = layout.offset(s, 0);
      std::memcpy(dl, m.sub.data() + o + 1, (n - 1) * sizeof(T));  // LAPACK's dl(i) is a_{i+1}
      std::memcpy(d, m.diag.data() + o, n * sizeof(T));
      std::memcpy(du, m.super.data() + o, (n - 1) * sizeof(T));
      std::memcpy(x + o, rhs + o, n * sizeof(T));
      failures += gtsv(int(n), dl, d, du, x + o) != 0;
    }
  }
  return failures;
}

// Columns one cache line wide per block: their elements in one memory row share a line.
template <class T>
constexpr ptrdiff_t kColumnBlock = 64 / sizeof(T);

// Distance between the systems of a block in the scratch: n plus one cache line, so that the
// 4 x kColumnBlock lines written per memory row do not all fall in the same cache set (with a
// distance of exactly n = 4096 they would, and the gather would thrash L1).
template <class T>
ptrdiff_t column_scratch_stride(ptrdiff_t n) {
  return n + kColumnBlock<T>;
}

// Solves the systems of a columns layout: gather a block of columns, solve each, scatter.
template <class T>
int gtsv_columns(const Diagonals<T>& m, const T* rhs, T* x, const BatchLayout& layout,
                 const GtsvScratch<T>& scratch, int threads) {
  const ptrdiff_t n = layout.n, pitch = layout.row_stride, block = kColumnBlock<T>;
  const ptrdiff_t ld = column_scratch_stride<T>(n), blocks = (layout.count + block - 1) / block;
  int failures = 0;
#pragma omp parallel num_threads(threads) reduction(+ : failures)
  {
    // Four arrays of block systems, system l of the block at l * ld.
    T* a = scratch.of_this_thread();
    T* b = a + block * ld;
    T* c = b + block * ld;
    T* d = c + block * ld;
#pragma omp for schedule(static)
    for (ptrdiff_t k = 0; k < blocks; ++k) {
      const ptrdiff_t first = k * block, width = std::min(block, layout.count - first);
      for (ptrdiff_t i = 0; i < n; ++i)
        for (ptrdiff_t l = 0; l < width; ++l) {
          const ptrdiff_t o = i * pitch + first + l;
          a[l * ld + i] = m.sub[o];
          b[l * ld + i] = m.diag[o];
          c[l * ld + i] = m.super[o];
          d[l * ld + i] = rhs[o];
        }
      for (ptrdiff_t l = 0; l < width; ++l)
        failures += gtsv(int(n), a + l * ld + 1, b + l * ld, c + l * ld, d + l * ld) != 0;
      for (ptrdiff_t i = 0; i < n; ++i)
        for (ptrdiff_t l = 0; l < width; ++l) x[i * pitch + first + l] = d[l * ld + i];
    }
  }
  return failures;
}

// One system: the copy of the inputs is made with the timer paused (see above).
template <class T>
int gtsv_single(benchmark::State& state, const Diagonals<T>& m, const T* rhs, T* x, ptrdiff_t n,
                const GtsvScratch<T>& scratch) {
  state.PauseTiming();
  T* dl = scratch.per_thread[0].data();
  T* d = dl + n;
  T* du = d + n;
  std::memcpy(dl, m.sub.data() + 1, (n - 1) * sizeof(T));
  std::memcpy(d, m.diag.data(), n * sizeof(T));
  std::memcpy(du, m.super.data(), (n - 1) * sizeof(T));
  std::memcpy(x, rhs, n * sizeof(T));
  state.ResumeTiming();
  return gtsv(int(n), dl, d, du, x) != 0;
}

template <class T>
void bm_lapack_gtsv(benchmark::State& state, Shape shape, int threads) {
  Problem<T>& p = problem<T>();
  const Diagonals<T>& m = diagonals<T>(shape);
  const BatchLayout layout = layout_of(shape);
  const GtsvScratch<T> scratch(
      threads, shape == Shape::Columns ? 4 * kColumnBlock<T> * column_scratch_stride<T>(layout.n)
                                       : 3 * layout.n);
  triad_bytes_per_second(threads);
  int failures = 0;
  for (auto _ : state) {
    if (shape == Shape::Single)
      failures += gtsv_single(state, m, p.rhs.data(), p.x.data(), layout.n, scratch);
    else if (shape == Shape::Columns)
      failures += gtsv_columns(m, p.rhs.data(), p.x.data(), layout, scratch, threads);
    else
      failures += gtsv_rows(m, p.rhs.data(), p.x.data(), layout, scratch, threads);
    benchmark::ClobberMemory();
  }
  if (failures > 0) return state.SkipWithError("?gtsv reported a singular system");
  check_solution(state, p, layout);
  set_counters(state, 5.0 * sizeof(T) * kElements, double(layout.count), double(kElements),
               threads);
}

// ---------------------------------------------------------------------------------------------
// The lines of a 3-D grid: the problem's arrays as a 256^3 grid (x fastest), the diffusion form
// solved along one axis in one call (BatchLayout::grid_lines), as an ADI step on a 3-D grid
// does. Axis x is the rows layout, y the columns of each xy plane, z the columns of the whole
// grid (the systems 256 elements apart in two batch dimensions, x then y).

constexpr ptrdiff_t kGridSide = 256;
static_assert(kGridSide * kGridSide * kGridSide == kElements, "the grid reuses the problem");

BatchLayout grid_layout(int axis) {
  const ptrdiff_t extent[3] = {kGridSide, kGridSide, kGridSide};
  const ptrdiff_t stride[3] = {1, kGridSide, kGridSide * kGridSide};
  return BatchLayout::grid_lines(extent, stride, axis);
}

template <class T>
void bm_grid_diffusion(benchmark::State& state, int axis, int threads) {
  Problem<T>& p = problem<T>();
  const BatchLayout layout = grid_layout(axis);
  triad_bytes_per_second(threads);  // measured before timing, not in the middle of it
  tridiff::SolveOptions options;
  options.threads = threads;
  try {
    for (auto _ : state) {
      solve_diffusion(p.beta.data(), p.rhs.data(), p.x.data(), layout, options);
      benchmark::ClobberMemory();
    }
  } catch (const std::exception& error) {
    return state.SkipWithError(error.what());
  }
  check_solution(state, p, layout);
  set_counters(state, 3.0 * sizeof(T) * kElements, double(layout.systems()), double(kElements),
               threads);
}

// ---------------------------------------------------------------------------------------------
// Registration

constexpr int kThreadCounts[] = {1, 2};

// The cyclic reduction family solves each system serially (per-system reference code, O(n),
// or O(n log n) for PCR) and took 3-5 s per solve of the single system of 2^24 in float; one
// system runs on one thread in these methods whatever SolveOptions::threads says. So for them
// the single shape is registered with 1 thread only: threads:2 would repeat the same
// measurement at that price. The other methods and the LAPACK peer keep threads:2 there, which
// shows whether one long system gains from a second thread.
bool is_reduction(Method method) { return method_row(method).reduction; }

// Every benchmark is timed on the wall clock: the work runs on OpenMP threads, and the CPU
// time Google Benchmark measures is the main thread's alone.
void finish(benchmark::internal::Benchmark* benchmark) {
  benchmark->UseRealTime()->Unit(benchmark::kMillisecond);
}

// Joins name parts with '/'. (Appending rather than `"literal" + std::string` avoids a false
// -Wrestrict of g++ 12.)
std::string join(std::initializer_list<std::string> parts) {
  std::string name;
  for (const std::string& part : parts) {
    if (!name.empty()) name += '/';
    name += part;
  }
  return name;
}

std::string threads_arg(int threads) { return "threads:" + std::to_string(threads); }

template <class T>
void register_solvers(const std::string& scalar) {
  for (Shape shape : kShapes) {
    for (int threads : kThreadCounts) {
      finish(benchmark::RegisterBenchmark(
          join({"BM_solvers_lapack_gtsv", scalar, "general", name_of(shape), threads_arg(threads)})
              .c_str(),
          bm_lapack_gtsv<T>, shape, threads));
      for (Form form : {Form::Diffusion, Form::General, Form::GeneralUnchecked}) {
        for (Method method : tridiff::kAllMethods) {
          if (form == Form::GeneralUnchecked && method != Method::Thomas) continue;
          if (shape == Shape::Single && threads > 1 && is_reduction(method)) continue;
          const std::string name = join({std::string("BM_solvers_") + to_string(method), scalar,
                                         name_of(form), name_of(shape), threads_arg(threads)});
          finish(benchmark::RegisterBenchmark(name.c_str(), bm_tridiff<T>, method, form, shape,
                                              threads));
        }
      }
    }
  }
}

void register_all() {
  const std::string array = "array:" + std::to_string(kStreamElements);
  for (int threads : kThreadCounts) {
    finish(benchmark::RegisterBenchmark(
        join({"BM_solvers_stream_copy", "float", array, threads_arg(threads)}).c_str(),
        bm_stream_copy, threads));
    finish(benchmark::RegisterBenchmark(
        join({"BM_solvers_stream_triad", "float", array, threads_arg(threads)}).c_str(),
        bm_stream_triad, threads));
    for (const ptrdiff_t lanes : {64, 256, 1024})
      finish(benchmark::RegisterBenchmark(
          join({"BM_solvers_stream_columns", "float", "lanes:" + std::to_string(lanes),
                threads_arg(threads)})
              .c_str(),
          bm_stream_columns, lanes, threads));
  }
  register_solvers<float>("float");
  register_solvers<double>("double");
  for (int axis = 0; axis < 3; ++axis)
    for (int threads : kThreadCounts) {
      const std::string shape = std::string("grid-") + "xyz"[axis] + ":" +
                                std::to_string(kGridSide * kGridSide) + "x" +
                                std::to_string(kGridSide);
      finish(benchmark::RegisterBenchmark(
          join({"BM_solvers_thomas", "float", "diffusion", shape, threads_arg(threads)}).c_str(),
          bm_grid_diffusion<float>, axis, threads));
    }
}

}  // namespace

int main(int argc, char** argv) {
  register_all();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

// ---------------------------------------------------------------------------------------------
// Factor once, solve many (tridiff/solvers/factor.hpp, refine.hpp)
//
//   BM_solvers_factored/<scalar>/general/<shape>/threads:<t>   solve(factors, rhs, x) with the
//       factors made once outside the timed loop; bytes: the three factor arrays (no pivoting
//       for this dominant matrix), rhs and x = 5 arrays.
//   BM_solvers_lapack_gttrs/<scalar>/general/rows:...            ?gttrs once per system on
//       ?gttrf's factors made outside the loop (rhs copied into x first, in place there);
//       bytes: dl, d, du, du2, ipiv, rhs, x = its 7 arrays.
//   BM_solvers_mixed/double/general/<shape>/threads:<t>         solve_mixed with float factors
//       made outside the loop: a float solve refined to a double backward error; bytes
//       counted as the double problem's 5 arrays, to compare with the double solves.
// Registered at static initialisation, so that this section needs no line elsewhere.

namespace {

template <class T>
void bm_factored(benchmark::State& state, Shape shape, int threads) {
  Problem<T>& p = problem<T>();
  const Diagonals<T>& m = diagonals<T>(shape);
  const BatchLayout layout = layout_of(shape);
  tridiff::FactorOptions factor_options;
  factor_options.threads = threads;
  const auto factors =
      tridiff::factor(m.sub.data(), m.diag.data(), m.super.data(), layout, factor_options);
  tridiff::FactoredSolveOptions options;
  options.threads = threads;
  triad_bytes_per_second(threads);
  for (auto _ : state) {
    tridiff::solve(factors, p.rhs.data(), p.x.data(), layout, options);
    benchmark::ClobberMemory();
  }
  check_solution(state, p, layout);
  set_counters(state, 5.0 * sizeof(T) * kElements, double(layout.count), double(kElements),
               threads);
}

void gttrf(int n, float* dl, float* d, float* du, float* du2, int* ipiv) {
  int info = 0;
  sgttrf_(&n, dl, d, du, du2, ipiv, &info);
}
void gttrf(int n, double* dl, double* d, double* du, double* du2, int* ipiv) {
  int info = 0;
  dgttrf_(&n, dl, d, du, du2, ipiv, &info);
}
void gttrs(int n, const float* dl, const float* d, const float* du, const float* du2,
           const int* ipiv, float* b) {
  const int nrhs = 1;
  int info = 0;
  sgttrs_("N", &n, &nrhs, dl, d, du, du2, ipiv, b, &n, &info, 1);
}
void gttrs(int n, const double* dl, const double* d, const double* du, const double* du2,
           const int* ipiv, double* b) {
  const int nrhs = 1;
  int info = 0;
  dgttrs_("N", &n, &nrhs, dl, d, du, du2, ipiv, b, &n, &info, 1);
}

// The rows shape only: ?gttrs needs contiguous systems.
template <class T>
void bm_lapack_gttrs(benchmark::State& state, int threads) {
  Problem<T>& p = problem<T>();
  const Diagonals<T>& m = diagonals<T>(Shape::Rows);
  const BatchLayout layout = layout_of(Shape::Rows);
  const ptrdiff_t n = layout.n;
  Array<T> dl(kElements), d(kElements), du(kElements), du2(kElements);
  Array<int> ipiv(kElements);
#pragma omp parallel for num_threads(threads) schedule(static)
  for (ptrdiff_t s = 0; s < layout.count; ++s) {
    const ptrdiff_t o = layout.offset(s, 0);
    std::memcpy(dl.data() + o, m.sub.data() + o + 1, (n - 1) * sizeof(T));
    std::memcpy(d.data() + o, m.diag.data() + o, n * sizeof(T));
    std::memcpy(du.data() + o, m.super.data() + o, (n - 1) * sizeof(T));
    gttrf(int(n), dl.data() + o, d.data() + o, du.data() + o, du2.data() + o, ipiv.data() + o);
  }
  triad_bytes_per_second(threads);
  for (auto _ : state) {
#pragma omp parallel for num_threads(threads) schedule(static)
    for (ptrdiff_t s = 0; s < layout.count; ++s) {
      const ptrdiff_t o = layout.offset(s, 0);
      std::memcpy(p.x.data() + o, p.rhs.data() + o, n * sizeof(T));
      gttrs(int(n), dl.data() + o, d.data() + o, du.data() + o, du2.data() + o, ipiv.data() + o,
            p.x.data() + o);
    }
    benchmark::ClobberMemory();
  }
  check_solution(state, p, layout);
  set_counters(state, (6.0 * sizeof(T) + sizeof(int)) * kElements, double(layout.count),
               double(kElements), threads);
}

void bm_mixed(benchmark::State& state, Shape shape, int threads) {
  Problem<double>& p = problem<double>();
  const Diagonals<double>& m = diagonals<double>(shape);
  const BatchLayout layout = layout_of(shape);
  tridiff::FactorOptions factor_options;
  factor_options.threads = threads;
  const auto factors = tridiff::factor_as<float>(m.sub.data(), m.diag.data(), m.super.data(),
                                                 layout, factor_options);
  tridiff::MixedOptions options;
  options.threads = threads;
  triad_bytes_per_second(threads);
  std::ptrdiff_t not_converged = 0;
  for (auto _ : state) {
    not_converged += tridiff::solve_mixed(factors, m.sub.data(), m.diag.data(), m.super.data(),
                                          p.rhs.data(), p.x.data(), layout, options)
                         .not_converged;
    benchmark::ClobberMemory();
  }
  if (not_converged > 0) return state.SkipWithError("mixed precision did not converge");
  // A double backward error, not just a correct answer: check_solution's bound is looser.
  const double error = backward_error(p, layout);
  if (!(error <= 8 * std::numeric_limits<double>::epsilon()))
    return state.SkipWithError(("backward error " + std::to_string(error)).c_str());
  set_counters(state, 5.0 * sizeof(double) * kElements, double(layout.count), double(kElements),
               threads);
}

[[maybe_unused]] const bool kFactoredRegistered = [] {
  for (Shape shape : {Shape::Rows, Shape::Columns})
    for (int threads : kThreadCounts) {
      const std::string where = name_of(shape), t = threads_arg(threads);
      finish(benchmark::RegisterBenchmark(
          join({"BM_solvers_factored", "float", "general", where, t}).c_str(), bm_factored<float>,
          shape, threads));
      finish(benchmark::RegisterBenchmark(
          join({"BM_solvers_factored", "double", "general", where, t}).c_str(), bm_factored<double>,
          shape, threads));
      finish(benchmark::RegisterBenchmark(
          join({"BM_solvers_mixed", "double", "general", where, t}).c_str(), bm_mixed, shape,
          threads));
      if (shape == Shape::Rows) {
        finish(benchmark::RegisterBenchmark(
            join({"BM_solvers_lapack_gttrs", "float", "general", where, t}).c_str(),
            bm_lapack_gttrs<float>, threads));
        finish(benchmark::RegisterBenchmark(
            join({"BM_solvers_lapack_gttrs", "double", "general", where, t}).c_str(),
            bm_lapack_gttrs<double>, threads));
      }
    }
  return true;
}();

}  // namespace
