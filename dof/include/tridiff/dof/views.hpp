// Pictures of what the depth-of-field methods see in a frame (`tridiff dof --view`): the signed
// CoC, the focal plane, the near layer and the tiles skipped as in focus. Each picture is a
// 3-channel image of the CoC map's size with values in [0, 1] (linear light).
#pragma once

#include <string_view>

#include "tridiff/dof/method.hpp"

namespace tridiff {

// The near layer that the diffusion methods blur on its own with DofOptions::layers: 1 where a
// pixel belongs to it, 0 where it is background; one channel, the CoC map's size. The one
// function outside the methods that states which pixels those are: near_layer (near_layer.hpp),
// as dof/src/diffusion_dof.cpp asks it.
Image near_layer_mask(ConstPlane coc, const DofOptions& options);

// The colours of the pictures.
inline constexpr float kViewNear[3] = {0.f, 0.f, 1.f};     // blue: in front of the focus
inline constexpr float kViewInFocus[3] = {0.f, 1.f, 0.f};  // green: sharp
inline constexpr float kViewFar[3] = {1.f, 0.f, 0.f};      // red: behind the focus
inline constexpr float kSkippedTileShade = 0.25f;          // the input's brightness there

// The signed CoC in false colour: red behind the focus, blue in front (green a quarter of
// either), black where 0; full brightness at the largest |CoC| of the frame.
Image coc_view(ConstPlane coc);
// Each pixel near, in focus or far by FocusTest{options.in_focus_coc_px} (the diffusion
// methods' threshold), in kViewNear, kViewInFocus or kViewFar.
Image focal_plane_view(ConstPlane coc, const DofOptions& options);
// near_layer_mask as a picture: white for the near layer, black for the background.
Image layers_view(ConstPlane coc, const DofOptions& options);
// The input (first three channels, clamped to [0, 1]) with the tiles that the methods skip as
// in focus darkened to kSkippedTileShade of it: the TileMap of every method's frame
// (TileMap::kDefaultTile squares, sharp below sharp_below_px(in_focus_coc_px), no margin).
// With options.skip_in_focus false no tile is skipped, so none is darkened.
Image tiles_view(const Image& color, ConstPlane coc, const DofOptions& options);

enum class DofView { coc, focal_plane, layers, tiles };

// "coc", "focal-plane", "layers" or "tiles"; InvalidArgument naming "view" and listing the
// names otherwise.
DofView dof_view_named(std::string_view name);

// The picture `view` of the frame, after validate_coc(color, coc) (InvalidArgument naming
// "coc" or the pixel otherwise).
Image dof_view(DofView view, const Image& color, ConstPlane coc, const DofOptions& options);

}  // namespace tridiff
