// Aligned scratch memory for the kernels, and the gathering of scattered systems into a
// lane-contiguous slab (one SIMD lane per system) and back.
#pragma once

#include <cstddef>
#include <cstdlib>
#include <memory>
#include <new>

#include "tridiff/solvers/detail/transpose.hpp"
#include "tridiff/solvers/layout.hpp"

namespace tridiff::detail {

// A buffer of `size` default-initialised scalars on a 64-byte (cache line, AVX-512) boundary.
template <class T>
class AlignedBuffer {
 public:
  AlignedBuffer() = default;
  explicit AlignedBuffer(std::ptrdiff_t size) { resize(size); }

  void resize(std::ptrdiff_t size) {
    if (size <= size_) return;
    const std::size_t bytes = (static_cast<std::size_t>(size) * sizeof(T) + 63) / 64 * 64;
    void* memory = std::aligned_alloc(64, bytes);
    if (memory == nullptr) throw std::bad_alloc();
    data_.reset(static_cast<T*>(memory));
    size_ = size;
  }
  T* data() const { return data_.get(); }
  std::ptrdiff_t size() const { return size_; }

 private:
  struct Free {
    void operator()(T* p) const { std::free(p); }
  };
  std::unique_ptr<T, Free> data_;
  std::ptrdiff_t size_ = 0;
};

// Copies `lanes` systems starting at `first` into slab[i * W + lane]; lanes past `lanes`
// receive `pad` so that they form harmless identity systems.
template <class T, int W>
void gather(const T* source, const BatchLayout& layout, std::ptrdiff_t first, int lanes, T pad,
            T* slab) {
  if (layout.row_stride == 1 && lanes == W)
    return transpose_into_lanes<T, W>(source + layout.offset(first, 0), layout.system_stride,
                                      layout.n, slab);
  for (std::ptrdiff_t i = 0; i < layout.n; ++i) {
    const T* row = source + layout.offset(first, i);
    T* out = slab + i * W;
    for (int l = 0; l < lanes; ++l) out[l] = row[l * layout.system_stride];
    for (int l = lanes; l < W; ++l) out[l] = pad;
  }
}

template <class T, int W>
void scatter(const T* slab, const BatchLayout& layout, std::ptrdiff_t first, int lanes,
             T* destination) {
  if (layout.row_stride == 1 && lanes == W)
    return transpose_from_lanes<T, W>(slab, layout.n, destination + layout.offset(first, 0),
                                      layout.system_stride);
  for (std::ptrdiff_t i = 0; i < layout.n; ++i) {
    T* row = destination + layout.offset(first, i);
    const T* in = slab + i * W;
    for (int l = 0; l < lanes; ++l) row[l * layout.system_stride] = in[l];
  }
}

}  // namespace tridiff::detail
