// Image I/O against files on disk: the sRGB curves, round trips per format, Auto encoding,
// depth channels and conventions, and every error path (including that failed writes leave
// nothing partial behind).
#include <gtest/gtest.h>
#include <unistd.h>

#include <OpenImageIO/imageio.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "tridiff/image/color.hpp"
#include "tridiff/image/io.hpp"
#include "test_util.hpp"

namespace tridiff::test {
namespace {

using namespace tridiff::testing_util;

namespace fs = std::filesystem;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

// The message of the E that `action` throws (a test failure if it throws nothing).
template <class E = ImageIoError>
std::string message_of(const std::function<void()>& action) {
  try {
    action();
  } catch (const E& error) {
    return error.what();
  }
  ADD_FAILURE() << "no exception thrown";
  return {};
}

// "(x, y)", as the errors name a pixel. (Appended piece by piece: "(" + std::string&& trips
// GCC 12's false -Wrestrict warning.)
std::string pixel_name(int x, int y) {
  std::string name("(");
  name += std::to_string(x);
  name += ", ";
  name += std::to_string(y);
  return name += ")";
}

// Writes interleaved `pixels` (of buffer type `buffer`) straight through OpenImageIO, so that
// reading is tested against files tridiff did not write.
void write_with_oiio(const std::string& path, int width, int height,
                     const std::vector<std::string>& names, OIIO::TypeDesc file_type,
                     OIIO::TypeDesc buffer, const void* pixels, const char* color_space = nullptr) {
  OIIO::ImageSpec spec(width, height, static_cast<int>(names.size()), file_type);
  spec.channelnames = names;
  spec.alpha_channel = -1;
  if (color_space != nullptr) spec.attribute("oiio:ColorSpace", color_space);
  auto output = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(output) << OIIO::geterror();
  ASSERT_TRUE(output->open(path, spec)) << output->geterror();
  ASSERT_TRUE(output->write_image(buffer, pixels)) << output->geterror();
  ASSERT_TRUE(output->close()) << output->geterror();
}

void write_floats(const std::string& path, int width, int height,
                  const std::vector<std::string>& names, const std::vector<float>& pixels,
                  OIIO::TypeDesc file_type = OIIO::TypeDesc::FLOAT) {
  ASSERT_EQ(pixels.size(), static_cast<std::size_t>(width * height) * names.size());
  write_with_oiio(path, width, height, names, file_type, OIIO::TypeDesc::FLOAT, pixels.data());
}

// A width x height float EXR with channels R, G, B and `depth_name` (value depth(x, y)).
void write_depth_exr(const std::string& path, int width, int height,
                     const std::function<float(int, int)>& depth,
                     const std::string& depth_name = "Z") {
  std::vector<float> pixels;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) pixels.insert(pixels.end(), {0.25f, 0.5f, 0.75f, depth(x, y)});
  write_floats(path, width, height, {"R", "G", "B", depth_name}, pixels);
}

OIIO::ImageSpec spec_of(const std::string& path) {
  auto input = OIIO::ImageInput::open(path);
  EXPECT_TRUE(input) << OIIO::geterror();
  return input ? input->spec() : OIIO::ImageSpec();
}

std::string bytes_of(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
}

class ImageIo : public ScratchFolderTest {};

// ---------------------------------------------------------------------------------------------
// sRGB curves

TEST(SrgbCurve, KnownPoints) {
  EXPECT_EQ(srgb_to_linear(0.f), 0.f);
  EXPECT_NEAR(srgb_to_linear(0.04045f), 0.04045f / 12.92f, 1e-9f);  // top of the linear part
  EXPECT_NEAR(srgb_to_linear(0.5f), 0.21404114f, 1e-7f);
  EXPECT_NEAR(srgb_to_linear(1.f), 1.f, 1e-7f);
  EXPECT_EQ(linear_to_srgb(0.f), 0.f);
  EXPECT_NEAR(linear_to_srgb(0.0031308f), 0.04045f, 1e-6f);
  EXPECT_NEAR(linear_to_srgb(0.21404114f), 0.5f, 1e-6f);
  EXPECT_NEAR(linear_to_srgb(1.f), 1.f, 1e-6f);
  EXPECT_EQ(linear_to_srgb(-0.5f), 0.f);  // negative light has no encoding: black
}

TEST(SrgbCurve, InverseRoundTrip) {
  for (int i = 0; i <= 10000; ++i) {
    const float encoded = static_cast<float>(i) / 10000.f;
    EXPECT_NEAR(linear_to_srgb(srgb_to_linear(encoded)), encoded, 1e-6f) << encoded;
    EXPECT_NEAR(srgb_to_linear(linear_to_srgb(encoded)), encoded, 1e-6f) << encoded;
  }
}

TEST(SrgbCurve, ImageOverloadsCurveColourAndLeaveAlpha) {
  const Image original = random_image(37, 5, 4, 0.f, 1.f, 1);
  for (int threads : {0, 1, 2, 3}) {
    Image image = original;
    srgb_to_linear(image, threads);
    for (std::ptrdiff_t y = 0; y < 5; ++y)
      for (std::ptrdiff_t x = 0; x < 37; ++x) {
        for (int c = 0; c < 3; ++c)
          ASSERT_EQ(image(x, y, c), srgb_to_linear(original(x, y, c))) << threads;
        ASSERT_EQ(image(x, y, 3), original(x, y, 3)) << "alpha changed, threads " << threads;
      }
    linear_to_srgb(image, threads);
    for (std::ptrdiff_t y = 0; y < 5; ++y)
      for (std::ptrdiff_t x = 0; x < 37; ++x)
        for (int c = 0; c < 4; ++c) ASSERT_NEAR(image(x, y, c), original(x, y, c), 1e-6f);
  }
  // The row padding stays zero.
  Image padded = make_image(3, 2, 1, [](auto, auto, int) { return 0.5f; });
  linear_to_srgb(padded);
  EXPECT_EQ(padded.data()[3], 0.f);
}

TEST(SrgbCurve, NegativeThreadsAreRejected) {
  Image image(2, 2, 3);
  const std::string message = message_of<InvalidArgument>([&] { srgb_to_linear(image, -1); });
  EXPECT_TRUE(contains(message, "'threads'"));
}

// ---------------------------------------------------------------------------------------------
// Round trips

TEST_F(ImageIo, FloatExrIsReadExactly) {
  const std::vector<float> pixels = {0.1f, 1e-7f,  123456.79f,   3.14159265f, -2.5f, 0.f,
                                     7e4f, 1e-30f, 0.333333343f, 1.f,         2.f,   65505.f};
  write_floats(file("float.exr"), 2, 2, {"R", "G", "B"}, pixels);
  const ColorImage read = read_color(file("float.exr"));
  EXPECT_EQ(read.encoding, ColorEncoding::Linear);
  ASSERT_EQ(read.pixels.channels(), 3);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 2; ++x)
      for (int c = 0; c < 3; ++c)
        EXPECT_EQ(read.pixels(x, y, c), pixels[(y * 2 + x) * 3 + c]) << x << "," << y << "," << c;
}

