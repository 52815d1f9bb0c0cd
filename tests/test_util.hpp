// Small helpers shared by the image, diffusion and DOF tests.
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <exception>
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <functional>
#include <random>
#include <filesystem>
#include <set>
#include <string>

#include <unistd.h>

#include "tridiff/image/image.hpp"

namespace tridiff::testing_util {

// A fixture whose every test gets a scratch folder of its own, removed afterwards.
class ScratchFolderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
    folder_ = std::filesystem::temp_directory_path() /
              ("tridiff_" + std::string(test->test_suite_name()) + "_" +
               std::to_string(::getpid()) + "_" + test->name());
    std::filesystem::remove_all(folder_);
    std::filesystem::create_directories(folder_);
  }
  void TearDown() override { std::filesystem::remove_all(folder_); }

  std::string file(const std::string& name) const { return (folder_ / name).string(); }

  // The names of the entries of the scratch folder.
  std::set<std::string> listing() const {
    std::set<std::string> names;
    for (const auto& entry : std::filesystem::directory_iterator(folder_))
      names.insert(entry.path().filename().string());
    return names;
  }

  std::filesystem::path folder_;
};

// Passes when `text` contains `part`, printing the whole text otherwise.
inline ::testing::AssertionResult contains(const std::string& text, const std::string& part) {
  if (text.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "'" << text << "' does not contain '" << part << "'";
}

// The InvalidArgument that `action` throws (a test failure, and an empty one, if none).
struct Thrown {
  std::string argument, message;
};
inline Thrown invalid_argument_of(const std::function<void()>& action) {
  try {
    action();
  } catch (const InvalidArgument& error) {
    return {error.argument(), error.what()};
  } catch (const std::exception& error) {
    ADD_FAILURE() << "threw something other than InvalidArgument: " << error.what();
    return {};
  }
  ADD_FAILURE() << "no InvalidArgument thrown";
  return {};
}

// An image whose value at (x, y, c) is value(x, y, c).
inline Image make_image(std::ptrdiff_t width, std::ptrdiff_t height, int channels,
                        const std::function<float(std::ptrdiff_t, std::ptrdiff_t, int)>& value) {
  Image image(width, height, channels);
  for (int c = 0; c < channels; ++c)
    for (std::ptrdiff_t y = 0; y < height; ++y)
      for (std::ptrdiff_t x = 0; x < width; ++x) image(x, y, c) = value(x, y, c);
  return image;
}

// Uniform random values in [low, high), the same for every run with the same seed.
inline Image random_image(std::ptrdiff_t width, std::ptrdiff_t height, int channels, float low,
                          float high, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> uniform(low, high);
  return make_image(width, height, channels, [&](auto, auto, int) { return uniform(rng); });
}
// One channel of uniform values in [0, 1).
inline Image random_image(std::ptrdiff_t width, std::ptrdiff_t height, unsigned seed) {
  return random_image(width, height, 1, 0.f, 1.f, seed);
}

// A one-channel CoC map.
inline Image make_coc(std::ptrdiff_t width, std::ptrdiff_t height,
                      const std::function<float(std::ptrdiff_t, std::ptrdiff_t)>& value) {
  return make_image(width, height, 1, [&](auto x, auto y, int) { return value(x, y); });
}

inline bool same_bits(float a, float b) {
  return std::bit_cast<std::uint32_t>(a) == std::bit_cast<std::uint32_t>(b);
}

// How many values of two images differ in their bits (a failure, and -1, if their shapes do).
inline std::ptrdiff_t differing_bits(const Image& a, const Image& b) {
  EXPECT_EQ(a.width(), b.width());
  EXPECT_EQ(a.height(), b.height());
  EXPECT_EQ(a.channels(), b.channels());
  if (a.width() != b.width() || a.height() != b.height() || a.channels() != b.channels()) return -1;
  std::ptrdiff_t differ = 0;
  for (int c = 0; c < a.channels(); ++c)
    for (std::ptrdiff_t y = 0; y < a.height(); ++y)
      for (std::ptrdiff_t x = 0; x < a.width(); ++x) differ += !same_bits(a(x, y, c), b(x, y, c));
  return differ;
}

// A DOF output against its input, pixel by pixel (every channel bit for bit), split by the CoC
// map: sharp pixels (|c| < sharp_below) and how many of them changed, and how many out-of-focus
// pixels moved (that the blur really happened).
struct FocusChanges {
  std::ptrdiff_t sharp = 0, sharp_changed = 0, blurred_moved = 0;
};
inline FocusChanges focus_changes(const Image& out, const Image& input, const Image& coc,
                                  float sharp_below = 1.f) {
  FocusChanges f;
  for (std::ptrdiff_t y = 0; y < input.height(); ++y)
    for (std::ptrdiff_t x = 0; x < input.width(); ++x) {
      bool same = true;
      for (int c = 0; c < input.channels(); ++c) same &= same_bits(out(x, y, c), input(x, y, c));
      if (std::abs(coc(x, y, 0)) < sharp_below) {
        ++f.sharp;
        f.sharp_changed += !same;
      } else {
        f.blurred_moved += !same;
      }
    }
  return f;
}

// The values of channel c, widened by a relative 1e-5 for float rounding: where the output of a
// method that takes convex combinations of its input must stay.
struct ValueRange {
  float lo = 0, hi = 0;
};
inline ValueRange channel_range(const Image& image, int c) {
  float lo = INFINITY, hi = -INFINITY;
  for (std::ptrdiff_t y = 0; y < image.height(); ++y)
    for (std::ptrdiff_t x = 0; x < image.width(); ++x) {
      lo = std::min(lo, image(x, y, c));
      hi = std::max(hi, image(x, y, c));
    }
  const float slack = 1e-5f * std::max(std::abs(lo), std::abs(hi));
  return {lo - slack, hi + slack};
}

// RMSE and largest |a - b| over every value of two images of one shape, in double.
struct ImageDifference {
  double rmse = 0, max = 0;
};
inline ImageDifference image_difference(const Image& a, const Image& b) {
  ImageDifference d;
  double sum = 0;
  for (int c = 0; c < a.channels(); ++c)
    for (std::ptrdiff_t y = 0; y < a.height(); ++y)
      for (std::ptrdiff_t x = 0; x < a.width(); ++x) {
        const double e = double(a(x, y, c)) - double(b(x, y, c));
        sum += e * e;
        d.max = std::max(d.max, std::abs(e));
      }
  d.rmse = std::sqrt(sum / double(a.channels() * a.width() * a.height()));
  return d;
}

}  // namespace tridiff::testing_util
