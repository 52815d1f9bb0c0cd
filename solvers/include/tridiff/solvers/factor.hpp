// Factor once, solve many: the LU factors of a whole batch of tridiagonal systems, kept for
// repeated solves with new right-hand sides (the steps of an ADI scheme, a spline refit), as
// LAPACK ?gttrf/?gttrs and MKL's dttrfb/dttrsb give for one system.
//
// Storage: systems are grouped in chunks of detail::kLanes<T> (64 float, 32 double, ...), each
// chunk's factors interleaved one SIMD lane per system, whatever the layout of the input: a
// solve then streams the factors with vector loads and no transposes. A chunk whose systems
// are all diagonally dominant stores the factors of elimination without pivoting; otherwise it
// stores the partial-pivoting factors of ?gttrf. Memory per system of n rows:
//   no pivoting:   3 n scalars (sub-diagonal, inverse pivots, unit upper super-diagonal)
//   pivoting:      4 n scalars + n bytes (multipliers, inverse pivots, two super-diagonals,
//                  interchanges)
// plus one real (the matrix's 1-norm, for condition estimates). The last chunk is padded to a
// whole chunk with identity systems.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

#include "tridiff/solvers/detail/factored.hpp"
#include "tridiff/solvers/solve.hpp"

namespace tridiff {

using detail::Apply;  // Apply::Matrix (A x = b), Apply::Transpose, Apply::Adjoint (A^H x = b)

enum class Factorization {
  Auto,        // no pivoting for chunks of diagonally dominant systems, pivoting otherwise
  NoPivoting,  // refuses a system that is not diagonally dominant (NumericalError)
  Pivoting,    // partial pivoting (?gttrf) for every system
};

struct FactorOptions {
  Factorization method = Factorization::Auto;
  int threads = 0;  // 0: all cores
};

// Several right-hand sides per system: right-hand side j of system s, row i, is at
// s * system_stride + i * row_stride + j * rhs_stride of rhs and of x. rhs_stride must step
// over the whole batch (at least layout.extent()), as LAPACK's ldb for one system.
struct FactoredSolveOptions {
  Apply apply = Apply::Matrix;
  std::ptrdiff_t nrhs = 1;
  std::ptrdiff_t rhs_stride = 0;  // 0: layout.extent()
  int threads = 0;                // 0: all cores
};

template <class T>
class TridiagonalFactors {
 public:
  using Real = real_t<T>;
  static constexpr int kChunk = detail::kLanes<T>;

  TridiagonalFactors() = default;

  std::ptrdiff_t n() const { return n_; }
  std::ptrdiff_t count() const { return count_; }
  // Whether system s was factored with partial pivoting.
  bool pivoted(std::ptrdiff_t s) const {
    return chunks_[s / kChunk].kind == detail::FactorKind::Pivoting;
  }
  // ||A||_1 of system s (largest column sum of magnitudes), as ?gtcon needs it.
  Real norm1(std::ptrdiff_t s) const { return norm1_[s]; }
  // Bytes of factor storage in all.
  std::ptrdiff_t bytes() const {
    std::ptrdiff_t total = std::ptrdiff_t(norm1_.size() * sizeof(Real));
    for (const Chunk& c : chunks_)
      total += c.values.size() * std::ptrdiff_t(sizeof(T)) + c.swapped.size();
    return total;
  }

  // The factors of the chunk holding systems [chunk * kChunk, chunk * kChunk + kChunk).
  detail::ChunkFactors<T> chunk(std::ptrdiff_t index) const {
    const Chunk& c = chunks_[index];
    const std::ptrdiff_t size = n_ * kChunk;
    const T* base = c.values.data();
    const bool pivoting = c.kind == detail::FactorKind::Pivoting;
    return {c.kind,
            base,
            base + size,
            base + 2 * size,
            pivoting ? base + 3 * size : nullptr,
            pivoting ? c.swapped.data() : nullptr};
  }
  std::ptrdiff_t chunks() const { return std::ptrdiff_t(chunks_.size()); }