TEST_F(ImageIo, ExrBeyondHalfRangeIsWrittenAsFloat) {
  const Image image = make_image(3, 2, 3, [](auto x, auto y, int c) {
    return 1e5f * static_cast<float>(x + 1) + 0.1f * static_cast<float>(y) + 0.01f * c;
  });
  write_image(file("big.exr"), image);
  EXPECT_EQ(spec_of(file("big.exr")).format, OIIO::TypeDesc::FLOAT);
  const Image read = read_color(file("big.exr")).pixels;
  for (int c = 0; c < 3; ++c)
    for (int y = 0; y < 2; ++y)
      for (int x = 0; x < 3; ++x) EXPECT_EQ(read(x, y, c), image(x, y, c));
}

// Half keeps 11 significant bits and ends at 65504: 1 + 2^-20 rounds to 1 in it, 1e6 does not
// fit. With float32 both come back to the bit, and so does every other value.
TEST_F(ImageIo, Float32ExrKeepsWhatHalfCannotHold) {
  const float fine = 1.f + std::ldexp(1.f, -20);
  Image image = random_image(5, 3, 3, 0.001f, 8.f, 11);
  image(0, 0, 0) = fine;
  image(1, 2, 2) = 1e6f;
  image(4, 1, 1) = -3.f + std::ldexp(1.f, -21);
  write_image(file("float.exr"), image, {.float32 = true});
  EXPECT_EQ(spec_of(file("float.exr")).format, OIIO::TypeDesc::FLOAT);
  const Image read = read_color(file("float.exr")).pixels;
  for (int c = 0; c < 3; ++c)
    for (int y = 0; y < 3; ++y)
      for (int x = 0; x < 5; ++x)
        EXPECT_TRUE(same_bits(read(x, y, c), image(x, y, c))) << x << ", " << y << ", " << c;
  // Without it, a frame within half's range is written as half: the fine value is lost.
  Image small = image;
  small(1, 2, 2) = 2.f;
  write_image(file("half.exr"), small);
  EXPECT_EQ(spec_of(file("half.exr")).format, OIIO::TypeDesc::HALF);
  EXPECT_EQ(read_color(file("half.exr")).pixels(0, 0, 0), 1.f);
}

// Radiance RGBE: a shared exponent and 8 bits of mantissa per channel, so a channel is kept to
// within 2^-7 of the pixel's largest channel (a step of 2^(e-8), the largest in [2^(e-1), 2^e)).
// Grey is written as three equal channels and alpha is left out (the writer takes exactly 3).
TEST_F(ImageIo, HdrRoundTripWithinRgbePrecision) {
  for (const int channels : {1, 3, 4}) {
    const Image image = random_image(9, 4, channels, 0.001f, 100.f, 12);
    const std::string path = file("rgbe" + std::to_string(channels) + ".hdr");
    write_image(path, image);
    const Image read = read_color(path).pixels;
    ASSERT_EQ(read.channels(), 3) << channels;
    const int colour = channels == 4 ? 3 : channels;
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 9; ++x) {
        float largest = 0;
        for (int c = 0; c < colour; ++c) largest = std::max(largest, image(x, y, c));
        for (int c = 0; c < 3; ++c)
          ASSERT_NEAR(read(x, y, c), image(x, y, std::min(c, colour - 1)),
                      largest * std::ldexp(1.f, -7))
              << channels << " channels, pixel " << x << ", " << y << ", " << c;
      }
  }
}

// OpenImageIO 2.4 reads PFM but has no writer for it: refused from the path alone.
TEST_F(ImageIo, PfmIsRefusedBeforeAnyImage) {
  const std::string message = message_of([&] { check_image_path(file("out.pfm")); });
  EXPECT_TRUE(contains(message, "out.pfm: unknown image format '.pfm'"));
  EXPECT_TRUE(contains(message, ".exr"));
  EXPECT_TRUE(listing().empty());
}

TEST_F(ImageIo, HalfExrRoundTripWithinHalfPrecision) {
  const Image image = random_image(19, 7, 4, 0.001f, 8.f, 2);
  write_image(file("half.exr"), image);
  const OIIO::ImageSpec spec = spec_of(file("half.exr"));
  EXPECT_EQ(spec.format, OIIO::TypeDesc::HALF);
  EXPECT_EQ(spec.get_string_attribute("oiio:ColorSpace"), "Linear");

  const ColorImage read = read_color(file("half.exr"));
  EXPECT_EQ(read.encoding, ColorEncoding::Linear);
  ASSERT_EQ(read.pixels.channels(), 4);
  for (int c = 0; c < 4; ++c)
    for (int y = 0; y < 7; ++y)
      for (int x = 0; x < 19; ++x) {
        const float value = image(x, y, c);
        // Half keeps 11 significant bits: rounding moves a value by at most 2^-11 of itself.
        ASSERT_NEAR(read.pixels(x, y, c), value, value * std::ldexp(1.f, -11));
      }
}

