// Where the equations of a batch of tridiagonal systems live in memory. One layout serves every
// coefficient array of a call, so an image row (row_stride 1) and an image column
// (row_stride = pitch) are the same kind of batch.
#pragma once

#include <algorithm>
#include <complex>
#include <cstddef>
#include <limits>
#include <string>
#include <utility>
#include <iterator>
#include <type_traits>

#include "tridiff/solvers/error.hpp"

namespace tridiff {

// Element i (0 <= i < n) of system s (0 <= s < count) is at offset
//   s * system_stride + i * row_stride
// from the base pointer of every array (sub-, main-, super-diagonal, right-hand side, solution).
// Strides are in elements and must be positive.
//
// A second batch dimension makes the lines of a 3-D grid along any axis one batch: with
// outer_count > 1 there are count * outer_count systems, and system s = j * count + k
// (0 <= k < count, 0 <= j < outer_count) starts at k * system_stride + j * outer_stride. Every
// system number the library reports (errors, per-system status) is this flat s.
struct BatchLayout {
  std::ptrdiff_t n = 0;              // unknowns per system
  std::ptrdiff_t count = 1;          // number of systems (per outer batch)
  std::ptrdiff_t row_stride = 1;     // from equation i to i + 1 of one system
  std::ptrdiff_t system_stride = 0;  // from system k to k + 1
  std::ptrdiff_t outer_count = 1;    // batches of `count` systems
  std::ptrdiff_t outer_stride = 0;   // from batch j to j + 1

  // One system of n unknowns, stored contiguously.
  static constexpr BatchLayout single(std::ptrdiff_t n) { return {n, 1, 1, n}; }
  // `count` systems of n unknowns, each contiguous, `pitch` elements apart (image rows).
  static constexpr BatchLayout rows(std::ptrdiff_t n, std::ptrdiff_t count, std::ptrdiff_t pitch) {
    return {n, count, 1, pitch};
  }
  // `count` systems of n unknowns interleaved: equation i of every system in one memory row of
  // `pitch` elements (image columns).
  static constexpr BatchLayout columns(std::ptrdiff_t n, std::ptrdiff_t count,
                                       std::ptrdiff_t pitch) {
    return {n, count, pitch, 1};
  }
  // The lines along `axis` (0, 1 or 2) of a 3-D array with `extent[d]` points and `stride[d]`
  // elements between neighbours along dimension d (padding allowed: any positive strides). The
  // other two dimensions are the batch, the one with the smaller stride inner, so that
  // neighbouring systems are as close in memory as the array allows.
  static constexpr BatchLayout grid_lines(const std::ptrdiff_t (&extent)[3],
                                          const std::ptrdiff_t (&stride)[3], int axis) {
    int inner = axis == 0 ? 1 : 0;
    int outer = 3 - axis - inner;
    if (stride[outer] < stride[inner]) std::swap(inner, outer);
    return {extent[axis], extent[inner], stride[axis], stride[inner], extent[outer], stride[outer]};
  }