 private:
  struct Chunk {
    detail::FactorKind kind = detail::FactorKind::NoPivoting;
    detail::AlignedBuffer<T> values;
    detail::AlignedBuffer<unsigned char> swapped;
  };

  template <class F, class In>
  friend TridiagonalFactors<F> factor_as(const In*, const In*, const In*, const BatchLayout&,
                                         const FactorOptions&);

  std::ptrdiff_t n_ = 0, count_ = 0;
  std::vector<Chunk> chunks_;
  std::vector<Real> norm1_;
};

namespace detail {

// ||A||_1 of one system: the largest column sum (column j: c[j-1], b[j], a[j+1]).
template <class T>
real_t<T> system_norm1(const SystemView<T>& s) {
  real_t<T> largest = 0;
  for (std::ptrdiff_t j = 0; j < s.n; ++j) {
    real_t<T> column = std::abs(s.b[j]);
    if (j > 0) column += std::abs(s.c[j - 1]);
    if (j + 1 < s.n) column += std::abs(s.a[j + 1]);
    largest = std::max(largest, column);
  }
  return largest;
}

// One system's coefficients, rounded to the factor type F when it differs from In (the float
// factors of double data for mixed precision), in three contiguous arrays.
template <class F, class In>
SystemView<F> system_as(const In* a, const In* b, const In* c, const BatchLayout& layout,
                        std::ptrdiff_t s, AlignedBuffer<F>& copy) {
  const std::ptrdiff_t n = layout.n, o = layout.offset(s, 0), rs = layout.row_stride;
  if constexpr (std::is_same_v<F, In>) {
    (void)copy;
    return {{a + o, rs}, {b + o, rs}, {c + o, rs}, {b + o, rs}, n, false};
  } else {
    copy.resize(3 * n);
    F* out = copy.data();
    for (std::ptrdiff_t i = 0; i < n; ++i) {
      out[i] = i > 0 ? F(a[o + i * rs]) : F(0);  // sub[0] and super[n-1] are not read
      out[n + i] = F(b[o + i * rs]);
      out[2 * n + i] = i + 1 < n ? F(c[o + i * rs]) : F(0);
    }
    return {{out, 1}, {out + n, 1}, {out + 2 * n, 1}, {out + n, 1}, n, false};
  }
}

// Lane `l` of a chunk buffer holding `arrays` arrays of n * W.
template <class T, int W>
Strided<T> lane_array(T* base, std::ptrdiff_t n, int array, int l) {
  return {base + array * n * W + l, W};
}

// Identity factors for the padding lanes of the last chunk.
template <class T, int W>
void pad_lane(T* values, unsigned char* swapped, std::ptrdiff_t n, int arrays, int l) {
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    for (int k = 0; k < arrays; ++k) values[k * n * W + i * W + l] = T(0);
    values[n * W + i * W + l] = T(1);
    if (swapped != nullptr) swapped[i * W + l] = 0;
  }
}

}  // namespace detail

