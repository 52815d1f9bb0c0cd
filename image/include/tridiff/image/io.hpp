// Reading and writing images with OpenImageIO: colour in linear light, depth as linear
// distance, and outputs written whole or not at all.
#pragma once

#include <string>
#include <vector>

#include "tridiff/image/image.hpp"

namespace tridiff {

// A file could not be read or written, or its content is not usable; the message names the
// file (and the channel or pixel at fault when there is one).
class ImageIoError : public Error {
 public:
  using Error::Error;
};

// How the numbers of a colour file are encoded.
enum class ColorEncoding {
  Auto,    // from the file: 8/16-bit integer data is sRGB unless its metadata says linear;
           // half and float data (OpenEXR, float TIFF) is linear
  Srgb,    // sRGB transfer curve
  Linear,  // already linear light
};

struct ColorImage {
  Image pixels;                  // linear light, 3 channels (RGB) or 4 (RGBA)
  ColorEncoding encoding;        // what the file held (never Auto)
};

// Reads the colour channels of `path` (R, G, B[, A]; a one-channel file is grey and is
// expanded to RGB) and converts them to linear light.
ColorImage read_color(const std::string& path, ColorEncoding encoding = ColorEncoding::Auto);

// How the values of a depth channel map to distance from the camera.
enum class DepthConvention {
  Linear,      // the value is the distance
  Normalized,  // value v in [0, 1]: distance = near + v * (far - near)
  Inverse,     // value v > 0 is 1 / distance (disparity-like)
};

struct DepthOptions {
  std::string channel;  // channel name ("Z", "depth", "A", ...); empty: "Z" if present, else
                        // "depth", else the first channel
  DepthConvention convention = DepthConvention::Linear;
  float near_plane = 0.f, far_plane = 0.f;  // for Normalized
};

// Reads one channel of `path` as linear distance (one-channel image). Every value must be
// finite and positive after conversion; otherwise the error names the file and pixel.
Image read_depth(const std::string& path, const DepthOptions& options = {});

// Writes `image` (linear light) to `path`, format from the extension (.png .jpg .tif .exr
// ...). Integer formats are sRGB-encoded and quantised unless `encoding` is Linear; float
// formats (.exr, .hdr, .pfm) keep linear values. Writes to a temporary file in the same folder
// and renames it over `path`: the file is whole or absent.
void write_image(const std::string& path, const Image& image,
                 ColorEncoding encoding = ColorEncoding::Auto);

// Channel names of `path` (for error messages and --help listings).
std::vector<std::string> channel_names(const std::string& path);

}  // namespace tridiff
