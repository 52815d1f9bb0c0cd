// How an n-dimensional numpy array of systems (one axis the equations, the others the batch)
// maps onto the solvers' BatchLayout. All of it lives here: when BatchLayout gains a second
// batch dimension, only plan_batch changes (it then absorbs the next group of axes instead of
// looping over it).
#pragma once

#include <cstddef>
#include <vector>

#include "tridiff/solvers/layout.hpp"

namespace tridiff::python {

// The solver calls that cover an array: `layout` for each call, at element offsets given by
// the outer loops (the batch axes that no stride of the layout could absorb).
struct BatchPlan {
  BatchLayout layout;
  std::vector<std::ptrdiff_t> loop_extents;  // outermost first
  std::vector<std::ptrdiff_t> loop_strides;  // in elements

  std::ptrdiff_t calls() const;
  // The element offset of call k (0 <= k < calls()).
  std::ptrdiff_t call_offset(std::ptrdiff_t k) const;
};

// `shape` and `strides` (in elements, positive, no two elements shared) of an array with at
// least one element, the equations along `axis` (0 <= axis < ndim). Batch axes whose strides
// nest (stride of one = extent x stride of the next) merge into one; the largest merged group
// becomes the layout's systems, the others are looped over.
BatchPlan plan_batch(const std::vector<std::ptrdiff_t>& shape,
                     const std::vector<std::ptrdiff_t>& strides, int axis);

// The index along each batch axis (every axis but `axis`, in order) of the system whose first
// equation is at element `offset`: the inverse of sum(index * stride) for nested strides.
std::vector<std::ptrdiff_t> batch_index(std::ptrdiff_t offset,
                                        const std::vector<std::ptrdiff_t>& shape,
                                        const std::vector<std::ptrdiff_t>& strides, int axis);

}  // namespace tridiff::python
