// tridiff::image, installed: an image's rows are padded to whole 64-byte lines, the sRGB curve
// runs over the image in the library, and the image encodes to PNG through OpenImageIO (what
// the static library needs at link time). Exits 0 only if every check holds.
#include <tridiff/image/color.hpp>
#include <tridiff/image/image.hpp>
#include <tridiff/image/io.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

int main() {
  int failures = 0;
  auto check = [&](bool ok, const char* what) {
    if (!ok) {
      std::printf("failed: %s\n", what);
      ++failures;
    }
  };
  tridiff::Image image(5, 3, 3);
  check(image.width() == 5 && image.height() == 3 && image.channels() == 3, "size");
  check(image.pitch() % tridiff::Image::kPitchAlign == 0 && image.pitch() >= 5, "pitch");
  for (int c = 0; c < 3; ++c)
    for (int y = 0; y < 3; ++y)
      for (int x = 0; x < 5; ++x) image(x, y, c) = 0.5f;
  tridiff::srgb_to_linear(image, 1);
  // 0.5 encoded is ((0.5 + 0.055) / 1.055)^2.4 = 0.21404 in linear light.
  check(std::abs(image(4, 2, 2) - 0.21404114f) <= 1e-5f, "srgb_to_linear(image)");

  const std::vector<unsigned char> png = tridiff::encode_image("consumer.png", image);
  const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  check(png.size() > 8 && std::equal(signature, signature + 8, png.begin()), "PNG signature");

  std::printf("%s\n",
              failures == 0 ? "tridiff::image consumer: ok" : "tridiff::image consumer: FAILED");
  return failures == 0 ? 0 : 1;
}
