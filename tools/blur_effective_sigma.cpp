// The effective sigma of every registered blur method (seed 001 §4.1.2): for each sigma asked
// for, the sigma of the exact Gaussian nearest to the method's output over the quality test
// patterns; and the effective sigma of every pyramid level beside seed 001's Tables A.1-A.3.
// Writes JSON for notebooks/blur.ipynb:
//   {"rows": [{"method": ..., "sigma": ..., "effective_sigma": ..., "max_error": ...}, ...],
//    "levels": [{"filter": ..., "levels": L, "effective_sigma": ..., "seed001_sigma": ...}, ...]}
//
//   tridiff_blur_effective_sigma [--out FILE] [--sigmas 2,4,8]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "tridiff/blur/blur.hpp"
#include "tridiff/blur/pyramid.hpp"
#include "tridiff/blur/quality.hpp"

namespace {

using namespace tridiff;

std::vector<double> parse_sigmas(const std::string& text) {
  std::vector<double> sigmas;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    char* end = nullptr;
    const double s = std::strtod(item.c_str(), &end);
    if (end == item.c_str() || *end != '\0' || !(s > 0))
      throw InvalidArgument("--sigmas", "'" + item + "' is not a sigma > 0");
    sigmas.push_back(s);
  }
  return sigmas;
}

// The patterns must be wide enough for the blur: 8 sigma and at least 96 pixels.
std::string row_json(const BlurMethod& method, double sigma) {
  const Border border =
      method.borders.contains(Border::replicate) ? Border::replicate : Border::mirror;
  const std::ptrdiff_t size = std::max<std::ptrdiff_t>(96, static_cast<std::ptrdiff_t>(8 * sigma));
  const std::vector<TestPattern> patterns = quality_test_set(size);
  const PlaneBlur run = plane_blur(method, {sigma, border, 0});
  const double effective = effective_sigma(run, patterns, sigma / 2, sigma * 2, border);
  double max_error = 0;
  for (const TestPattern& p : patterns) {
    Image out(size, size, 1);
    run(out.plane(0), p.image.plane(0));
    const DoublePlane exact = reference_gaussian(p.image.plane(0), sigma, border);
    max_error = std::max(max_error, blur_error(out.plane(0), exact).max_abs);
  }
  char line[256];
  std::snprintf(line, sizeof line,
                "{\"method\": \"%s\", \"sigma\": %g, \"effective_sigma\": %.6g, "
                "\"max_error\": %.4g}",
                std::string(method.name).c_str(), sigma, effective, max_error);
  return line;
}

// Seed 001 appendix A, row "D mean" (levels 1-5), as tests/blur_pyramid_test.cpp asserts them.
struct SeedTable {
  PyramidFilter filter;
  double sigma[5];
};
constexpr SeedTable kSeedTables[] = {
    {PyramidFilter::quasi, {1.5, 3.004808, 6.235577, 12.668269, 25.466346}},  // Table A.1
    {PyramidFilter::box2, {1.139423, 2.24519, 4.51442, 9.34134, 18.71153}},   // Table A.2
    {PyramidFilter::box4, {1.504808, 3.25, 6.533654, 13.408654, 26.947115}},  // Table A.3
};

std::string level_json(const SeedTable& seed, int levels) {
  const double guess = pyramid_sigma(seed.filter, levels);
  const std::ptrdiff_t size = std::max<std::ptrdiff_t>(96, static_cast<std::ptrdiff_t>(8 * guess));
  const std::vector<TestPattern> patterns = quality_test_set(size);
  const PlaneBlur run = [&](Plane out, ConstPlane in) {
    pyramid_blur(out, in, seed.filter, levels);
  };
  const double effective = effective_sigma(run, patterns, 0.8 * guess, 1.25 * guess);
  char line[256];
  std::snprintf(line, sizeof line,
                "{\"filter\": \"%s\", \"levels\": %d, \"effective_sigma\": %.6g, "
                "\"seed001_sigma\": %.6g}",
                std::string(pyramid_filter_name(seed.filter)).c_str(), levels, effective,
                seed.sigma[levels - 1]);
  return line;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    std::string out_path;
    std::vector<double> sigmas = {2, 4, 8};
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      if ((arg == "--out" || arg == "--sigmas") && i + 1 < argc) {
        (arg == "--out" ? out_path = argv[++i] : (sigmas = parse_sigmas(argv[++i]), out_path));
      } else {
        std::cerr << "usage: tridiff_blur_effective_sigma [--out FILE] [--sigmas 2,4,8]\n";
        return 2;
      }
    }
    std::vector<std::string> rows;
    for (const BlurMethod& method : blur_methods())
      for (double sigma : sigmas)
        if (sigma >= method.min_sigma && sigma <= method.max_sigma) {
          rows.push_back(row_json(method, sigma));
          std::cerr << rows.back() << "\n";
        }
    std::vector<std::string> levels;
    for (const SeedTable& seed : kSeedTables)
      for (int l = 1; l <= 5; ++l) {
        levels.push_back(level_json(seed, l));
        std::cerr << levels.back() << "\n";
      }
    auto list = [](const std::vector<std::string>& items) {
      std::string text;
      for (std::size_t i = 0; i < items.size(); ++i)
        text += "  " + items[i] + (i + 1 < items.size() ? ",\n" : "\n");
      return text;
    };
    std::ostringstream json;
    json << "{\"rows\": [\n" << list(rows) << "],\n\"levels\": [\n" << list(levels) << "]}\n";
    if (out_path.empty()) {
      std::cout << json.str();
    } else {
      const std::string temp = out_path + ".tmp";
      std::ofstream(temp) << json.str();
      if (std::rename(temp.c_str(), out_path.c_str()) != 0)
        throw std::runtime_error("cannot write " + out_path);
    }
  } catch (const std::exception& error) {
    std::cerr << "tridiff_blur_effective_sigma: " << error.what() << "\n";
    return 1;
  }
  return 0;
}