// Factors every system of the batch  sub[i] x[i-1] + diag[i] x[i] + super[i] x[i+1]  in the
// factor scalar F (F = In, or float factors of double data for solve_mixed). sub[0] and
// super[n-1] are not read. Throws InvalidArgument for bad arguments or a non-finite
// coefficient, and NumericalError naming system and row for a singular system (an exactly zero
// pivot with pivoting), a system Factorization::NoPivoting cannot take, or factors that
// overflow F.
template <class F, class In>
TridiagonalFactors<F> factor_as(const In* sub, const In* diag, const In* super,
                                const BatchLayout& layout, const FactorOptions& options = {}) {
  static_assert(is_supported_scalar_v<F> && is_supported_scalar_v<In>,
                "tridiff solvers support float, double and complex");
  using namespace detail;
  constexpr int W = kLanes<F>;
  validate_layout(layout);
  detail::require_one_batch_dimension(layout, "the factored solve");
  require_pointer(sub, "sub");
  require_pointer(diag, "diag");
  require_pointer(super, "super");
  const int threads = resolve_threads(options.threads);
  if (options.method != Factorization::Auto && options.method != Factorization::NoPivoting &&
      options.method != Factorization::Pivoting)
    throw InvalidArgument("method", "is not a Factorization (" +
                                        std::to_string(static_cast<int>(options.method)) + ")");
  const std::ptrdiff_t n = layout.n;
  TridiagonalFactors<F> result;
  result.n_ = n;
  result.count_ = layout.count;
  result.chunks_.resize((layout.count + W - 1) / W);
  result.norm1_.resize(layout.count);

  auto factor_chunk = [&](std::ptrdiff_t first, std::ptrdiff_t systems, Scratch<F>& scratch) {
    auto& chunk = result.chunks_[first / W];
    // Inputs first: every system finite, and whether all may go without pivoting.
    bool dominant = options.method != Factorization::Pivoting;
    for (std::ptrdiff_t l = 0; l < systems; ++l) {
      const std::ptrdiff_t s = first + l;
      const SystemView<In> view = system_view(sub, diag, super, diag, layout, s, false);
      require_finite_matrix(view, s);
      result.norm1_[s] = real_t<F>(system_norm1(view));
      if (options.method == Factorization::Pivoting) continue;
      const Dominance d = dominance(view, 0, n);
      if (!d.holds() && options.method == Factorization::NoPivoting)
        throw NumericalError(s, d.first_row_failure,
                             "the matrix is not diagonally dominant, so factoring it without "
                             "pivoting is unsafe; use Factorization::Pivoting or Auto");
      dominant = dominant && d.holds();
    }
    auto factor_lanes = [&](FactorKind kind) -> std::ptrdiff_t {  // -1, or the failing lane
      const int arrays = kind == FactorKind::Pivoting ? 4 : 3;
      chunk.kind = kind;
      chunk.values.resize(arrays * n * W);
      if (kind == FactorKind::Pivoting) chunk.swapped.resize(n * W);
      F* v = chunk.values.data();
      unsigned char* swaps = kind == FactorKind::Pivoting ? chunk.swapped.data() : nullptr;
      for (int l = 0; l < W; ++l) {
        if (l >= systems) {
          pad_lane<F, W>(v, swaps, n, arrays, l);
          continue;
        }
        const SystemView<F> s = system_as<F>(sub, diag, super, layout, first + l, scratch.slab);
        const std::ptrdiff_t bad =
            kind == FactorKind::NoPivoting
                ? factor_no_pivoting(n, s.a, s.b, s.c, lane_array<F, W>(v, n, 0, l),
                                     lane_array<F, W>(v, n, 1, l), lane_array<F, W>(v, n, 2, l))
                : factor_pivoting(n, s.a, s.b, s.c, lane_array<F, W>(v, n, 0, l),
                                  lane_array<F, W>(v, n, 1, l), lane_array<F, W>(v, n, 2, l),
                                  lane_array<F, W>(v, n, 3, l),
                                  Strided<unsigned char>{swaps + l, W});
        if (bad >= 0) {
          if (kind == FactorKind::NoPivoting && options.method == Factorization::Auto) return l;
          throw NumericalError(first + l, bad,
                               std::string("zero pivot in the ") +
                                   (kind == FactorKind::Pivoting ? "pivoting " : "") +
                                   "LU factorization: the matrix is singular to working precision");
        }
      }
      return -1;
    };
    // A dominant system whose pivot still vanished is singular or nearly: pivoting decides.
    if (!dominant || factor_lanes(FactorKind::NoPivoting) >= 0) factor_lanes(FactorKind::Pivoting);
    // Factors past the range of F (huge ratios of coefficients, or double data beyond float's
    // range) would turn every solve into inf or NaN.
    const std::ptrdiff_t values = (chunk.kind == FactorKind::Pivoting ? 4 : 3) * n * W;
    for (std::ptrdiff_t k = 0; k < values; ++k)
      if (!is_finite(chunk.values.data()[k]))
        throw NumericalError(first + (k % W), (k / W) % n,
                             "the LU factors overflow: the matrix is singular or badly scaled");
  };
  for_each_chunk<F>(layout.count, W, threads, factor_chunk);
  return result;
}

