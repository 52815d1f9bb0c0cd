// The pictures of views.hpp: what the methods see in a frame, for `tridiff dof --view`.
#include "tridiff/dof/views.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "tridiff/dof/near_layer.hpp"
#include "tridiff/dof/tiles.hpp"

namespace tridiff {
namespace {

void paint(Image& picture, std::ptrdiff_t x, std::ptrdiff_t y, const float (&rgb)[3]) {
  for (int c = 0; c < 3; ++c) picture(x, y, c) = rgb[c];
}

}  // namespace

Image near_layer_mask(ConstPlane coc, const DofOptions& options) {
  const NearLayer near = near_layer(coc, options.in_focus_coc_px, options.threads);
  Image mask(coc.width(), coc.height(), 1);
  for (std::ptrdiff_t y = 0; y < coc.height(); ++y)
    for (std::ptrdiff_t x = 0; x < coc.width(); ++x)
      mask(x, y, 0) = near.contains(coc(x, y)) ? 1.f : 0.f;
  return mask;
}

Image coc_view(ConstPlane coc) {
  float largest = 1e-6f;  // an all-sharp frame stays black rather than dividing by 0
  for (std::ptrdiff_t y = 0; y < coc.height(); ++y)
    for (std::ptrdiff_t x = 0; x < coc.width(); ++x)
      largest = std::max(largest, std::abs(coc(x, y)));
  Image picture(coc.width(), coc.height(), 3);
  for (std::ptrdiff_t y = 0; y < coc.height(); ++y)
    for (std::ptrdiff_t x = 0; x < coc.width(); ++x) {
      const float v = coc(x, y) / largest;
      picture(x, y, 0) = std::max(v, 0.f);
      picture(x, y, 1) = 0.25f * std::abs(v);
      picture(x, y, 2) = std::max(-v, 0.f);
    }
  return picture;
}

Image focal_plane_view(ConstPlane coc, const DofOptions& options) {
  const FocusTest focus{options.in_focus_coc_px};
  Image picture(coc.width(), coc.height(), 3);
  for (std::ptrdiff_t y = 0; y < coc.height(); ++y)
    for (std::ptrdiff_t x = 0; x < coc.width(); ++x) {
      const float c = coc(x, y);
      paint(picture, x, y,
            focus.is_near(c)  ? kViewNear
            : focus.is_far(c) ? kViewFar
                              : kViewInFocus);
    }
  return picture;
}

Image layers_view(ConstPlane coc, const DofOptions& options) {
  const Image mask = near_layer_mask(coc, options);
  Image picture(coc.width(), coc.height(), 3);
  for (int c = 0; c < 3; ++c) copy_plane(picture.plane(c), mask.plane(0));
  return picture;
}

Image tiles_view(const Image& color, ConstPlane coc, const DofOptions& options) {
  const TileMap tiles(coc, sharp_below_px(options.in_focus_coc_px), TileMap::kDefaultTile, 0,
                      options.threads);
  Image picture(coc.width(), coc.height(), 3);
  for (std::ptrdiff_t y = 0; y < coc.height(); ++y)
    for (std::ptrdiff_t x = 0; x < coc.width(); ++x) {
      const TileInfo& tile = tiles.of_pixel(x, y);
      const bool skipped = options.skip_in_focus && tile.reach_radius == 0;
      const float shade = skipped ? kSkippedTileShade : 1.f;
      for (int c = 0; c < 3; ++c) {
        // A grey input has one channel; RGBA's alpha is not shown.
        const float value = color(x, y, std::min(c, color.channels() - 1));
        picture(x, y, c) = shade * std::clamp(value, 0.f, 1.f);
      }
    }
  return picture;
}

DofView dof_view_named(std::string_view name) {
  if (name == "coc") return DofView::coc;
  if (name == "focal-plane") return DofView::focal_plane;
  if (name == "layers") return DofView::layers;
  if (name == "tiles") return DofView::tiles;
  throw InvalidArgument(
      "view", "'" + std::string(name) + "' is not a view (coc, focal-plane, layers or tiles)");
}

Image dof_view(DofView view, const Image& color, ConstPlane coc, const DofOptions& options) {
  validate_coc(color, coc, options.threads);
  switch (view) {
    case DofView::coc: return coc_view(coc);
    case DofView::focal_plane: return focal_plane_view(coc, options);
    case DofView::layers: return layers_view(coc, options);
    case DofView::tiles: return tiles_view(color, coc, options);
  }
  throw InvalidArgument("view", "is not a DofView");
}

}  // namespace tridiff