// Integer round trips are exact to half a quantisation step in the encoded (sRGB) domain.
void expect_encoded_within(const Image& written, const Image& read, float step) {
  ASSERT_EQ(read.channels(), written.channels());
  for (int c = 0; c < written.channels(); ++c)
    for (std::ptrdiff_t y = 0; y < written.height(); ++y)
      for (std::ptrdiff_t x = 0; x < written.width(); ++x) {
        const bool colour = c < 3;  // alpha is stored linear
        const float expected = colour ? linear_to_srgb(written(x, y, c)) : written(x, y, c);
        const float got = colour ? linear_to_srgb(read(x, y, c)) : read(x, y, c);
        ASSERT_NEAR(got, expected, 0.5f * step + 1e-6f) << x << "," << y << "," << c;
      }
}

TEST_F(ImageIo, Tiff16RoundTripWithinQuantisationStep) {
  Image image = random_image(23, 9, 4, 0.f, 1.f, 3);
  image(4, 4, 3) = 0.f;  // fully transparent, yet its colour must survive
  image(4, 4, 1) = 0.6f;
  write_image(file("deep.tif"), image);
  const OIIO::ImageSpec spec = spec_of(file("deep.tif"));
  EXPECT_EQ(spec.format, OIIO::TypeDesc::UINT16);
  // Not tagged Linear: integer TIFF is sRGB to readers (see output_spec on why it carries no
  // "sRGB" tag).
  EXPECT_NE(spec.get_string_attribute("oiio:ColorSpace"), "Linear");

  const ColorImage read = read_color(file("deep.tif"));
  EXPECT_EQ(read.encoding, ColorEncoding::Srgb);
  expect_encoded_within(image, read.pixels, 1.f / 65535.f);
}

// The sRGB encoding and decoding run on `threads`: the bytes and the pixels do not depend on
// how many, and a bad count is refused before any file is touched.
TEST_F(ImageIo, ThreadsChangeNothingAndBadCountsAreRefused) {
  const Image image = random_image(37, 29, 4, 0.f, 1.f, 11);
  const auto one = encode_image(file("t.png"), image, {.threads = 1});
  EXPECT_EQ(encode_image(file("t.png"), image, {.threads = 2}), one);
  write_image(file("t.png"), image, {.threads = 2});
  const ColorImage a = read_color(file("t.png"), {.threads = 1});
  const ColorImage b = read_color(file("t.png"), {.threads = 2});
  EXPECT_EQ(image_difference(a.pixels, b.pixels).max, 0.0);
  EXPECT_EQ(
      invalid_argument_of([&] { encode_image(file("u.png"), image, {.threads = -1}); }).argument,
      "threads");
  EXPECT_EQ(invalid_argument_of([&] { read_color(file("t.png"), {.threads = -1}); }).argument,
            "threads");
  EXPECT_FALSE(std::filesystem::exists(file("u.png")));
}

TEST_F(ImageIo, Png8RoundTripWithinQuantisationStep) {
  Image image = random_image(31, 6, 4, 0.f, 1.f, 4);
  image(5, 2, 3) = 0.f;  // fully transparent, yet its colour must survive
  image(5, 2, 0) = 0.7f;
  write_image(file("rgba.png"), image);
  const OIIO::ImageSpec spec = spec_of(file("rgba.png"));
  EXPECT_EQ(spec.format, OIIO::TypeDesc::UINT8);
  EXPECT_EQ(spec.nchannels, 4);

  const ColorImage read = read_color(file("rgba.png"));
  EXPECT_EQ(read.encoding, ColorEncoding::Srgb);
  expect_encoded_within(image, read.pixels, 1.f / 255.f);
  EXPECT_EQ(read.pixels(5, 2, 3), 0.f);
}

TEST_F(ImageIo, OutOfRangeValuesAreClampedInIntegerFiles) {
  const Image image = make_image(4, 1, 3, [](auto x, auto, int) {
    const float values[] = {-1.f, 2.f, kNaN, kInf};
    return values[x];
  });
  write_image(file("clamped.png"), image);
  const Image read = read_color(file("clamped.png")).pixels;
  for (int c = 0; c < 3; ++c) {
    EXPECT_EQ(read(0, 0, c), 0.f);
    EXPECT_NEAR(read(1, 0, c), 1.f, 1e-6f);
    EXPECT_EQ(read(2, 0, c), 0.f);
    EXPECT_NEAR(read(3, 0, c), 1.f, 1e-6f);
  }
}

TEST_F(ImageIo, JpegRoundTripIsClose) {
  // A flat colour survives JPEG's block transform almost unchanged.
  const Image image = make_image(16, 16, 3, [](auto, auto, int c) { return 0.1f + 0.3f * c; });
  write_image(file("flat.jpg"), image);
  const ColorImage read = read_color(file("flat.jpg"));
  EXPECT_EQ(read.encoding, ColorEncoding::Srgb);
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(linear_to_srgb(read.pixels(8, 8, c)), linear_to_srgb(image(8, 8, c)), 2.f / 255.f);
}

TEST_F(ImageIo, LinearPngIsTaggedAndReadBackLinear) {
  const Image image = random_image(8, 8, 3, 0.f, 1.f, 5);
  write_image(file("linear.png"), image, {.encoding = ColorEncoding::Linear});
  EXPECT_EQ(spec_of(file("linear.png")).get_string_attribute("oiio:ColorSpace"), "Linear");
  const ColorImage read = read_color(file("linear.png"));
  EXPECT_EQ(read.encoding, ColorEncoding::Linear);
  for (int c = 0; c < 3; ++c)
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 8; ++x)
        ASSERT_NEAR(read.pixels(x, y, c), image(x, y, c), 0.5f / 255.f + 1e-7f);
}

// ---------------------------------------------------------------------------------------------
// Encodings and channels

TEST_F(ImageIo, AutoReads8BitPngAsSrgb) {
  const std::vector<std::uint8_t> pixels(4 * 3 * 3, 128);
  write_with_oiio(file("grey128.png"), 4, 3, {"R", "G", "B"}, OIIO::TypeDesc::UINT8,
                  OIIO::TypeDesc::UINT8, pixels.data());
  const ColorImage read = read_color(file("grey128.png"));
  EXPECT_EQ(read.encoding, ColorEncoding::Srgb);
  const float expected = srgb_to_linear(128.f / 255.f);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(read.pixels(3, 2, c), expected, 1e-6f * expected);

  // Asking overrides the file.
  const ColorImage raw = read_color(file("grey128.png"), {.encoding = ColorEncoding::Linear});
  EXPECT_EQ(raw.encoding, ColorEncoding::Linear);
  EXPECT_FLOAT_EQ(raw.pixels(0, 0, 0), 128.f / 255.f);
}