// Factors the batch in its own scalar type.
template <class T>
TridiagonalFactors<T> factor(const T* sub, const T* diag, const T* super, const BatchLayout& layout,
                             const FactorOptions& options = {}) {
  return factor_as<T, T>(sub, diag, super, layout, options);
}

// Factors the diffusion systems of solve_diffusion (seed 000 eq. 3.10, insulated ends) from
// beta alone: strictly diagonally dominant, so always without pivoting.
template <class T>
TridiagonalFactors<T> factor_diffusion(const real_t<T>* beta, const BatchLayout& layout,
                                       const FactorOptions& options = {}) {
  using namespace detail;
  validate_layout(layout);
  detail::require_one_batch_dimension(layout, "the factored solve");
  require_pointer(beta, "beta");
  const std::ptrdiff_t n = layout.n;
  std::vector<T> a(n * layout.count), b(n * layout.count), c(n * layout.count);
  for (std::ptrdiff_t s = 0; s < layout.count; ++s) {
    const Strided<const real_t<T>> system_beta{beta + layout.offset(s, 0), layout.row_stride};
    require_valid_beta(system_beta, n, false, s);
    expand_diffusion(system_beta, n, false, a.data() + s * n, b.data() + s * n, c.data() + s * n);
  }
  FactorOptions no_pivoting = options;
  no_pivoting.method = Factorization::NoPivoting;
  return factor(a.data(), b.data(), c.data(), BatchLayout::rows(n, layout.count, n), no_pivoting);
}

