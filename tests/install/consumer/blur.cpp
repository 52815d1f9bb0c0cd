// tridiff::blur, installed: the registry finds the FFT method (the one linking FFTW) and the
// recursive Gaussian by name with what they state about themselves, and the border rule maps
// pixels outside a line as documented. Exits 0 only if every check holds.
#include <tridiff/blur/blur.hpp>

#include <cstdio>

int main() {
  int failures = 0;
  auto check = [&](bool ok, const char* what) {
    if (!ok) {
      std::printf("failed: %s\n", what);
      ++failures;
    }
  };
  const tridiff::BlurMethod& fft = tridiff::find_blur_method("fft");
  check(fft.name == "fft" && fft.exact && fft.run != nullptr, "fft is registered as exact");
  check(fft.borders.contains(tridiff::Border::periodic), "fft supports the periodic border");
  const tridiff::BlurMethod& iir = tridiff::find_blur_method("iir-deriche");
  check(!iir.exact && iir.max_error > 0 && iir.min_sigma <= iir.max_sigma,
        "iir-deriche states an error bound and a sigma range");
  check(tridiff::blur_methods().size() >= 10, "every method registered");
  try {
    tridiff::find_blur_method("no-such-method");
    check(false, "an unknown name is refused");
  } catch (const tridiff::InvalidArgument&) {
  }
  // Mirror: d c b a | a b c d; periodic: the line repeats.
  check(tridiff::border_index(-1, 5, tridiff::Border::mirror) == 0, "mirror border");
  check(tridiff::border_index(6, 5, tridiff::Border::periodic) == 1, "periodic border");
  check(tridiff::border_index(-3, 5, tridiff::Border::zero) == -1, "zero border");
  std::printf("%s\n",
              failures == 0 ? "tridiff::blur consumer: ok" : "tridiff::blur consumer: FAILED");
  return failures == 0 ? 0 : 1;
}