  // The number of systems of the batch, both batch dimensions together.
  constexpr std::ptrdiff_t systems() const { return count * outer_count; }
  constexpr std::ptrdiff_t offset(std::ptrdiff_t system, std::ptrdiff_t row) const {
    if (outer_count == 1) return system * system_stride + row * row_stride;
    return (system % count) * system_stride + (system / count) * outer_stride + row * row_stride;
  }
  // Number of elements from the first to one past the last element of the batch.
  constexpr std::ptrdiff_t extent() const {
    return (n - 1) * row_stride + (count - 1) * system_stride + (outer_count - 1) * outer_stride +
           1;
  }
};

namespace detail {

// One dimension of a layout: `count` elements `stride` apart, `name` being the stride's.
struct LayoutDimension {
  std::ptrdiff_t count, stride;
  const char* name;
};

// Throws unless the dimensions that have more than one element nest: sorted by stride, each
// stride spans the whole extent of the dimensions inside it. Then no two elements share an
// address. (A sufficient condition: a layout that interleaves dimensions without overlapping,
// which no array library produces, is refused too.)
inline void require_nested(LayoutDimension (&dims)[3]) {
  std::sort(std::begin(dims), std::end(dims),
            [](const LayoutDimension& a, const LayoutDimension& b) { return a.stride < b.stride; });
  std::ptrdiff_t spanned = 1;  // elements covered by the dimensions seen so far
  for (const LayoutDimension& d : dims) {
    if (d.count <= 1) continue;
    if (d.stride < spanned)
      throw InvalidArgument(d.name, "systems overlap in memory: stride " +
                                        std::to_string(d.stride) + " is smaller than " +
                                        std::to_string(spanned));
    spanned = d.stride * d.count;
  }
}

// For the calls that take one batch dimension only (the factored solve, refinement).
inline void require_one_batch_dimension(const BatchLayout& layout, const char* call) {
  if (layout.outer_count != 1)
    throw InvalidArgument("outer_count", std::string("must be 1 in ") + call + " (got " +
                                             std::to_string(layout.outer_count) +
                                             "): call it once per outer batch");
}

}  // namespace detail

// Throws InvalidArgument unless the layout describes n >= 1 unknowns in count >= 1 systems
// (times outer_count >= 1) with positive strides, and no two (system, row) pairs share an
// element.
inline void validate_layout(const BatchLayout& layout) {
  if (layout.n < 1)
    throw InvalidArgument("n", "must be at least 1, got " + std::to_string(layout.n));
  if (layout.count < 1)
    throw InvalidArgument("count", "must be at least 1, got " + std::to_string(layout.count));
  if (layout.outer_count < 1)
    throw InvalidArgument("outer_count",
                          "must be at least 1, got " + std::to_string(layout.outer_count));
  if (layout.row_stride < 1 && layout.n > 1)
    throw InvalidArgument("row_stride",
                          "must be positive, got " + std::to_string(layout.row_stride));
  if (layout.system_stride < 1 && layout.count > 1)
    throw InvalidArgument("system_stride",
                          "must be positive, got " + std::to_string(layout.system_stride));
  if (layout.outer_stride < 1 && layout.outer_count > 1)
    throw InvalidArgument("outer_stride",
                          "must be positive, got " + std::to_string(layout.outer_stride));
  // First, so that the products below cannot overflow: each is at most max_extent plus a
  // stride that is itself at most max_extent, and the three terms of extent() together at
  // most 3 * max_extent.
  const auto max_extent = std::numeric_limits<std::ptrdiff_t>::max() / 4;
  auto too_long = [&](std::ptrdiff_t count, std::ptrdiff_t stride) {
    return (count - 1) > max_extent / std::max<std::ptrdiff_t>(stride, 1);
  };
  if (too_long(layout.n, layout.row_stride) || too_long(layout.count, layout.system_stride) ||
      too_long(layout.outer_count, layout.outer_stride) || layout.extent() > max_extent)
    throw InvalidArgument("layout", "extent overflows the address space");
  detail::LayoutDimension dims[3] = {{layout.n, layout.row_stride, "row_stride"},
                                     {layout.count, layout.system_stride, "system_stride"},
                                     {layout.outer_count, layout.outer_stride, "outer_stride"}};
  detail::require_nested(dims);
}

// The real type underlying a scalar: float for std::complex<float>, and so on.
template <class T>
struct real_type {
  using type = T;
};
template <class T>
struct real_type<std::complex<T>> {
  using type = T;
};
template <class T>
using real_t = typename real_type<T>::type;

template <class T>
inline constexpr bool is_complex_v = !std::is_same_v<T, real_t<T>>;

// The scalars the solvers are built and tested for.
template <class T>
inline constexpr bool is_supported_scalar_v =
    std::is_same_v<T, float> || std::is_same_v<T, double> ||
    std::is_same_v<T, std::complex<float>> || std::is_same_v<T, std::complex<double>>;

}  // namespace tridiff
