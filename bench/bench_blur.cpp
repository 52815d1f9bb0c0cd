// Blur methods: run time against error, with OpenCV's GaussianBlur as the peer and a plain copy
// as the floor, all in this one binary so that the ratios are meaningful.
//   BM_blur_copy/<n>/threads:<t>                      copy of the n x n RGB float image
//   BM_blur_fma_peak/threads:<t>                      the arithmetic ceiling: independent
//                                                      512-bit multiply-adds on t threads
//   BM_blur/<method>/sigma:<s>/<n>/threads:<t>        one registered method, replicate border
//                                                      (mirror for the diffusion methods)
//   BM_blur/opencv/sigma:<s>/<n>/threads:<t>          cv::GaussianBlur, float, kernel
//                                                      2 ceil(3 sigma) + 1, replicate border; on
//                                                      2 threads two row stripes, one per thread
//                                                      (the Debian build runs float on one)
// Counters:
//   copy_ratio         time / the copy's time at the same size and thread count
//   pixels_per_second  pixels of one plane x 3 planes per second
//   max_error, rmse, psnr, ssim   against the exact Gaussian (double, +-6 sigma) on the fixed
//                      1024^2 test image (edges, discs, 1/f texture in R, G, B), whatever n is:
//                      a method's error does not depend on the image size
// A (method, sigma, n) whose first call on a 256^2 image predicts more than kMaxSeconds per call
// at n is skipped with a message (direct convolution at large sigma, explicit diffusion).
#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <functional>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "tridiff/blur/blur.hpp"
#include "tridiff/blur/quality.hpp"
#include "tridiff/blur/reference.hpp"
#include "tridiff/image/copy.hpp"

namespace {

using namespace tridiff;
using benchmark::Counter;

constexpr double kMaxSeconds = 4.0;
constexpr std::ptrdiff_t kErrorSize = 1024;
const double kSigmas[] = {1, 2, 4, 8, 16, 32, 64};
const std::ptrdiff_t kSizes[] = {1024, 4096};

using ImageBlur = std::function<void(const Image& in, Image& out, double sigma, int threads)>;

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The fixed test image: three patterns of the quality harness as R, G and B.
const Image& test_image(std::ptrdiff_t n) {
  static std::map<std::ptrdiff_t, Image> cache;
  if (auto it = cache.find(n); it != cache.end()) return it->second;
  const std::vector<TestPattern> set = quality_test_set(n);
  Image image(n, n, 3);
  const char* names[] = {"edges", "discs", "texture"};
  for (int c = 0; c < 3; ++c)
    for (const TestPattern& p : set)
      if (p.name == names[c]) copy_plane(image.plane(c), p.image.plane(0));
  return cache.emplace(n, std::move(image)).first->second;
}

// Best of 5 copies, cached per (size, threads).
double copy_seconds(std::ptrdiff_t n, int threads) {
  static std::map<std::pair<std::ptrdiff_t, int>, double> cache;
  if (auto it = cache.find({n, threads}); it != cache.end()) return it->second;
  const Image& src = test_image(n);
  Image dst(n, n, 3);
  copy_image(dst, src, threads);  // touch the pages
  double best = 1e30;
  for (int i = 0; i < 5; ++i) {
    const auto start = std::chrono::steady_clock::now();
    copy_image(dst, src, threads);
    best = std::min(best, seconds_since(start));
  }
  return cache[{n, threads}] = best;
}

// OpenCV on one plane; with 2+ threads, one row stripe per thread. Each stripe is a view into
// the whole plane, so OpenCV reads the rows beyond it (not a border): the output is identical.
void opencv_gaussian(const Image& in, Image& out, double sigma, int threads) {
  const int ksize = 2 * static_cast<int>(std::ceil(3 * sigma)) + 1;
  const int h = static_cast<int>(in.height()), w = static_cast<int>(in.width());
  for (int c = 0; c < in.channels(); ++c) {
    const cv::Mat src(h, w, CV_32F, const_cast<float*>(in.plane(c).data()),
                      in.pitch() * sizeof(float));
    cv::Mat dst(h, w, CV_32F, out.plane(c).data(), out.pitch() * sizeof(float));
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int t = 0; t < threads; ++t) {
      const cv::Range rows(h * t / threads, h * (t + 1) / threads);
      cv::Mat stripe_out = dst.rowRange(rows);
      cv::GaussianBlur(src.rowRange(rows), stripe_out, cv::Size(ksize, ksize), sigma, sigma,
                       cv::BORDER_REPLICATE);
    }
  }
}

