// Where the equations of a batch of tridiagonal systems live in memory. One layout serves every
// coefficient array of a call, so an image row (row_stride 1) and an image column
// (row_stride = pitch) are the same kind of batch.
#pragma once

#include <algorithm>
#include <complex>
#include <cstddef>
#include <limits>
#include <type_traits>

#include "tridiff/solvers/error.hpp"

namespace tridiff {

// Element i (0 <= i < n) of system s (0 <= s < count) is at offset
//   s * system_stride + i * row_stride
// from the base pointer of every array (sub-, main-, super-diagonal, right-hand side, solution).
// Strides are in elements and must be positive.
struct BatchLayout {
  std::ptrdiff_t n = 0;              // unknowns per system
  std::ptrdiff_t count = 1;          // number of systems
  std::ptrdiff_t row_stride = 1;     // from equation i to i + 1 of one system
  std::ptrdiff_t system_stride = 0;  // from system s to s + 1

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

  constexpr std::ptrdiff_t offset(std::ptrdiff_t system, std::ptrdiff_t row) const {
    return system * system_stride + row * row_stride;
  }
  // Number of elements from the first to one past the last element of the batch.
  constexpr std::ptrdiff_t extent() const {
    return (n - 1) * row_stride + (count - 1) * system_stride + 1;
  }
};

// Throws InvalidArgument unless the layout describes n >= 1 unknowns in count >= 1 systems
// with positive strides, and no two (system, row) pairs share an element.
inline void validate_layout(const BatchLayout& layout) {
  if (layout.n < 1)
    throw InvalidArgument("n", "must be at least 1, got " + std::to_string(layout.n));
  if (layout.count < 1)
    throw InvalidArgument("count", "must be at least 1, got " + std::to_string(layout.count));
  if (layout.row_stride < 1 && layout.n > 1)
    throw InvalidArgument("row_stride",
                          "must be positive, got " + std::to_string(layout.row_stride));
  if (layout.system_stride < 1 && layout.count > 1)
    throw InvalidArgument("system_stride",
                          "must be positive, got " + std::to_string(layout.system_stride));
  // First, so that the products below cannot overflow: each is at most max_extent plus a
  // stride that is itself at most max_extent.
  const auto max_extent = std::numeric_limits<std::ptrdiff_t>::max() / 4;
  if ((layout.n - 1) > max_extent / std::max<std::ptrdiff_t>(layout.row_stride, 1) ||
      (layout.count - 1) > max_extent / std::max<std::ptrdiff_t>(layout.system_stride, 1))
    throw InvalidArgument("layout", "extent overflows the address space");
  if (layout.n > 1 && layout.count > 1) {
    // Injective iff the larger stride steps over the whole extent of the smaller dimension.
    const bool rows_inner = layout.row_stride <= layout.system_stride;
    const std::ptrdiff_t inner_stride = rows_inner ? layout.row_stride : layout.system_stride;
    const std::ptrdiff_t inner_count = rows_inner ? layout.n : layout.count;
    const std::ptrdiff_t outer_stride = rows_inner ? layout.system_stride : layout.row_stride;
    if (outer_stride < inner_stride * inner_count)
      throw InvalidArgument(rows_inner ? "system_stride" : "row_stride",
                            "systems overlap in memory: stride " + std::to_string(outer_stride) +
                                " is smaller than " + std::to_string(inner_stride * inner_count));
  }
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