TEST_F(ImageIo, AutoReadsLinearTaggedIntegerFileLinear) {
  const std::vector<std::uint16_t> pixels(2 * 2 * 3, 32768);
  write_with_oiio(file("tagged.png"), 2, 2, {"R", "G", "B"}, OIIO::TypeDesc::UINT16,
                  OIIO::TypeDesc::UINT16, pixels.data(), "Linear");
  const ColorImage read = read_color(file("tagged.png"));
  EXPECT_EQ(read.encoding, ColorEncoding::Linear);
  EXPECT_FLOAT_EQ(read.pixels(1, 1, 2), 32768.f / 65535.f);
}

TEST_F(ImageIo, AutoReadsExrUnchanged) {
  const std::vector<float> pixels = {0.5f, 0.25f, 2.f, 0.75f};
  write_floats(file("linear.exr"), 1, 1, {"R", "G", "B", "A"}, pixels, OIIO::TypeDesc::HALF);
  const ColorImage read = read_color(file("linear.exr"));
  EXPECT_EQ(read.encoding, ColorEncoding::Linear);
  ASSERT_EQ(read.pixels.channels(), 4);
  for (int c = 0; c < 4; ++c) EXPECT_EQ(read.pixels(0, 0, c), pixels[c]);

  // Forcing sRGB curves the colour but never the alpha.
  const ColorImage forced = read_color(file("linear.exr"), {.encoding = ColorEncoding::Srgb});
  EXPECT_EQ(forced.encoding, ColorEncoding::Srgb);
  EXPECT_FLOAT_EQ(forced.pixels(0, 0, 0), srgb_to_linear(0.5f));
  EXPECT_EQ(forced.pixels(0, 0, 3), 0.75f);
}

TEST_F(ImageIo, GreyFileExpandsToThreeEqualChannels) {
  std::vector<std::uint8_t> pixels(5 * 4);
  for (std::size_t i = 0; i < pixels.size(); ++i) pixels[i] = static_cast<std::uint8_t>(i * 12);
  write_with_oiio(file("grey.png"), 5, 4, {"Y"}, OIIO::TypeDesc::UINT8, OIIO::TypeDesc::UINT8,
                  pixels.data());
  const ColorImage read = read_color(file("grey.png"));
  ASSERT_EQ(read.pixels.channels(), 3);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 5; ++x) {
      const float expected = srgb_to_linear(static_cast<float>(pixels[y * 5 + x]) / 255.f);
      // Within float rounding: OpenImageIO may scale by 1/255 rather than divide by 255.
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(read.pixels(x, y, c), expected, 1e-6f * expected);
    }
}

TEST_F(ImageIo, ChannelsAreFoundByName) {
  // Colour channels stored out of order, plus one that is not colour at all.
  const std::vector<float> pixels = {0.3f, 9.f, 0.1f, 0.2f};
  write_floats(file("named.exr"), 1, 1, {"B", "Z", "R", "G"}, pixels);
  const Image read = read_color(file("named.exr")).pixels;
  ASSERT_EQ(read.channels(), 3);
  EXPECT_EQ(read(0, 0, 0), 0.1f);
  EXPECT_EQ(read(0, 0, 1), 0.2f);
  EXPECT_EQ(read(0, 0, 2), 0.3f);
}

TEST_F(ImageIo, ChannelNamesListTheFile) {
  write_depth_exr(file("rgbz.exr"), 2, 2, [](int, int) { return 1.f; });
  const std::vector<std::string> names = channel_names(file("rgbz.exr"));
  EXPECT_EQ(std::set<std::string>(names.begin(), names.end()),
            (std::set<std::string>{"R", "G", "B", "Z"}));
}

TEST_F(ImageIo, NonFiniteColourIsRefusedNamingPixelAndChannel) {
  struct Case {
    float value;
    int x, y, channel;  // channel of R, G, B, A
    OIIO::TypeDesc type;
    const char* words;
  };
  constexpr OIIO::TypeDesc::BASETYPE kFloat = OIIO::TypeDesc::FLOAT, kHalf = OIIO::TypeDesc::HALF;
  const Case cases[] = {{kNaN, 3, 1, 1, kFloat, "pixel (3, 1) of channel 'G' is NaN"},
                        {kInf, 0, 2, 2, kFloat, "pixel (0, 2) of channel 'B' is infinite"},
                        {-kInf, 4, 0, 0, kFloat, "pixel (4, 0) of channel 'R' is infinite"},
                        {kNaN, 2, 2, 3, kFloat, "pixel (2, 2) of channel 'A' is NaN"},
                        {kInf, 1, 1, 0, kHalf, "pixel (1, 1) of channel 'R' is infinite"}};
  for (const Case& bad : cases) {
    SCOPED_TRACE(bad.words);
    std::vector<float> pixels(5 * 3 * 4, 0.5f);
    pixels[(bad.y * 5 + bad.x) * 4 + bad.channel] = bad.value;
    write_floats(file("bad.exr"), 5, 3, {"R", "G", "B", "A"}, pixels, bad.type);
    const std::string message = message_of([&] { read_color(file("bad.exr")); });
    EXPECT_TRUE(contains(message, "bad.exr: " + std::string(bad.words)));
  }
}

TEST_F(ImageIo, FiniteExtremesOfColourAreRead) {
  // 0 * value is 0 for every finite value, however large or small: none may be refused.
  constexpr float kMax = std::numeric_limits<float>::max();
  constexpr float kTiny = std::numeric_limits<float>::denorm_min();
  const std::vector<float> pixels = {kMax, -kMax, kTiny, -0.f, 0.f, 1.f};
  write_floats(file("extremes.exr"), 2, 1, {"R", "G", "B"}, pixels);
  const Image read = read_color(file("extremes.exr")).pixels;
  for (int x = 0; x < 2; ++x)
    for (int c = 0; c < 3; ++c) EXPECT_EQ(read(x, 0, c), pixels[x * 3 + c]) << x << "," << c;
}

