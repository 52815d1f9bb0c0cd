// Built-in test scenes for the depth-of-field methods, given directly as colour and a signed CoC
// map (no depth, no lens), each made to provoke one known artefact (seed 000 §6, seed 002
// §28.3): a blurred foreground over a sharp background, colour leaking of a sharp foreground
// into a blurred background, very large blur, a smooth depth ramp, and bright highlights.
//
// Every scene is deterministic and has any size >= 1 x 1. Shapes and textures scale with the
// frame (1024^2 and 3840 x 2160 show the same scene); the CoC amplitudes are a blur budget in
// pixels that does not scale (as ThinLens::max_coc_px), so a method's work per pixel is the same
// at every size. The exceptions are `procedural` and `lamps` (the ray-traced scenes of
// scene.hpp), whose thin-lens CoC grows with the width.
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <string_view>

#include "tridiff/image/image.hpp"

namespace tridiff {

struct DofScene {
  std::string name;
  Image color;  // linear light, RGB; highlights may exceed 1
  Image coc;    // one channel: signed CoC diameter in pixels, negative in front of the focus
};

struct DofSceneInfo {
  std::string_view name;
  std::string_view provokes;  // what the scene provokes, one line
};

// Every built-in scene, in a fixed order: foreground-blur, sharp-foreground, large-coc,
// depth-gradient, highlights, procedural, lamps.
std::span<const DofSceneInfo> dof_scenes();

// The scene called `name` at width x height (InvalidArgument naming the known scenes, or the
// size, otherwise). `threads` for the ray-traced scenes' tracing (0: all cores).
DofScene make_dof_scene(std::string_view name, std::ptrdiff_t width, std::ptrdiff_t height,
                        int threads = 0);

// A textured frame of which a compact block at the top left (the frame's aspect, area
// `fraction` of the frame, rounded to whole pixels) is out of focus behind the focus (CoC +16
// px) and the rest is sharp (CoC 0): the scene for cost against out-of-focus fraction.
// InvalidArgument unless 0 <= fraction <= 1.
DofScene focus_fraction_scene(std::ptrdiff_t width, std::ptrdiff_t height, double fraction);

}  // namespace tridiff
