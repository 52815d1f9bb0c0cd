// tridiff::dof, installed: the thin-lens circle of confusion (seed 000 eq. 3.2) is zero at the
// focus distance, negative in front of it and positive behind it, and a lens with no aperture
// is refused. Exits 0 only if every check holds.
#include <tridiff/dof/lens.hpp>

#include <cstdio>

int main() {
  int failures = 0;
  auto check = [&](bool ok, const char* what) {
    if (!ok) {
      std::printf("failed: %s\n", what);
      ++failures;
    }
  };
  tridiff::ThinLens lens;
  lens.focus_distance_m = 2.f;
  tridiff::validate(lens);
  check(tridiff::coc_thin_lens(2.f, lens, 1920) == 0.f, "no blur at the focus distance");
  check(tridiff::coc_thin_lens(1.f, lens, 1920) < 0.f, "near field negative");
  check(tridiff::coc_thin_lens(8.f, lens, 1920) > 0.f, "far field positive");
  lens.f_number = 0.f;
  try {
    tridiff::validate(lens);
    check(false, "f_number 0 refused");
  } catch (const tridiff::InvalidArgument& e) {
    check(e.argument() == "f_number", "the error names f_number");
  }
  std::printf("%s\n",
              failures == 0 ? "tridiff::dof consumer: ok" : "tridiff::dof consumer: FAILED");
  return failures == 0 ? 0 : 1;
}
