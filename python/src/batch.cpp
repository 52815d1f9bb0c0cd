// plan_batch and batch_index (batch.hpp).
#include "batch.hpp"

#include <algorithm>
#include <numeric>

namespace tridiff::python {

namespace {

struct Group {
  std::ptrdiff_t extent, stride;
};

// The batch axes with more than one element, largest stride first.
std::vector<int> batch_axes_by_stride(const std::vector<std::ptrdiff_t>& shape,
                                      const std::vector<std::ptrdiff_t>& strides, int axis) {
  std::vector<int> axes;
  for (int k = 0; k < static_cast<int>(shape.size()); ++k)
    if (k != axis && shape[k] > 1) axes.push_back(k);
  std::stable_sort(axes.begin(), axes.end(), [&](int p, int q) { return strides[p] > strides[q]; });
  return axes;
}

}  // namespace

std::ptrdiff_t BatchPlan::calls() const {
  return std::accumulate(loop_extents.begin(), loop_extents.end(), std::ptrdiff_t(1),
                         std::multiplies<>());
}

std::ptrdiff_t BatchPlan::call_offset(std::ptrdiff_t k) const {
  std::ptrdiff_t offset = 0;
  for (std::size_t d = loop_extents.size(); d-- > 0;) {
    offset += (k % loop_extents[d]) * loop_strides[d];
    k /= loop_extents[d];
  }
  return offset;
}

BatchPlan plan_batch(const std::vector<std::ptrdiff_t>& shape,
                     const std::vector<std::ptrdiff_t>& strides, int axis) {
  std::vector<Group> groups;
  for (int k : batch_axes_by_stride(shape, strides, axis)) {
    if (!groups.empty() && groups.back().stride == shape[k] * strides[k]) {
      groups.back().extent *= shape[k];
      groups.back().stride = strides[k];
    } else {
      groups.push_back({shape[k], strides[k]});
    }
  }
  BatchPlan plan;
  const std::ptrdiff_t n = shape[axis];
  const std::ptrdiff_t row_stride = n > 1 ? strides[axis] : 1;
  plan.layout = BatchLayout{n, 1, row_stride, n * row_stride};
  // The most systems per call: the threads and the SIMD lanes work within one call.
  // Of equals the last (the smallest stride: interleaved systems, the lanes' best layout).
  std::size_t widest = 0;
  for (std::size_t g = 1; g < groups.size(); ++g)
    if (groups[g].extent >= groups[widest].extent) widest = g;
  for (std::size_t g = 0; g < groups.size(); ++g) {
    if (g == widest) {
      plan.layout.count = groups[g].extent;
      plan.layout.system_stride = groups[g].stride;
    } else {
      plan.loop_extents.push_back(groups[g].extent);
      plan.loop_strides.push_back(groups[g].stride);
    }
  }
  return plan;
}

std::vector<std::ptrdiff_t> batch_index(std::ptrdiff_t offset,
                                        const std::vector<std::ptrdiff_t>& shape,
                                        const std::vector<std::ptrdiff_t>& strides, int axis) {
  std::vector<std::ptrdiff_t> index(shape.size(), 0);
  for (int k : batch_axes_by_stride(shape, strides, axis)) {
    index[k] = offset / strides[k];
    offset %= strides[k];
  }
  index.erase(index.begin() + axis);
  return index;
}

}  // namespace tridiff::python