namespace detail {

// to[0, count) = from[0, count), the whole 64-byte pieces with non-temporal stores: a solution
// row that nothing reads again soon is then not first read from memory to be overwritten
// (the write-allocate that STREAM counting leaves out). The caller ends with
// finish_streaming_stores() before the data may be read by another thread.
template <class T>
void copy_streaming(const T* from, std::ptrdiff_t count, T* to) {
#if defined(__AVX512F__)
  static_assert(sizeof(T) % sizeof(float) == 0);
  const auto* in = reinterpret_cast<const float*>(from);
  auto* out = reinterpret_cast<float*>(to);
  std::ptrdiff_t k = 0, floats = count * std::ptrdiff_t(sizeof(T) / sizeof(float));
  while (k < floats && (reinterpret_cast<std::uintptr_t>(out + k) & 63) != 0) {
    out[k] = in[k];
    ++k;
  }
  for (; k + 16 <= floats; k += 16) _mm512_stream_ps(out + k, _mm512_loadu_ps(in + k));
  for (; k < floats; ++k) out[k] = in[k];
#else
  std::copy(from, from + count, to);
#endif
}

[[noreturn]] inline void report_overflow(std::ptrdiff_t system) {
  throw NumericalError(system, -1, "the solution overflowed: rhs is too large for this matrix");
}

// Throws for the first non-finite value of a chunk's rhs (the caller's fault), otherwise for
// an overflow in the first lane whose probe is not zero.
template <class T, class R>
[[noreturn]] void report_chunk_failure(const T* rhs, const BatchLayout& layout,
                                       std::ptrdiff_t first, int lanes, const R* probe) {
  for (std::ptrdiff_t i = 0; i < layout.n; ++i)
    for (int l = 0; l < lanes; ++l)
      if (!is_finite(rhs[layout.offset(first + l, i)]))
        throw InvalidArgument("rhs", first + l, i, "is not finite");
  for (int l = 0; l < lanes; ++l)
    if (!(probe[l] == 0)) report_overflow(first + l);
  report_overflow(first);
}

// The hot case of a factored solve, A x = b without pivoting on a whole chunk into an x apart
// from rhs, with no slab round trip: interleaved systems (image columns) are solved where they
// lie; contiguous ones (image rows) are transposed into lanes kTransposeBlock rows at a time,
// each block swept while it is in L1, and back the same way. Returns false for other cases.
template <class T>
bool solve_chunk_streaming(const ChunkFactors<T>& f, const T* rhs, T* x, const BatchLayout& layout,
                           std::ptrdiff_t first, std::ptrdiff_t systems, Scratch<T>& scratch) {
  constexpr int W = kLanes<T>;
  const std::ptrdiff_t n = layout.n, o = layout.offset(first, 0);
  if (f.kind != FactorKind::NoPivoting || systems != W || x == rhs) return false;
  real_t<T> probe[W], block_probe[W];
  if (layout.system_stride == 1) {
    const std::ptrdiff_t rs = layout.row_stride;
    forward_no_pivoting<T, W, W>(f, 0, n, rhs + o, rs, x + o, rs);
    backward_no_pivoting<T, W, W>(f, n, 0, n, x + o, rs, probe);
  } else if (layout.row_stride == 1) {
    // The W rows are first copied one after another into a staging area, as
    // diffusion_thomas_rows does: W rows read side by side are more streams than DRAM and the
    // prefetchers serve well.
    const std::ptrdiff_t pitch = layout.system_stride, staged = staging_pitch(n);
    scratch.work.resize(n * W);
    scratch.slab.resize(W * staged);
    T* lanes = scratch.work.data();
    T* staging = scratch.slab.data();
    for (int l = 0; l < W; ++l)
      std::copy(rhs + o + l * pitch, rhs + o + l * pitch + n, staging + l * staged);
    for (std::ptrdiff_t begin = 0; begin < n; begin += kTransposeBlock) {
      const std::ptrdiff_t end = std::min(n, begin + kTransposeBlock);
      transpose_into_lanes<T, W>(staging + begin, staged, end - begin, lanes + begin * W);
      forward_no_pivoting<T, W, W>(f, begin, end, lanes, W, lanes, W);
    }
    for (int l = 0; l < W; ++l) probe[l] = 0;
    for (std::ptrdiff_t begin = (n - 1) / kTransposeBlock * kTransposeBlock; begin >= 0;
         begin -= kTransposeBlock) {
      const std::ptrdiff_t end = std::min(n, begin + kTransposeBlock);
      backward_no_pivoting<T, W, W>(f, n, begin, end, lanes, W, block_probe);
      for (int l = 0; l < W; ++l) probe[l] += block_probe[l];
      transpose_from_lanes<T, W>(lanes + begin * W, end - begin, staging + begin, staged);
    }
    for (int l = 0; l < W; ++l) copy_streaming(staging + l * staged, n, x + o + l * pitch);
    finish_streaming_stores();
  } else {
    return false;
  }
  real_t<T> sum = 0;
  for (int l = 0; l < W; ++l) sum += probe[l];
  if (!(sum == 0)) report_chunk_failure(rhs, layout, first, W, probe);
  return true;
}

// Solves one chunk's right-hand side j in lanes: through a lane-contiguous slab (gathered,
// solved, checked, scattered), so that an in-place solve that overflows leaves rhs as it was.
template <class F, class T>
void solve_chunk_factored(const ChunkFactors<F>& f, Apply apply, const T* rhs, T* x,
                          const BatchLayout& layout, std::ptrdiff_t first, std::ptrdiff_t systems,
                          Scratch<F>& scratch) {
  constexpr int W = kLanes<F>;
  const std::ptrdiff_t n = layout.n;
  scratch.work.resize(n * W);
  F* slab = scratch.work.data();
  const int lanes = int(systems);
  if constexpr (std::is_same_v<F, T>) {
    gather<T, W>(rhs, layout, first, lanes, T(0), slab);
  } else {
    for (std::ptrdiff_t i = 0; i < n; ++i)
      for (int l = 0; l < W; ++l)
        slab[i * W + l] = l < lanes ? F(rhs[layout.offset(first + l, i)]) : F(0);
  }
  solve_factored<F, W, W>(f, apply, n, slab, W);
  real_t<F> probe[W];  // NaN iff some value of the lane is not finite
  for (int l = 0; l < W; ++l) probe[l] = 0;
  for (std::ptrdiff_t i = 0; i < n; ++i)
#pragma omp simd
    for (int l = 0; l < W; ++l) probe[l] += magnitude(slab[i * W + l]) * 0;
  real_t<F> sum = 0;
  for (int l = 0; l < lanes; ++l) sum += probe[l];
  if (!(sum == 0)) report_chunk_failure(rhs, layout, first, lanes, probe);
  if constexpr (std::is_same_v<F, T>) {
    scatter<T, W>(slab, layout, first, lanes, x);
  } else {
    for (std::ptrdiff_t i = 0; i < n; ++i)
      for (int l = 0; l < lanes; ++l) x[layout.offset(first + l, i)] = T(slab[i * W + l]);
  }
}

inline std::ptrdiff_t rhs_stride_of(const FactoredSolveOptions& options,
                                    const BatchLayout& layout) {
  if (options.nrhs < 1)
    throw InvalidArgument("nrhs", "must be at least 1, got " + std::to_string(options.nrhs));
  const std::ptrdiff_t stride = options.rhs_stride == 0 ? layout.extent() : options.rhs_stride;
  if (options.nrhs > 1 && stride < layout.extent())
    throw InvalidArgument("rhs_stride", "must be at least the batch's extent " +
                                            std::to_string(layout.extent()) + ", got " +
                                            std::to_string(stride));
  return stride;
}

template <class F>
void require_matching(const TridiagonalFactors<F>& factors, const BatchLayout& layout) {
  if (factors.n() != layout.n || factors.count() != layout.count)
    throw InvalidArgument("layout", "describes " + std::to_string(layout.count) + " systems of " +
                                        std::to_string(layout.n) + " rows, the factors " +
                                        std::to_string(factors.count()) + " of " +
                                        std::to_string(factors.n()));
}

}  // namespace detail