Border border_for(const BlurMethod& method) {
  return method.borders.contains(Border::replicate) ? Border::replicate : Border::mirror;
}

ImageBlur method_blur(const BlurMethod& method) {
  return [&method](const Image& in, Image& out, double sigma, int threads) {
    blur(out, in, method, {sigma, border_for(method), threads});
  };
}

struct Quality {
  BlurError error;         // worst channel's max error, mean of the others
  double seconds_256 = 0;  // best of two calls on 256^2 (1 thread): the cost guard
};

// The exact Gaussian of the test image, cached per (sigma, border).
const std::vector<DoublePlane>& exact(double sigma, Border border) {
  static std::map<std::pair<double, Border>, std::vector<DoublePlane>> cache;
  auto key = std::pair{sigma, border};
  if (auto it = cache.find(key); it != cache.end()) return it->second;
  std::vector<DoublePlane> planes;
  const Image& in = test_image(kErrorSize);
  for (int c = 0; c < 3; ++c) planes.push_back(reference_gaussian(in.plane(c), sigma, border));
  return cache[key] = std::move(planes);
}

const Quality& quality(const std::string& name, const ImageBlur& run, double sigma, Border border) {
  static std::map<std::pair<std::string, double>, Quality> cache;
  auto key = std::pair{name, sigma};
  if (auto it = cache.find(key); it != cache.end()) return it->second;
  Quality q;
  {
    const Image& big = test_image(kErrorSize);
    Image small(256, 256, 3), out(256, 256, 3);
    for (int c = 0; c < 3; ++c) copy_plane(small.plane(c), big.plane(c).sub({0, 0, 256, 256}));
    q.seconds_256 = INFINITY;
    for (int i = 0; i < 2; ++i) {  // the first call pays for thread start-up and page faults
      const auto start = std::chrono::steady_clock::now();
      run(small, out, sigma, 1);  // one thread: no barrier waits for a busy core
      q.seconds_256 = std::min(q.seconds_256, seconds_since(start));
    }
  }
  if (q.seconds_256 * (kErrorSize / 256.0) * (kErrorSize / 256.0) <= kMaxSeconds) {
    const Image& in = test_image(kErrorSize);
    Image out(kErrorSize, kErrorSize, 3);
    run(in, out, sigma, 2);
    const std::vector<DoublePlane>& ref = exact(sigma, border);
    for (int c = 0; c < 3; ++c) {
      const BlurError e = blur_error(out.plane(c), ref[c]);
      q.error.max_abs = std::max(q.error.max_abs, e.max_abs);
      q.error.rmse += e.rmse / 3;
      q.error.ssim += e.ssim / 3;
    }
    q.error.psnr = q.error.rmse > 0 ? -20 * std::log10(q.error.rmse) : INFINITY;
  } else {
    q.error.max_abs = NAN;
  }
  return cache[key] = q;
}

void run_blur(benchmark::State& state, const std::string& name, ImageBlur run, Border border,
              double sigma, std::ptrdiff_t n, int threads) {
  const Quality& q = quality(name, run, sigma, border);
  const double predicted = q.seconds_256 * (n / 256.0) * (n / 256.0);
  if (predicted > kMaxSeconds || std::isnan(q.error.max_abs)) {
    state.SkipWithError(("skipped: about " + std::to_string(predicted) + " s per call").c_str());
    for (auto _ : state) {
    }
    return;
  }
  const Image& in = test_image(n);
  Image out(n, n, 3);
  run(in, out, sigma, threads);  // touch the pages
  for (auto _ : state) {
    run(in, out, sigma, threads);
    benchmark::ClobberMemory();
  }
  const double pixels = 3.0 * n * n;
  state.counters["pixels_per_second"] = Counter(pixels, Counter::kIsIterationInvariantRate);
  // elapsed / (iterations x copy time): the time per call in copies.
  state.counters["copy_ratio"] =
      Counter(copy_seconds(n, threads), Counter::kIsIterationInvariantRate | Counter::kInvert);
  state.counters["max_error"] = q.error.max_abs;
  state.counters["rmse"] = q.error.rmse;
  state.counters["psnr"] = q.error.psnr;
  state.counters["ssim"] = q.error.ssim;
  state.counters["sigma"] = sigma;
}

