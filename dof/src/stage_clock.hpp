// Wall-clock time of a method's stages, for DofReport::stages. Private to dof/src.
#pragma once

#include <chrono>

namespace tridiff::dof_detail {

using StageClock = std::chrono::steady_clock;

inline double seconds_since(StageClock::time_point start) {
  return std::chrono::duration<double>(StageClock::now() - start).count();
}

}  // namespace tridiff::dof_detail