// Float data forced through the sRGB curve: finite in the file, infinite once decoded (the
// curve's power overflows float above about 1e16): refused, not passed on as infinity. 1e15
// decodes to a finite (huge) value and is kept.
TEST_F(ImageIo, ForcedSrgbThatOverflowsIsRefusedNamingThePixel) {
  std::vector<float> pixels(4 * 2 * 3, 0.5f);
  pixels[(1 * 4 + 2) * 3 + 1] = 1e20f;  // pixel (2, 1), G
  write_floats(file("bright.exr"), 4, 2, {"R", "G", "B"}, pixels);
  const std::string message =
      message_of([&] { read_color(file("bright.exr"), {.encoding = ColorEncoding::Srgb}); });
  EXPECT_TRUE(contains(message,
                       "bright.exr: pixel (2, 1) of channel 'G' is too large for the "
                       "sRGB curve"))
      << message;
  EXPECT_EQ(read_color(file("bright.exr")).pixels(2, 1, 1), 1e20f);  // linear: as stored
  pixels[(1 * 4 + 2) * 3 + 1] = 1e15f;
  write_floats(file("bright.exr"), 4, 2, {"R", "G", "B"}, pixels);
  const float decoded =
      read_color(file("bright.exr"), {.encoding = ColorEncoding::Srgb}).pixels(2, 1, 1);
  EXPECT_NEAR(decoded / std::pow(1e15 / 1.055, 2.4), 1.0, 1e-4);
}

// ---------------------------------------------------------------------------------------------
// Depth

TEST_F(ImageIo, DepthPicksZByDefault) {
  write_depth_exr(file("rgbz.exr"), 6, 4, [](int x, int y) { return 1.f + x + 10.f * y; });
  const Image depth = read_depth(file("rgbz.exr"));
  ASSERT_EQ(depth.channels(), 1);
  ASSERT_EQ(depth.width(), 6);
  ASSERT_EQ(depth.height(), 4);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 6; ++x) EXPECT_EQ(depth(x, y, 0), 1.f + x + 10.f * y);
}

TEST_F(ImageIo, DepthFallsBackToDepthThenTheOnlyChannel) {
  write_depth_exr(
      file("rgbdepth.exr"), 2, 2, [](int x, int) { return 5.f + x; }, "depth");
  EXPECT_EQ(read_depth(file("rgbdepth.exr"))(1, 0, 0), 6.f);

  const std::vector<float> single = {4.f, 3.f};
  write_floats(file("single.exr"), 2, 1, {"distance"}, single);
  EXPECT_EQ(read_depth(file("single.exr"))(0, 0, 0), 4.f);
}

TEST_F(ImageIo, DepthFromDifferingColourChannelsIsRefused) {
  // Grey everywhere but the last pixel: the whole image is checked, not a sample of it.
  std::vector<float> pixels(4 * 3 * 3, 2.f);
  pixels.back() = 3.f;
  write_floats(file("rgb.exr"), 4, 3, {"R", "G", "B"}, pixels);
  const std::string message = message_of([&] { read_depth(file("rgb.exr")); });
  EXPECT_TRUE(contains(message, "rgb.exr: cannot tell which channel holds depth"));
  EXPECT_TRUE(contains(message, "(channels: R, G, B)"));
  EXPECT_TRUE(contains(message, "--depth-channel NAME"));
}

TEST_F(ImageIo, GreyRgbPngIsReadAsDepth) {
  // A depth map saved as 8-bit RGBA: R = G = B = level, alpha opaque (and so unlike colour).
  const int width = 4, height = 2;
  std::vector<std::uint8_t> pixels;
  for (int i = 0; i < width * height; ++i) {
    const auto level = static_cast<std::uint8_t>(30 * i + 15);
    pixels.insert(pixels.end(), {level, level, level, 255});
  }
  write_with_oiio(file("grey_depth.png"), width, height, {"R", "G", "B", "A"},
                  OIIO::TypeDesc::UINT8, OIIO::TypeDesc::UINT8, pixels.data());
  DepthOptions options;
  options.convention = DepthConvention::Normalized;
  options.near_plane = 1.f;
  options.far_plane = 11.f;
  const Image depth = read_depth(file("grey_depth.png"), options);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      // Level 15 is 1 + 10 * 15 / 255 = 1.588 m, ..., level 225 is 9.824 m.
      const float expected = 1.f + 10.f * static_cast<float>(30 * (y * width + x) + 15) / 255.f;
      EXPECT_NEAR(depth(x, y, 0), expected, 1e-5f) << x << "," << y;
    }
}

TEST_F(ImageIo, NaNInGreyDepthIsNamedAsNaN) {
  // Equal NaNs across R, G, B keep the file grey; the depth check then names the pixel.
  std::vector<float> pixels(3 * 2 * 3, 4.f);
  for (int c = 0; c < 3; ++c) pixels[(1 * 3 + 2) * 3 + c] = kNaN;
  write_floats(file("grey_nan.exr"), 3, 2, {"R", "G", "B"}, pixels);
  EXPECT_TRUE(contains(message_of([&] { read_depth(file("grey_nan.exr")); }),
                       "grey_nan.exr: pixel (2, 1) of channel 'R' is NaN"));
}

TEST_F(ImageIo, DepthByName) {
  std::vector<float> pixels;
  for (int x = 0; x < 3; ++x) pixels.insert(pixels.end(), {100.f + x, 2.f + x});
  write_floats(file("two.exr"), 3, 1, {"Z", "depth"}, pixels);
  DepthOptions options;
  options.channel = "depth";
  const Image depth = read_depth(file("two.exr"), options);
  for (int x = 0; x < 3; ++x) EXPECT_EQ(depth(x, 0, 0), 2.f + x);
  options.channel = "G";
  const std::string message = message_of([&] { read_depth(file("two.exr"), options); });
  EXPECT_TRUE(contains(message, "two.exr: channel 'G' not found (channels: Z, depth)"));
}

