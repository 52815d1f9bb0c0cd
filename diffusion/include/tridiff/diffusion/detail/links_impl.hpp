// links_from_pixels: a template, so the value-to-conductance map inlines into the loop.
#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cmath>
#include <string>
#include <vector>

#include "tridiff/threads.hpp"

namespace tridiff {

// The slow path: names the first pixel whose conductance is negative or not finite.
template <class ToLink>
[[noreturn]] void throw_bad_conductance(ConstPlane value, ToLink to_link) {
  for (std::ptrdiff_t y = 0; y < value.height(); ++y)
    for (std::ptrdiff_t x = 0; x < value.width(); ++x) {
      const float k = to_link(value(x, y));
      if (!(k >= 0) || !std::isfinite(k))
        throw InvalidArgument("value", "pixel (" + std::to_string(x) + ", " + std::to_string(y) +
                                           "): " + std::to_string(value(x, y)) +
                                           " maps to conductance " + std::to_string(k) +
                                           "; it must be finite and >= 0");
    }
  throw InvalidArgument("value", "a conductance is not finite and >= 0");
}

template <class ToLink>
LinkField links_from_pixels(ConstPlane value, ToLink to_link, int threads) {
  const std::ptrdiff_t width = value.width(), height = value.height();
  LinkField links(width, height);
  Plane horizontal = links.horizontal(), vertical = links.vertical();
  const int team = resolve_threads(threads);
  constexpr std::ptrdiff_t tile = LinkField::kTile;
  const std::ptrdiff_t tiles_x = links.tiles_x();
  // Per tile: the largest horizontal and vertical link, found while the links are written.
  std::vector<float> h_max(tiles_x * links.tiles_y(), 0.f), v_max(h_max.size(), 0.f);
  // The conductances are checked (bad_value); valid ones give valid links.
  constexpr std::int32_t kInfinity = 0x7f800000;
  bool bad_value = false;
#pragma omp parallel num_threads(team) reduction(|| : bad_value)
  {
    std::vector<float> here(width), below(width);  // per-pixel conductances of rows y, y + 1
#pragma omp for schedule(static)
    for (std::ptrdiff_t ty = 0; ty < links.tiles_y(); ++ty) {
      for (std::ptrdiff_t y = ty * tile; y < std::min(height, (ty + 1) * tile); ++y) {
        const float* row = y == ty * tile ? value.row(y) : nullptr;
        if (row) {
#pragma omp simd
          for (std::ptrdiff_t x = 0; x < width; ++x) here[x] = to_link(row[x]);
        } else
          here.swap(below);  // row y's conductances were computed as "below" of row y - 1
        float* h = horizontal.row(y);
        float* v = vertical.row(y);
        const bool has_below = y + 1 < height;
        if (has_below) {
          const float* next = value.row(y + 1);
#pragma omp simd
          for (std::ptrdiff_t x = 0; x < width; ++x) below[x] = to_link(next[x]);
        }
        for (std::ptrdiff_t tx = 0; tx < tiles_x; ++tx) {
          // A tile whose pixels (and the pixels right of and below it) all have conductance
          // zero keeps its links at zero without writing them: in-focus parts of a frame cost
          // one read of `value` and nothing else.
          const std::ptrdiff_t x0 = tx * tile, x1 = std::min(width, x0 + tile);
          const std::ptrdiff_t x1_right = std::min(width, x1 + 1);
          // The checks compare bit patterns as integers (integer reductions vectorise; float
          // min/max reductions do not, in GCC 12): for floats >= +0 the order is the same, a
          // negative float (or -0) is a negative integer, NaN and infinity are >= kInfinity.
          // Negatives are found by OR-ing the sign bits, not by a min: with SSE2 alone
          // (TRIDIFF_NATIVE=OFF) GCC 12 compiled the max and min pair through an MMX register
          // and left the x87 stack marked full (no emms), so the caller's next long double
          // result was NaN.
          std::int32_t highest = 0, sign_bits = 0;
#pragma omp simd reduction(max : highest) reduction(| : sign_bits)
          for (std::ptrdiff_t x = x0; x < x1_right; ++x) {
            const auto b = std::bit_cast<std::int32_t>(here[x]);
            highest = std::max(highest, b);
            sign_bits |= b;
          }
          if (has_below) {
#pragma omp simd reduction(max : highest) reduction(| : sign_bits)
            for (std::ptrdiff_t x = x0; x < x1; ++x) {
              const auto b = std::bit_cast<std::int32_t>(below[x]);
              highest = std::max(highest, b);
              sign_bits |= b;
            }
          }
          if (sign_bits < 0 || highest >= kInfinity) bad_value = true;
          if (highest == 0) continue;
          // Valid conductances give valid links (each the smaller of two).
          std::int32_t hm = 0, vm = 0;
          const std::ptrdiff_t h_end = std::min(x1, width - 1);  // the last column has no link
#pragma omp simd reduction(max : hm)
          for (std::ptrdiff_t x = x0; x < h_end; ++x) {
            h[x] = std::min(here[x], here[x + 1]);
            hm = std::max(hm, std::bit_cast<std::int32_t>(h[x]));
          }
          if (has_below) {
#pragma omp simd reduction(max : vm)
            for (std::ptrdiff_t x = x0; x < x1; ++x) {
              v[x] = std::min(here[x], below[x]);
              vm = std::max(vm, std::bit_cast<std::int32_t>(v[x]));
            }
          }
          float& h_tile = h_max[ty * tiles_x + tx];
          float& v_tile = v_max[ty * tiles_x + tx];
          h_tile = std::max(h_tile, std::bit_cast<float>(hm));
          v_tile = std::max(v_tile, std::bit_cast<float>(vm));
        }
      }
    }
  }
  if (bad_value) throw_bad_conductance(value, to_link);
  links.set_activity(h_max, v_max);
  return links;
}

}  // namespace tridiff
