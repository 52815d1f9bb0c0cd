// What a `threads` argument means everywhere in tridiff: 0 is all cores (the OpenMP default),
// a positive count is that many threads, at most kMaxThreads. Every OpenMP region of the
// library passes num_threads(resolve_threads(threads)); scripts/lint.sh fails CI on a region
// that does not.
#pragma once

#include <algorithm>
#include <string>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "tridiff/solvers/error.hpp"

namespace tridiff {

// The most threads any call of the library accepts (`threads` above it is InvalidArgument):
// a team of tens of thousands overflows the OpenMP runtime's stacks or the process table long
// before it could help, and no machine this library targets has more than a few hundred cores.
inline constexpr int kMaxThreads = 1024;

// The team size for a `threads` argument: 0 is the OpenMP default (all cores, at most
// kMaxThreads); negative and more than kMaxThreads are InvalidArgument("threads").
inline int resolve_threads(int threads) {
  if (threads < 0) throw InvalidArgument("threads", "must be >= 0 (0: all cores)");
  if (threads > kMaxThreads)
    throw InvalidArgument("threads", "must be at most " + std::to_string(kMaxThreads) + ", got " +
                                         std::to_string(threads));
#ifdef _OPENMP
  // 0 follows OMP_NUM_THREADS, which nothing else bounds.
  return threads == 0 ? std::min(omp_get_max_threads(), kMaxThreads) : threads;
#else
  return 1;
#endif
}

}  // namespace tridiff
