// libFuzzer target: arbitrary files through tridiff::read_color and tridiff::read_depth.
//
// Input layout: byte 0 picks the file's extension (OpenImageIO tries the reader of the
// extension first, then the others) and the colour encoding, byte 1 the depth options, the
// rest is the file. The
// readers may refuse a file with tridiff::Error; anything else is a finding: a crash, a
// sanitizer report, another exception (std::bad_alloc included), or a returned image that
// breaks io.hpp's promises (finite colour; finite, positive depth).
//
// OpenImageIO and the codecs under it are Debian's uninstrumented builds: the fuzzer is
// guided by the coverage of tridiff's own code only, but a memory error inside them is still
// caught where it touches memory our code allocated, and any crash is reported.
#include <stdlib.h>  // mkdtemp

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include "tridiff/image/io.hpp"
#include "tridiff/solvers/error.hpp"

namespace {

using namespace tridiff;

[[noreturn]] void finding(const std::string& what) {
  std::fprintf(stderr, "fuzz_image_read: %s\n", what.c_str());
  std::abort();
}

// One private folder per process, made once and removed at exit, so parallel fuzzers and
// other programs never see or clobber each other's files.
class Scratch {
 public:
  Scratch() {
    const char* base = std::getenv("TMPDIR");
    std::string pattern = std::string(base && *base ? base : "/tmp") + "/tridiff-fuzz-XXXXXX";
    if (!mkdtemp(pattern.data())) {
      std::perror("fuzz_image_read: mkdtemp");
      std::abort();
    }
    folder_ = pattern;
  }
  ~Scratch() {
    std::error_code ignored;
    std::filesystem::remove_all(folder_, ignored);
  }
  Scratch(const Scratch&) = delete;
  Scratch& operator=(const Scratch&) = delete;

  // Writes `bytes` to a file named for `extension`, replacing the previous one.
  std::string write(const char* extension, const std::uint8_t* bytes, std::size_t size) const {
    const std::string path = folder_ + "/input." + extension;
    std::ofstream file(path, std::ios::binary | std::ios::trunc);
    file.write(reinterpret_cast<const char*>(bytes), static_cast<std::streamsize>(size));
    if (!file.flush()) finding("cannot write " + path);
    return path;
  }

 private:
  std::string folder_;
};

// Far below the library's default (2^28): a header declaring more must be refused before any
// pixel is allocated, and what tridiff allocates for a file within the limit (a few MiB for
// 4 channels) stays far below the single allocation of 256 MiB that scripts/fuzz.sh reports.
constexpr std::int64_t kMaxPixels = std::int64_t(1) << 16;

// Bits 0-2 of byte 0.
const char* pick_extension(std::uint8_t byte) {
  constexpr const char* kExtensions[] = {"png", "jpg", "tif", "exr", "hdr", "bmp", "tga", "ppm"};
  return kExtensions[byte & 7];
}

// Bits 3-4 of byte 0 (3 is past the last enumerator).
ColorEncoding pick_encoding(std::uint8_t byte) {
  return static_cast<ColorEncoding>((byte >> 3) & 3);
}

// Bits 0-2: the channel asked for; bits 3-4: the convention (3 is past the last enumerator);
// bits 5-7: the near and far planes, valid ones and each way of being wrong.
DepthOptions pick_depth_options(std::uint8_t byte) {
  constexpr const char* kChannels[] = {"", "Z", "depth", "A", "R", "Y", "G", "no such channel"};
  constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
  constexpr float kInf = std::numeric_limits<float>::infinity();
  constexpr float kPlanes[][2] = {{0, 0}, {0, 1},    {1, 10},   {0.1f, 1e4f},
                                  {5, 1}, {kNan, 1}, {0, kInf}, {-1, 1}};
  DepthOptions options;
  options.channel = kChannels[byte & 7];
  options.convention = static_cast<DepthConvention>((byte >> 3) & 3);
  options.near_plane = kPlanes[byte >> 5][0];
  options.far_plane = kPlanes[byte >> 5][1];
  options.max_pixels = kMaxPixels;
  return options;
}

void check_finite(const Image& image, const char* what, bool positive) {
  for (int c = 0; c < image.channels(); ++c)
    for (std::ptrdiff_t y = 0; y < image.height(); ++y)
      for (std::ptrdiff_t x = 0; x < image.width(); ++x) {
        const float v = image(x, y, c);
        if (!std::isfinite(v) || (positive && !(v > 0)))
          finding(std::string(what) + " returned " + std::to_string(v) + " at pixel (" +
                  std::to_string(x) + ", " + std::to_string(y) + ") of channel " +
                  std::to_string(c));
      }
}

void read_as_color(const std::string& path, ColorEncoding encoding) {
  try {
    const ColorImage color =
        read_color(path, {.encoding = encoding, .max_pixels = kMaxPixels, .threads = 1});
    if (color.pixels.channels() != 3 && color.pixels.channels() != 4)
      finding("read_color returned " + std::to_string(color.pixels.channels()) + " channels");
    if (color.encoding == ColorEncoding::Auto) finding("read_color returned encoding Auto");
    check_finite(color.pixels, "read_color", false);
  } catch (const Error&) {
    // Refused: allowed.
  }
}

void read_as_depth(const std::string& path, const DepthOptions& options) {
  try {
    const Image depth = read_depth(path, options);
    if (depth.channels() != 1)
      finding("read_depth returned " + std::to_string(depth.channels()) + " channels");
    check_finite(depth, "read_depth", true);
  } catch (const Error&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  static const Scratch scratch;
  const std::string path = scratch.write(pick_extension(data[0]), data + 2, size - 2);
  read_as_color(path, pick_encoding(data[0]));
  read_as_depth(path, pick_depth_options(data[1]));
  return 0;
}
