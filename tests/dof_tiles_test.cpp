// The shared tile classification against a brute-force per-pixel reach, and against the scatter
// reference: a tile that needs no work is one the reference leaves untouched.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "test_util.hpp"
#include "tridiff/dof/method.hpp"
#include "tridiff/dof/tiles.hpp"
#include "tridiff/solvers/solve.hpp"  // kMaxThreads

namespace tridiff {
namespace {

using testing_util::make_coc;
using testing_util::random_image;

// A sparse CoC map: sharp, with a few discs of random signed diameter up to max_coc.
Image sparse_coc(std::ptrdiff_t width, std::ptrdiff_t height, float max_coc, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> coc(-max_coc, max_coc);
  std::uniform_int_distribution<int> px(0, int(width - 1)), py(0, int(height - 1));
  Image map(width, height, 1);
  for (int k = 0; k < 6; ++k) map(px(rng), py(rng), 0) = coc(rng);
  return map;
}

// The largest radius of a pixel whose disc (ceil(r + 1/2) + margin) overlaps the rectangle.
float brute_force_reach(ConstPlane coc, const Rect& area, float in_focus, std::ptrdiff_t margin) {
  float reach = 0;
  for (std::ptrdiff_t y = 0; y < coc.height(); ++y)
    for (std::ptrdiff_t x = 0; x < coc.width(); ++x) {
      const float c = coc(x, y);
      if (std::abs(c) < in_focus) continue;
      const std::ptrdiff_t e = std::ptrdiff_t(std::ceil(std::abs(c) / 2 + 0.5f)) + margin;
      const bool overlaps = x + e >= area.x && x - e < area.x + area.width && y + e >= area.y &&
                            y - e < area.y + area.height;
      if (overlaps) reach = std::max(reach, std::abs(c) / 2);
    }
  return reach;
}

TEST(DofTiles, ReachCoversEveryPixelDiscAndKindsMatchThePixels) {
  for (unsigned seed = 1; seed <= 6; ++seed)
    for (std::ptrdiff_t margin : {0, 2}) {
      const Image coc = sparse_coc(97, 65, 40.f, seed);
      const TileMap tiles(coc.plane(0), 1.f, 16, margin, 2);
      ASSERT_EQ(tiles.tiles_x(), 7);
      ASSERT_EQ(tiles.tiles_y(), 5);
      std::ptrdiff_t reached_pixels = 0;
      for (std::ptrdiff_t ty = 0; ty < tiles.tiles_y(); ++ty)
        for (std::ptrdiff_t tx = 0; tx < tiles.tiles_x(); ++tx) {
          const Rect area = tiles.rect(tx, ty);
          const float exact = brute_force_reach(coc.plane(0), area, 1.f, margin);
          // Conservative (a tile's largest radius stands for all its pixels), never short.
          EXPECT_GE(tiles.at(tx, ty).reach_radius, exact) << tx << "," << ty;
          EXPECT_EQ(tiles.needs_work(tx, ty), tiles.at(tx, ty).reach_radius > 0);
          bool near = false, far = false;
          for (std::ptrdiff_t y = area.y; y < area.y + area.height; ++y)
            for (std::ptrdiff_t x = area.x; x < area.x + area.width; ++x) {
              near = near || coc(x, y, 0) <= -1.f;
              far = far || coc(x, y, 0) >= 1.f;
            }
          EXPECT_EQ(tiles.at(tx, ty).kind, TileKind((far ? 1 : 0) | (near ? 2 : 0)));
          if (tiles.needs_work(tx, ty)) reached_pixels += area.area();
        }
      EXPECT_DOUBLE_EQ(tiles.work_fraction(), double(reached_pixels) / (97.0 * 65.0));
    }
}

TEST(DofTiles, SummariesOfSharpNearAndFarFrames) {
  const TileMap sharp(make_coc(50, 40, [](auto, auto) { return 0.9f; }).plane(0), 1.f);
  EXPECT_FALSE(sharp.has_near());
  EXPECT_FALSE(sharp.has_far());
  EXPECT_EQ(sharp.work_fraction(), 0.0);
  EXPECT_EQ(sharp.max_radius(), 0.f);

  const Image far_coc = make_coc(50, 40, [](auto x, auto) { return x < 25 ? 0.f : 6.f; });
  const TileMap far(far_coc.plane(0), 1.f, 8);
  EXPECT_TRUE(far.has_far());
  EXPECT_FALSE(far.has_near());
  EXPECT_EQ(far.max_radius(), 3.f);
  EXPECT_EQ(far.at(0, 0).kind, TileKind::sharp);
  EXPECT_FALSE(far.needs_work(0, 0));  // 3.5 px of reach do not cross 8 px of sharp tile
  EXPECT_EQ(far.at(0, 0).near_reach_radius, 0.f);

  const Image near_coc = make_coc(50, 40, [](auto x, auto) { return x < 25 ? -9.f : 0.f; });
  const TileMap near(near_coc.plane(0), 1.f, 8);
  EXPECT_TRUE(near.has_near());
  EXPECT_FALSE(near.has_far());
  EXPECT_EQ(near.at(6, 0).kind, TileKind::sharp);
  EXPECT_EQ(near.at(3, 0).near_reach_radius, 4.5f);  // tile x 24..31 holds both
}

TEST(DofTiles, UnreachedTilesAreWhatTheScatterReferenceLeavesUntouched) {
  const Image color = random_image(120, 90, 3, 0.f, 1.f, 7);
  const Image coc = sparse_coc(120, 90, 30.f, 11);
  Image out;
  DofReport report;
  DofOptions settings;
  report = depth_of_field(out, color, coc.plane(0), find_dof_method("scatter"), settings);
  const TileMap tiles(coc.plane(0), settings.in_focus_coc_px, 16);
  ASSERT_GT(tiles.work_fraction(), 0.0);
  ASSERT_LT(tiles.work_fraction(), 1.0);
  for (std::ptrdiff_t ty = 0; ty < tiles.tiles_y(); ++ty)
    for (std::ptrdiff_t tx = 0; tx < tiles.tiles_x(); ++tx) {
      if (tiles.needs_work(tx, ty)) continue;
      const Rect area = tiles.rect(tx, ty);
      for (int c = 0; c < 3; ++c)
        for (std::ptrdiff_t y = area.y; y < area.y + area.height; ++y)
          for (std::ptrdiff_t x = area.x; x < area.x + area.width; ++x)
            ASSERT_EQ(out(x, y, c), color(x, y, c)) << x << "," << y;
    }
}

TEST(DofTiles, CopyUnreachedTilesWritesOnlyThoseTiles) {
  const Image in = random_image(40, 30, 1);
  const Image coc = make_coc(40, 30, [](auto x, auto y) { return x < 8 && y < 8 ? 4.f : 0.f; });
  const TileMap tiles(coc.plane(0), 1.f, 8);
  Image out(40, 30, 1);
  copy_unreached_tiles(out.plane(0), in.plane(0), tiles);
  for (std::ptrdiff_t y = 0; y < 30; ++y)
    for (std::ptrdiff_t x = 0; x < 40; ++x) {
      const bool reached = x < 16 && y < 16;
      EXPECT_EQ(out(x, y, 0), reached ? 0.f : in(x, y, 0)) << x << "," << y;
    }
}

// One definition of "in focus": every finite CoC is exactly one of sharp, near and far, and the
// tiles are classified by the same predicate (TileMap::focus()).
TEST(DofTiles, FocusTestIsTheTileClassification) {
  for (const float in_focus : {1.f, 2.5f}) {
    const Image coc = sparse_coc(97, 61, 12.f, 7);
    const TileMap tiles(coc.plane(0), in_focus, 16);
    const FocusTest focus = tiles.focus();
    EXPECT_EQ(focus.sharp_below, in_focus);
    for (std::ptrdiff_t ty = 0; ty < tiles.tiles_y(); ++ty)
      for (std::ptrdiff_t tx = 0; tx < tiles.tiles_x(); ++tx) {
        const Rect area = tiles.rect(tx, ty);
        bool near = false, far = false;
        for (std::ptrdiff_t y = area.y; y < area.y + area.height; ++y)
          for (std::ptrdiff_t x = area.x; x < area.x + area.width; ++x) {
            const float c = coc(x, y, 0);
            ASSERT_EQ(int(focus.is_sharp(c)) + int(focus.is_near(c)) + int(focus.is_far(c)), 1)
                << c;
            near = near || focus.is_near(c);
            far = far || focus.is_far(c);
          }
        const TileKind kind = tiles.at(tx, ty).kind;
        EXPECT_EQ(near, kind == TileKind::near || kind == TileKind::mixed);
        EXPECT_EQ(far, kind == TileKind::far || kind == TileKind::mixed);
      }
  }
}

TEST(DofTiles, BadArgumentsAreNamed) {
  const Image coc(10, 10, 1);
  EXPECT_THROW(TileMap(coc.plane(0), 1.f, 0), InvalidArgument);
  EXPECT_THROW(TileMap(coc.plane(0), 1.f, 8, -1), InvalidArgument);
  Image other(11, 10, 1);
  const TileMap tiles(coc.plane(0), 1.f, 8);
  EXPECT_THROW(copy_unreached_tiles(other.plane(0), coc.plane(0), tiles), InvalidArgument);
  // `threads` means what it means everywhere in the library: 0 to kMaxThreads.
  for (int threads : {-1, kMaxThreads + 1, 1 << 20}) {
    EXPECT_EQ(testing_util::invalid_argument_of([&] {
                TileMap(coc.plane(0), 1.f, 8, 0, threads);
              }).argument,
              "threads")
        << threads;
    Image out(10, 10, 1);
    EXPECT_EQ(testing_util::invalid_argument_of([&] {
                copy_unreached_tiles(out.plane(0), coc.plane(0), tiles, threads);
              }).argument,
              "threads")
        << threads;
  }
  EXPECT_NO_THROW(TileMap(coc.plane(0), 1.f, 8, 0, kMaxThreads));
}

}  // namespace
}  // namespace tridiff