TEST_F(ImageIo, DepthNormalizedMapsToNearFar) {
  write_depth_exr(file("normalized.exr"), 5, 1, [](int x, int) { return 0.25f * x; });
  DepthOptions options;
  options.convention = DepthConvention::Normalized;
  options.near_plane = 2.f;
  options.far_plane = 10.f;
  const Image depth = read_depth(file("normalized.exr"), options);
  for (int x = 0; x < 5; ++x) EXPECT_FLOAT_EQ(depth(x, 0, 0), 2.f + 0.25f * x * 8.f);

  // v = 0 with near = 0 is distance zero: refused, naming the pixel.
  options.near_plane = 0.f;
  const std::string message = message_of([&] { read_depth(file("normalized.exr"), options); });
  EXPECT_TRUE(contains(message, "pixel (0, 0)"));
  EXPECT_TRUE(contains(message, "zero"));
}

TEST_F(ImageIo, DepthNormalizedOutsideUnitRangeIsRefused) {
  struct Case {
    float value;
    int x, y;
    const char* words;
  };
  // (Printed to float's max_digits10: -0.1f is -0.100000001.)
  const Case cases[] = {{1.5f, 2, 1, "is 1.5;"}, {-0.1f, 0, 2, "is -0.100000001;"}};
  DepthOptions options;
  options.convention = DepthConvention::Normalized;
  options.near_plane = 2.f;
  options.far_plane = 10.f;
  for (const Case& bad : cases) {
    SCOPED_TRACE(bad.words);
    write_depth_exr(file("bad.exr"), 4, 3,
                    [&](int x, int y) { return x == bad.x && y == bad.y ? bad.value : 0.5f; });
    const std::string message = message_of([&] { read_depth(file("bad.exr"), options); });
    EXPECT_TRUE(contains(
        message, "bad.exr: pixel " + pixel_name(bad.x, bad.y) + " of channel 'Z' " + bad.words));
    EXPECT_TRUE(contains(message, "must lie in [0, 1]"));
  }
}

TEST_F(ImageIo, DepthNormalizedNeedsValidPlanes) {
  write_depth_exr(file("d.exr"), 1, 1, [](int, int) { return 0.5f; });
  DepthOptions options;
  options.convention = DepthConvention::Normalized;
  const auto argument_of = [&](float near, float far) {
    options.near_plane = near;
    options.far_plane = far;
    try {
      read_depth(file("d.exr"), options);
    } catch (const InvalidArgument& error) {
      return error.argument();
    }
    return std::string("nothing thrown");
  };
  EXPECT_EQ(argument_of(-1.f, 10.f), "near_plane");
  EXPECT_EQ(argument_of(kNaN, 10.f), "near_plane");
  EXPECT_EQ(argument_of(5.f, 5.f), "far_plane");
  EXPECT_EQ(argument_of(5.f, 1.f), "far_plane");
  EXPECT_EQ(argument_of(1.f, kInf), "far_plane");
  EXPECT_EQ(argument_of(0.f, 1.f), "nothing thrown");
}

TEST_F(ImageIo, DepthInverseIsReciprocal) {
  write_depth_exr(file("inverse.exr"), 4, 2, [](int x, int y) { return 0.5f + x + 2.f * y; });
  DepthOptions options;
  options.convention = DepthConvention::Inverse;
  const Image depth = read_depth(file("inverse.exr"), options);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 4; ++x) EXPECT_FLOAT_EQ(depth(x, y, 0), 1.f / (0.5f + x + 2.f * y));

  write_depth_exr(file("inverse0.exr"), 4, 3,
                  [](int x, int y) { return x == 3 && y == 2 ? 0.f : 1.f; });
  const std::string message = message_of([&] { read_depth(file("inverse0.exr"), options); });
  EXPECT_TRUE(contains(message, "inverse0.exr: pixel (3, 2) of channel 'Z' is 0"));
  EXPECT_TRUE(contains(message, "infinite"));
}

TEST_F(ImageIo, DepthMissingChannelListsChannels) {
  const std::vector<float> pixels = {0.1f, 0.2f, 0.3f, 1.f};
  write_floats(file("rgba.exr"), 1, 1, {"R", "G", "B", "A"}, pixels);
  DepthOptions options;
  options.channel = "Z";
  const std::string message = message_of([&] { read_depth(file("rgba.exr"), options); });
  EXPECT_TRUE(contains(message, "tridiff: "));
  EXPECT_TRUE(contains(message, "rgba.exr: channel 'Z' not found (channels: R, G, B, A)"));
}

TEST_F(ImageIo, BadDepthValuesNameThePixel) {
  struct Case {
    float value;
    int x, y;
    const char* words;
  };
  const Case cases[] = {{kNaN, 2, 1, "is NaN"},
                        {-0.5f, 0, 2, "is negative (-0.5)"},
                        {kInf, 4, 0, "is infinite"},
                        {0.f, 3, 2, "is zero"}};
  for (const Case& bad : cases) {
    SCOPED_TRACE(bad.words);
    const std::string name = file("bad.exr");
    write_depth_exr(name, 5, 3,
                    [&](int x, int y) { return x == bad.x && y == bad.y ? bad.value : 1.f; });
    const std::string message = message_of([&] { read_depth(name); });
    EXPECT_TRUE(contains(
        message, "bad.exr: pixel " + pixel_name(bad.x, bad.y) + " of channel 'Z' " + bad.words));
  }
}

// ---------------------------------------------------------------------------------------------
// Errors

TEST_F(ImageIo, MissingFileIsNamed) {
  const std::string message = message_of([&] { read_color(file("absent.png")); });
  EXPECT_TRUE(contains(message, "absent.png: file not found"));
  EXPECT_TRUE(contains(message_of([&] { read_depth(file("absent.exr")); }), "absent.exr"));
  EXPECT_TRUE(contains(message_of([&] { channel_names(file("absent.tif")); }), "absent.tif"));
}