// Solves op(A) x = rhs for every system and right-hand side with factors from `factor`.
// layout describes rhs and x (not necessarily the layout the matrix was factored from); x may
// be rhs (in place) and must not otherwise overlap it. Throws InvalidArgument for bad
// arguments or a non-finite rhs, NumericalError if a solution overflows; on an exception an
// in-place solve leaves the rhs of the failing chunk of systems as it was.
template <class T>
void solve(const TridiagonalFactors<T>& factors, const T* rhs, T* x, const BatchLayout& layout,
           const FactoredSolveOptions& options = {}) {
  using namespace detail;
  constexpr int W = kLanes<T>;
  validate_layout(layout);
  detail::require_one_batch_dimension(layout, "the factored solve");
  require_matching(factors, layout);
  require_pointer(rhs, "rhs");
  require_pointer(x, "x");
  const std::ptrdiff_t stride = rhs_stride_of(options, layout);
  // Every right-hand side as one span, for the overlap check.
  const BatchLayout all = BatchLayout::single((options.nrhs - 1) * stride + layout.extent());
  require_disjoint(rhs, "rhs", x, all, true);
  if (options.apply != Apply::Matrix && options.apply != Apply::Transpose &&
      options.apply != Apply::Adjoint)
    throw InvalidArgument(
        "apply", "is not an Apply (" + std::to_string(static_cast<int>(options.apply)) + ")");
  const int threads = resolve_threads(options.threads);
  for_each_chunk<T>(layout.count, W, threads,
                    [&](std::ptrdiff_t first, std::ptrdiff_t systems, Scratch<T>& scratch) {
                      const ChunkFactors<T> f = factors.chunk(first / W);
                      for (std::ptrdiff_t j = 0; j < options.nrhs; ++j) {
                        const T* b = rhs + j * stride;
                        T* out = x + j * stride;
                        if (options.apply == Apply::Matrix &&
                            solve_chunk_streaming(f, b, out, layout, first, systems, scratch))
                          continue;
                        solve_chunk_factored(f, options.apply, b, out, layout, first, systems,
                                             scratch);
                      }
                    });
}

}  // namespace tridiff
