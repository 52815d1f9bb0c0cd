// Reading and writing images with OpenImageIO: colour in linear light, depth as linear
// distance, and outputs written whole or not at all.
#pragma once

#include <cstdint>
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
  Image pixels;            // linear light, 3 channels (RGB) or 4 (RGBA)
  ColorEncoding encoding;  // what the file held (never Auto)
};

// The most pixels a file may declare before reading it is refused: a 16384 x 16384 image.
// Checked against the header before any pixel is allocated (a 100-byte PNG can declare a
// gigapixel image); a caller with the memory raises it per call.
inline constexpr std::int64_t kDefaultMaxPixels = std::int64_t(1) << 28;

struct ReadOptions {
  ColorEncoding encoding = ColorEncoding::Auto;  // Auto: from the file's metadata
  std::int64_t max_pixels = kDefaultMaxPixels;   // larger files are refused before reading
  int threads = 0;                               // for the sRGB decoding; 0: all cores
};

// Reads the colour channels of `path` (R, G, B[, A]; a one-channel file is grey and is
// expanded to RGB) and converts them to linear light. Every value read is finite: a NaN or an
// infinity in the file (only half and float data can hold one) is an ImageIoError naming the
// file, the pixel and the channel. A file of more than `options.max_pixels` pixels, a damaged or
// truncated file (also one whose reader fills the missing part with black) and a file too
// large for the memory are ImageIoErrors naming it.
ColorImage read_color(const std::string& path, const ReadOptions& options = {});

// How the values of a depth channel map to distance from the camera.
enum class DepthConvention {
  Linear,      // the value is the distance
  Normalized,  // value v in [0, 1]: distance = near + v * (far - near)
  Inverse,     // value v > 0 is 1 / distance (disparity-like)
};

struct DepthOptions {
  std::string channel;  // channel name ("Z", "depth", "A", ...); empty: "Z" if present, else
                        // "depth" (any case), else the only channel, else the first colour
                        // channel of a grey image (all channels but alpha equal at every
                        // pixel); any other file is an error listing its channels
  DepthConvention convention = DepthConvention::Linear;
  float near_plane = 0.f, far_plane = 0.f;      // for Normalized
  std::int64_t max_pixels = kDefaultMaxPixels;  // as for read_color
};

// Reads one channel of `path` as linear distance (one-channel image). Every value must be
// finite and positive after conversion, and a Normalized value must lie in [0, 1]; otherwise
// the error names the file, channel and pixel. Limits and damage as for read_color.
Image read_depth(const std::string& path, const DepthOptions& options = {});

struct WriteOptions {
  ColorEncoding encoding = ColorEncoding::Auto;  // Linear: integer formats store linear values
  int threads = 0;                               // for the sRGB encoding; 0: all cores
  // OpenEXR: 32-bit float, every value kept to the bit. Otherwise half (11 significant bits,
  // half the size), or float when a value exceeds half's range.
  bool float32 = false;
};

// The bytes of `image` (linear light) encoded in the format of `path`'s extension (.png .jpg
// .tif .exr ...); nothing is written. Integer formats are sRGB-encoded and quantised unless
// `options.encoding` is Linear; float formats (.exr, .hdr) keep linear values. Radiance .hdr
// (RGBE: 8 bits of mantissa per channel and a shared exponent, no negative values) holds RGB
// only: a grey image is written as three equal channels, an alpha channel is left out.
std::vector<unsigned char> encode_image(const std::string& path, const Image& image,
                                        const WriteOptions& options = {});

// encode_image, then the file written as an OutputFiles set of one (output_files.hpp): whole
// or not at all, a full disk an error, and never over a folder or a special file.
void write_image(const std::string& path, const Image& image, const WriteOptions& options = {});

// Refuses (ImageIoError naming the file) a path whose format encode_image cannot write
// whatever the image: no extension, a format OpenImageIO has no writer for or cannot encode
// into memory. Touches nothing on disk: a program checks its outputs with it (and the file
// system side with OutputFiles::claim) before long work.
void check_image_path(const std::string& path);

// Channel names of `path` (for error messages and --help listings).
std::vector<std::string> channel_names(const std::string& path);

}  // namespace tridiff