TEST_F(ImageIo, GarbageFileIsReportedUnreadable) {
  std::ofstream(file("garbage.png"), std::ios::binary) << "this is not a PNG at all, just text";
  const std::string message = message_of([&] { read_color(file("garbage.png")); });
  EXPECT_TRUE(contains(message, "garbage.png: cannot read"));

  std::ofstream(file("garbage.xyz"), std::ios::binary) << "nor is this anything";
  EXPECT_TRUE(contains(message_of([&] { read_color(file("garbage.xyz")); }),
                       "garbage.xyz: unknown image format"));
}

// (Not PNG: OpenImageIO 2.4's PNG reader longjmps past a string of its own on a truncated file,
// a 31-byte leak that LeakSanitizer would pin on this test.)
TEST_F(ImageIo, TruncatedFileIsReportedUnreadable) {
  for (const std::string extension : {".exr", ".tif"}) {
    write_image(file("whole" + extension), random_image(64, 64, 3, 0.f, 1.f, 6));
    const std::string bytes = bytes_of(file("whole" + extension));
    std::ofstream(file("cut" + extension), std::ios::binary) << bytes.substr(0, bytes.size() / 2);
    EXPECT_TRUE(contains(message_of([&] { read_color(file("cut" + extension)); }),
                         "cut" + extension + ": cannot read"));
  }
}

TEST_F(ImageIo, UnknownOutputExtensionWritesNothing) {
  const Image image(2, 2, 3);
  EXPECT_TRUE(contains(message_of([&] { write_image(file("out.xyz"), image); }),
                       "out.xyz: unknown image format"));
  EXPECT_TRUE(contains(message_of([&] { write_image(file("noextension"), image); }),
                       "noextension: has no extension"));
  EXPECT_TRUE(listing().empty());
}

// check_image_path refuses the formats write_image cannot write, without an image and without
// touching the disk (the folder is OutputFiles::claim's to check); a writable path passes.
TEST_F(ImageIo, CheckImagePathRefusesWhatWriteImageWould) {
  EXPECT_TRUE(contains(message_of([&] { check_image_path(file("out.xyz")); }),
                       "out.xyz: unknown image format"));
  EXPECT_TRUE(contains(message_of([&] { check_image_path(file("noextension")); }),
                       "noextension: has no extension"));
  // OpenImageIO has an SGI writer, but it cannot encode into memory, where writes are checked.
  EXPECT_TRUE(contains(message_of([&] { check_image_path(file("out.sgi")); }),
                       "out.sgi: tridiff cannot write the 'sgi' format"));
  EXPECT_NO_THROW(check_image_path(file("out.exr")));
  EXPECT_NO_THROW(check_image_path(file("out.png")));
  EXPECT_TRUE(listing().empty());
}

TEST_F(ImageIo, WriteIntoMissingFolderLeavesNothing) {
  const std::string path = file("missing/sub/out.png");
  const std::string message = message_of([&] { write_image(path, Image(2, 2, 3)); });
  EXPECT_TRUE(contains(message, "out.png: the folder"));
  EXPECT_TRUE(contains(message, "does not exist"));
  EXPECT_FALSE(fs::exists(folder_ / "missing"));
  EXPECT_TRUE(listing().empty());
}

TEST_F(ImageIo, FailedWriteKeepsTheOldFile) {
  const std::string target = file("keep.png");
  write_image(target, random_image(8, 8, 3, 0.f, 1.f, 7));
  const std::string before = bytes_of(target);
  ASSERT_FALSE(before.empty());

  // PNG holds at most 4 channels: the writer fails after creating its (temporary) file.
  const std::string message =
      message_of([&] { write_image(target, random_image(8, 8, 5, 0.f, 1.f, 8)); });
  EXPECT_TRUE(contains(message, "keep.png: cannot encode"));
  EXPECT_EQ(bytes_of(target), before);
  EXPECT_EQ(listing(), (std::set<std::string>{"keep.png"}));

  // HDR holds RGB, and alpha it leaves out: five channels are refused.
  write_image(file("keep.hdr"), random_image(4, 4, 3, 0.f, 1.f, 9));
  const std::string hdr = bytes_of(file("keep.hdr"));
  EXPECT_THROW(write_image(file("keep.hdr"), Image(4, 4, 5)), ImageIoError);
  EXPECT_EQ(bytes_of(file("keep.hdr")), hdr);
  EXPECT_EQ(listing(), (std::set<std::string>{"keep.png", "keep.hdr"}));
}

TEST_F(ImageIo, WritingOverAFolderFails) {
  fs::create_directory(folder_ / "taken.png");
  const std::string message = message_of([&] { write_image(file("taken.png"), Image(2, 2, 3)); });
  EXPECT_TRUE(contains(message, "taken.png: is a folder"));
  EXPECT_TRUE(fs::is_directory(folder_ / "taken.png"));
  EXPECT_EQ(listing(), (std::set<std::string>{"taken.png"}));
}

TEST_F(ImageIo, WriteReplacesAnExistingFileWhole) {
  const std::string target = file("replace.tif");
  write_image(target, make_image(4, 4, 3, [](auto, auto, int) { return 0.f; }));
  write_image(target, make_image(4, 4, 3, [](auto, auto, int) { return 1.f; }));
  const Image read = read_color(target).pixels;
  EXPECT_NEAR(read(3, 3, 2), 1.f, 1e-6f);
  EXPECT_EQ(listing(), (std::set<std::string>{"replace.tif"}));
}

TEST_F(ImageIo, JpegLimitsAreCheckedBeforeWriting) {
  // libjpeg would end the process on this size; it must be an exception instead.
  EXPECT_TRUE(contains(message_of([&] { write_image(file("wide.jpg"), Image(70000, 1, 3)); }),
                       "wide.jpg: JPEG images are at most 65500"));
  EXPECT_THROW(write_image(file("two.jpg"), Image(2, 2, 2)), ImageIoError);
  EXPECT_TRUE(listing().empty());
}

// ---------------------------------------------------------------------------------------------
// Hostile files: sizes declared in the header, damage the reader would let through

