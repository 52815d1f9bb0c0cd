// The lens-character options of `tridiff dof` (issue 26): the aperture's shape or kernel image
// and the highlight treatment, into DofOptions.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "common.hpp"
#include "tridiff/dof/method.hpp"

namespace tridiff::cli {

extern const std::vector<std::string> kLensCharacterOptions;
extern const char* const kLensCharacterUsage;

// Reads the numbers into `settings` and checks their ranges (InvalidArgument naming the option,
// e.g. --aperture-blades) and registers --aperture-image as an input of `files`. Reads no file.
void plan_lens_character(const Arguments& args, DofOptions& settings, OutputFiles& files);

// Reads --aperture-image, if given, as one channel (the luminance of its colour) into
// `settings` and checks it (empty, negative, not finite, all zero: naming --aperture-image).
void load_aperture_image(const Arguments& args, DofOptions& settings, int threads);

// Runs `work`, naming the lens-character fields of its InvalidArgument as these options.
void with_lens_character_named(const std::function<void()>& work);

}  // namespace tridiff::cli
