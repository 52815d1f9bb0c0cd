// The lens-character options of `tridiff dof` (lens_character.hpp).
#include "lens_character.hpp"

#include <limits>
#include <memory>

#include "tridiff/dof/aperture.hpp"
#include "tridiff/image/io.hpp"

namespace tridiff::cli {

const std::vector<std::string> kLensCharacterOptions = {"aperture-blades",     "aperture-rotation",
                                                        "aperture-roundness",  "aperture-image",
                                                        "highlight-threshold", "highlight-gain"};

const char* const kLensCharacterUsage = R"(lens character (methods scatter, bokeh, auto)
  --aperture-blades N       0 = a circle (default), or a polygon of N >= 3 straight blades
  --aperture-rotation DEG   the polygon's rotation, counter-clockwise (default 0)
  --aperture-roundness R    0 = straight blades (default) .. 1 = a circle
  --aperture-image FILE     a custom aperture (its luminance; overrides the blades): a point of
                            light takes this picture, scaled to its CoC diameter
  --highlight-threshold T   linear light: an out-of-focus pixel whose largest channel exceeds T
                            is a highlight (default: none; bokeh: 1)
  --highlight-gain G        a highlight's excess over T is multiplied by G, hue kept (default 1)
)";

void with_lens_character_named(const std::function<void()>& work) {
  with_fields_as_options(kLensCharacterOptions, work);
}

void plan_lens_character(const Arguments& args, DofOptions& settings, OutputFiles& files) {
  settings.aperture.blades = args.integer("aperture-blades", 0);
  settings.aperture.rotation_deg = args.number("aperture-rotation", 0.f);
  settings.aperture.roundness = args.number("aperture-roundness", 0.f);
  settings.highlight_threshold =
      args.number("highlight-threshold", std::numeric_limits<float>::infinity());
  settings.highlight_gain = args.number("highlight-gain", 1.f);
  with_lens_character_named([&] { validate_lens_character(settings); });
  if (args.has("aperture-image")) files.input("--aperture-image", args.text("aperture-image", ""));
}

void load_aperture_image(const Arguments& args, DofOptions& settings, int threads) {
  if (!args.has("aperture-image")) return;
  const Image color = read_color(args.text("aperture-image", ""), {.encoding = ColorEncoding::Auto,
                                                                   .max_pixels = max_pixels(args),
                                                                   .threads = threads})
                          .pixels;
  // Rec. 709 luminance: the light the aperture lets through, whatever tint the picture has.
  auto kernel = std::make_shared<Image>(color.width(), color.height(), 1);
  for (std::ptrdiff_t y = 0; y < color.height(); ++y)
    for (std::ptrdiff_t x = 0; x < color.width(); ++x)
      (*kernel)(x, y, 0) =
          0.2126f * color(x, y, 0) + 0.7152f * color(x, y, 1) + 0.0722f * color(x, y, 2);
  with_lens_character_named([&] { validate_aperture_image(*kernel); });
  settings.aperture_image = std::move(kernel);
}

}  // namespace tridiff::cli
