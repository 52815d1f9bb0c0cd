// One band of rows per thread: what the splatting methods (scatter, bokeh) share, so that every
// output pixel is written by one thread only, and in the same order whatever the thread count.
#pragma once

#include <cstddef>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace tridiff::dof_detail {

// Calls body(first, last, thread) on `threads` threads, thread t with rows
// [height * t / n, height * (t + 1) / n) of n threads (the team OpenMP gives).
template <class Body>
void for_each_row_band(std::ptrdiff_t height, int threads, Body&& body) {
#pragma omp parallel num_threads(threads)
  {
#ifdef _OPENMP
    const int thread = omp_get_thread_num(), team = omp_get_num_threads();
#else
    const int thread = 0, team = 1;
#endif
    body(height * thread / team, height * (thread + 1) / team, thread);
  }
}

}  // namespace tridiff::dof_detail