void run_copy(benchmark::State& state, std::ptrdiff_t n, int threads) {
  const Image& in = test_image(n);
  Image out(n, n, 3);
  copy_image(out, in, threads);
  for (auto _ : state) {
    copy_image(out, in, threads);
    benchmark::ClobberMemory();
  }
  state.counters["pixels_per_second"] = Counter(3.0 * n * n, Counter::kIsIterationInvariantRate);
  state.counters["bytes_per_second"] =
      Counter(2 * 3.0 * n * n * sizeof(float), Counter::kIsIterationInvariantRate);
}

// The arithmetic floor of a method that needs k vector multiply-adds per 16 pixels is
// k * pixels / 16 / (this rate): the recursive Gaussian's 32 per 16 pixels, for instance. Twelve
// independent chains, more than the multiply-add latency times the issue width needs.
void run_fma_peak(benchmark::State& state, int threads) {
  typedef float Vec __attribute__((vector_size(64)));
  constexpr long kSteps = 1 << 22;
  constexpr int kChains = 12;
  for (auto _ : state) {
#pragma omp parallel num_threads(threads)
    {
      Vec acc[kChains];
      for (int j = 0; j < kChains; ++j) acc[j] = Vec{} + float(j);
      const Vec scale = Vec{} + 0.999999f, add = Vec{} + 1e-7f;
      for (long i = 0; i < kSteps; ++i)
        for (int j = 0; j < kChains; ++j) {
          acc[j] = acc[j] * scale + add;
          asm volatile("" : "+v"(acc[j]));  // keep every multiply-add
        }
      float sum = 0;
      for (int j = 0; j < kChains; ++j) sum += acc[j][0];
      benchmark::DoNotOptimize(sum);
    }
  }
  state.counters["vector_fma_per_second"] =
      Counter(double(kSteps) * kChains * threads, Counter::kIsIterationInvariantRate);
}

std::string sized(const std::string& base, std::ptrdiff_t n, int threads) {
  return base + "/" + std::to_string(n) + "/threads:" + std::to_string(threads);
}

void register_all() {
  for (std::ptrdiff_t n : kSizes)
    for (int threads : {1, 2}) {
      if (n == kSizes[0])
        benchmark::RegisterBenchmark(
            ("BM_blur_fma_peak/threads:" + std::to_string(threads)).c_str(), run_fma_peak, threads)
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime();
      benchmark::RegisterBenchmark(sized("BM_blur_copy", n, threads).c_str(), run_copy, n, threads)
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime();
      for (double sigma : kSigmas) {
        const std::string s = "/sigma:" + std::to_string(static_cast<int>(sigma));
        for (const BlurMethod& m : blur_methods()) {
          if (sigma < m.min_sigma || sigma > m.max_sigma) continue;
          const std::string name(m.name);
          benchmark::RegisterBenchmark(sized("BM_blur/" + name + s, n, threads).c_str(), run_blur,
                                       name, method_blur(m), border_for(m), sigma, n, threads)
              ->Unit(benchmark::kMillisecond)
              ->UseRealTime();
        }
        benchmark::RegisterBenchmark(sized("BM_blur/opencv" + s, n, threads).c_str(), run_blur,
                                     std::string("opencv"), ImageBlur(opencv_gaussian),
                                     Border::replicate, sigma, n, threads)
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime();
      }
    }
}

}  // namespace

int main(int argc, char** argv) {
  cv::setNumThreads(1);  // the stripes are the parallelism; see opencv_gaussian
  register_all();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