TEST_F(ImageIo, DeclaredSizeAboveTheLimitIsRefusedFromTheHeader) {
  // 34 bytes declaring 20000 x 20000 pixels (4.8 GB of floats had they been allocated).
  {
    std::ofstream out(file("huge.ppm"), std::ios::binary);
    out << "P6\n20000 20000\n255\n" << std::string(16, '\x7f');
  }
  const std::string limit = "is 20000 x 20000 = 400000000 pixels, more than the limit of 268435456";
  EXPECT_TRUE(contains(message_of([&] { read_color(file("huge.ppm")); }), "huge.ppm: " + limit));
  EXPECT_TRUE(contains(message_of([&] { read_depth(file("huge.ppm")); }), "huge.ppm: " + limit));

  // The limit is the caller's: a 6 x 5 image against 29 and 30 pixels.
  write_image(file("small.png"), random_image(6, 5, 3, 0.f, 1.f, 4));
  EXPECT_TRUE(contains(message_of([&] { read_color(file("small.png"), {.max_pixels = 29}); }),
                       "small.png: is 6 x 5 = 30 pixels, more than the limit of 29"));
  EXPECT_NO_THROW(read_color(file("small.png"), {.max_pixels = 30}));
  DepthOptions depth;
  depth.max_pixels = 29;
  depth.channel = "R";
  EXPECT_THROW(read_depth(file("small.png"), depth), ImageIoError);
  depth.max_pixels = 30;
  EXPECT_NO_THROW(read_depth(file("small.png"), depth));
}

// The issue asks that a 16K x 16K image pass the default limit.
TEST(ImageIoLimits, DefaultLimitIsA16KSquare) {
  EXPECT_EQ(kDefaultMaxPixels, std::int64_t(16384) * 16384);
}

// OpenEXR allocates a header attribute at its declared size before reading it: 40 bytes
// declaring a 2 GB string are refused before OpenImageIO sees them (found by fuzzing).
TEST_F(ImageIo, ExrHeaderDeclaringMoreThanTheFileHoldsIsRefused) {
  std::string bytes("\x76\x2f\x31\x01\x02\x00\x00\x00", 8);  // magic, version 2, one part
  bytes += std::string("comment\0string\0", 15) + std::string("\xf0\xff\xff\x7f", 4) + "abc";
  std::ofstream(file("bomb.exr"), std::ios::binary) << bytes;
  EXPECT_TRUE(contains(message_of([&] { read_color(file("bomb.exr")); }),
                       "bomb.exr: is damaged: its header's attribute 'comment' declares "
                       "2147483632 bytes, more than the 3 left in the file"));
  // A name past OpenEXR's 31 characters (no long-names flag): OpenEXR would read the rest as
  // the type and size, ASCII as 1.9 GB (found by fuzzing).
  std::string long_name("\x76\x2f\x31\x01\x02\x00\x00\x00", 8);
  long_name += std::string(40, 'n') + std::string(
                                          "\0string\0\x03\x00\x00\x00"
                                          "abc",
                                          15);
  std::ofstream(file("long.exr"), std::ios::binary) << long_name;
  EXPECT_TRUE(contains(message_of([&] { read_color(file("long.exr")); }),
                       "long.exr: is damaged: a header name is longer than 31 characters"));
  // A whole file of ours passes the same check.
  write_image(file("fine.exr"), random_image(5, 4, 3, 0.f, 1.f, 12));
  EXPECT_NO_THROW(read_color(file("fine.exr")));
}

// Colour channels far apart in a file with many channels are read one by one, and right; a
// depth file of many unnamed channels is refused rather than read whole to guess.
TEST_F(ImageIo, ManyChannelsCostNoMemoryInProportion) {
  const int width = 5, height = 3, n = 12;
  std::vector<std::string> names;
  // "N.." sorts between G and R: OpenEXR stores channels by name.
  for (int c = 0; c < n; ++c) names.push_back(std::string("N") += std::to_string(c));
  names[0] = "A";
  names[1] = "B";
  names[2] = "G";
  names[n - 1] = "R";
  std::vector<float> values(std::size_t(width * height * n));
  for (std::size_t i = 0; i < values.size(); ++i) values[i] = float(i % n) / 16.f;
  write_with_oiio(file("wide.exr"), width, height, names, OIIO::TypeDesc::FLOAT,
                  OIIO::TypeDesc::FLOAT, values.data());
  const Image color = read_color(file("wide.exr")).pixels;
  ASSERT_EQ(color.channels(), 4);
  EXPECT_EQ(color(4, 2, 0), float(n - 1) / 16.f);  // R, the last channel
  EXPECT_EQ(color(4, 2, 1), 2.f / 16.f);           // G
  EXPECT_EQ(color(4, 2, 2), 1.f / 16.f);           // B
  EXPECT_EQ(color(4, 2, 3), 0.f);                  // A
  const std::vector<std::string> unnamed = {"c0", "c1", "c2", "c3", "c4"};
  std::vector<float> grey(std::size_t(width * height * 5), 2.f);
  write_with_oiio(file("five.exr"), width, height, unnamed, OIIO::TypeDesc::FLOAT,
                  OIIO::TypeDesc::FLOAT, grey.data());
  EXPECT_TRUE(contains(message_of([&] { read_depth(file("five.exr")); }),
                       "cannot tell which channel holds depth"));
}

// TIFF's reader returns success with the missing strips left black and the failure only in
// its error log (OpenImageIO 2.4): every cut must still be an error naming the file.
TEST_F(ImageIo, TruncatedTiffIsRefusedWhereverItIsCut) {
  write_image(file("whole.tif"), random_image(160, 120, 3, 0.f, 1.f, 11));
  const std::string whole = bytes_of(file("whole.tif"));
  for (const int percent : {10, 30, 50, 70, 90, 99}) {
    std::ofstream(file("cut.tif"), std::ios::binary | std::ios::trunc)
        << whole.substr(0, whole.size() * percent / 100);
    EXPECT_TRUE(contains(message_of([&] { read_color(file("cut.tif")); }), "cut.tif: cannot read"))
        << percent << "%";
  }
}

}  // namespace
}  // namespace tridiff::test
