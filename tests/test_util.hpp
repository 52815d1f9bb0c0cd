// Small helpers shared by the image, diffusion and DOF tests.
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <exception>
#include <functional>
#include <string>

#include "tridiff/image/image.hpp"

namespace tridiff::testing_util {

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

}  // namespace tridiff::testing_util
