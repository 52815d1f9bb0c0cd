// The shared tile classification (tiles.hpp).
#include "tridiff/dof/tiles.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "tridiff/threads.hpp"

namespace tridiff {
namespace {

int thread_count(int threads) { return resolve_threads(threads); }

// The tile's own statistics from its pixels.
TileInfo classify(ConstPlane coc, const Rect& area, FocusTest focus) {
  TileInfo info;
  info.min_coc = info.max_coc = coc(area.x, area.y);
  bool near = false, far = false;
  std::ptrdiff_t x0 = area.x + area.width, x1 = -1, y0 = area.y + area.height, y1 = -1;
  for (std::ptrdiff_t y = area.y; y < area.y + area.height; ++y) {
    const float* row = coc.row(y);
    for (std::ptrdiff_t x = area.x; x < area.x + area.width; ++x) {
      const float c = row[x];
      info.min_coc = std::min(info.min_coc, c);
      info.max_coc = std::max(info.max_coc, c);
      if (focus.is_sharp(c)) continue;
      x0 = std::min(x0, x);
      x1 = std::max(x1, x);
      y0 = std::min(y0, y);
      y1 = std::max(y1, y);
      info.max_radius = std::max(info.max_radius, std::abs(c) / 2);
      near = near || c < 0;
      far = far || c > 0;
    }
  }
  info.kind = static_cast<TileKind>((far ? 1 : 0) | (near ? 2 : 0));
  if (x1 >= 0) info.blurred = {x0, y0, x1 - x0 + 1, y1 - y0 + 1};
  return info;
}

}  // namespace

TileMap::TileMap(ConstPlane coc, float in_focus_coc_px, std::ptrdiff_t tile,
                 std::ptrdiff_t margin_px, int threads)
    : width_(coc.width()), height_(coc.height()), tile_(tile), in_focus_(in_focus_coc_px) {
  if (tile < 1) throw InvalidArgument("tile", "must be at least 1, got " + std::to_string(tile));
  if (margin_px < 0)
    throw InvalidArgument("margin_px", "must be >= 0, got " + std::to_string(margin_px));
  if (!(in_focus_coc_px >= 0)) throw InvalidArgument("in_focus_coc_px", "must be >= 0");
  tiles_x_ = (width_ + tile - 1) / tile;
  tiles_y_ = (height_ + tile - 1) / tile;
  info_.resize(std::size_t(tiles_x_ * tiles_y_));

  // 1. Each tile's own range and kind.
#pragma omp parallel for schedule(static) num_threads(thread_count(threads))
  for (std::ptrdiff_t ty = 0; ty < tiles_y_; ++ty)
    for (std::ptrdiff_t tx = 0; tx < tiles_x_; ++tx)
      info_[std::size_t(ty * tiles_x_ + tx)] = classify(coc, rect(tx, ty), focus());

  // 2. Reach: every tile with a disc stamps its largest radius onto the tiles that its pixels'
  // discs can overlap (its largest extent around the box of its out-of-focus pixels). Clamping
  // the reach at the frame edge also covers a mirror border (the folded part of a disc lands
  // nearer its centre than the unfolded part would). Serial: the stamps overlap, and there are
  // few tiles (8160 at 3840 x 2160).
  for (std::ptrdiff_t ty = 0; ty < tiles_y_; ++ty)
    for (std::ptrdiff_t tx = 0; tx < tiles_x_; ++tx) {
      const TileInfo& source = at(tx, ty);
      if (source.max_radius <= 0) continue;
      const bool near = source.kind == TileKind::near || source.kind == TileKind::mixed;
      // A disc wider than the frame reaches all of it: cap before converting (|CoC| may be huge).
      const float radius = std::min(source.max_radius, float(width_ + height_));
      const std::ptrdiff_t extent =
          static_cast<std::ptrdiff_t>(std::ceil(radius + 0.5f)) + margin_px;
      const Rect& area = source.blurred;
      const std::ptrdiff_t x0 = std::max<std::ptrdiff_t>(area.x - extent, 0) / tile_,
                           x1 = std::min(area.x + area.width - 1 + extent, width_ - 1) / tile_,
                           y0 = std::max<std::ptrdiff_t>(area.y - extent, 0) / tile_,
                           y1 = std::min(area.y + area.height - 1 + extent, height_ - 1) / tile_;
      for (std::ptrdiff_t j = y0; j <= y1; ++j)
        for (std::ptrdiff_t i = x0; i <= x1; ++i) {
          TileInfo& target = info_[std::size_t(j * tiles_x_ + i)];
          target.reach_radius = std::max(target.reach_radius, source.max_radius);
          // A mixed tile's largest radius may be a far pixel's; near reach stays conservative.
          if (near)
            target.near_reach_radius = std::max(target.near_reach_radius, source.max_radius);
        }
    }

  // 3. Frame summaries.
  std::ptrdiff_t worked = 0;
  for (std::ptrdiff_t ty = 0; ty < tiles_y_; ++ty)
    for (std::ptrdiff_t tx = 0; tx < tiles_x_; ++tx) {
      const TileInfo& info = at(tx, ty);
      has_near_ = has_near_ || info.kind == TileKind::near || info.kind == TileKind::mixed;
      has_far_ = has_far_ || info.kind == TileKind::far || info.kind == TileKind::mixed;
      max_radius_ = std::max(max_radius_, info.max_radius);
      if (info.reach_radius > 0) worked += rect(tx, ty).area();
    }
  work_fraction_ = double(worked) / double(width_ * height_);
}

Rect TileMap::rect(std::ptrdiff_t tx, std::ptrdiff_t ty) const {
  const std::ptrdiff_t x = tx * tile_, y = ty * tile_;
  return {x, y, std::min(tile_, width_ - x), std::min(tile_, height_ - y)};
}

void copy_unreached_tiles(Plane out, ConstPlane in, const TileMap& tiles, int threads) {
  if (in.width() != tiles.width() || in.height() != tiles.height() ||
      out.width() != tiles.width() || out.height() != tiles.height())
    throw InvalidArgument("out", "planes must have the tile map's size");
#pragma omp parallel for schedule(static) num_threads(thread_count(threads))
  for (std::ptrdiff_t ty = 0; ty < tiles.tiles_y(); ++ty)
    for (std::ptrdiff_t tx = 0; tx < tiles.tiles_x(); ++tx) {
      if (tiles.needs_work(tx, ty)) continue;
      const Rect area = tiles.rect(tx, ty);
      for (std::ptrdiff_t y = area.y; y < area.y + area.height; ++y)
        std::copy_n(in.row(y) + area.x, area.width, out.row(y) + area.x);
    }
}

}  // namespace tridiff
