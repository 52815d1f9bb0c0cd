// Image storage: zeroed, aligned, and in huge pages when large; the parallel image copy.
#include "tridiff/image/image.hpp"

#include "tridiff/image/copy.hpp"
#include "tridiff/threads.hpp"

#include <sys/mman.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <new>

namespace tridiff::detail {
namespace {

constexpr std::size_t kHugePage = std::size_t(2) << 20;
constexpr std::size_t kMapAbove = std::size_t(1) << 20;  // smaller arrays use the heap

}  // namespace

void StorageFree::operator()(float* p) const {
  if (bytes == 0)
    std::free(p);
  else
    munmap(p, bytes);
}

FloatStorage allocate_zeroed_floats(std::ptrdiff_t count) {
  const std::size_t bytes = static_cast<std::size_t>(count) * sizeof(float);
  if (bytes < kMapAbove) {
    void* memory = std::aligned_alloc(64, (bytes + 63) / 64 * 64);
    if (memory == nullptr) throw std::bad_alloc();
    std::memset(memory, 0, bytes);
    return FloatStorage(static_cast<float*>(memory), StorageFree{0});
  }
  // Anonymous mappings are zero-filled by the kernel. Round up to whole huge pages so that the
  // kernel can back every part of the array with them.
  // Huge pages also need a 2 MiB aligned address: map one huge page more, trim both ends.
  const std::size_t length = (bytes + kHugePage - 1) / kHugePage * kHugePage;
  void* mapped =
      mmap(nullptr, length + kHugePage, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (mapped == MAP_FAILED) throw std::bad_alloc();
  const auto start = reinterpret_cast<std::uintptr_t>(mapped);
  const std::uintptr_t aligned = (start + kHugePage - 1) / kHugePage * kHugePage;
  if (aligned > start) munmap(mapped, aligned - start);
  if (const std::size_t tail = start + length + kHugePage - (aligned + length))
    munmap(reinterpret_cast<void*>(aligned + length), tail);
  void* memory = reinterpret_cast<void*>(aligned);
#ifdef MADV_HUGEPAGE
  madvise(memory, length, MADV_HUGEPAGE);  // a hint; without it the array still works
#endif
  return FloatStorage(static_cast<float*>(memory), StorageFree{length});
}

}  // namespace tridiff::detail

namespace tridiff {

void copy_image(Image& dst, const Image& src, int threads) {
  const int team = resolve_threads(threads);
  if (dst.width() != src.width() || dst.height() != src.height() ||
      dst.channels() != src.channels())
    throw InvalidArgument("dst", "shape differs from src");
  const std::ptrdiff_t rows = src.height() * src.channels();
#pragma omp parallel for num_threads(team) schedule(static)
  for (std::ptrdiff_t r = 0; r < rows; ++r) {
    const int c = static_cast<int>(r / src.height());
    const std::ptrdiff_t y = r % src.height();
    std::memcpy(dst.plane(c).row(y), src.plane(c).row(y), src.width() * sizeof(float));
  }
}

}  // namespace tridiff
