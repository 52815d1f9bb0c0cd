// The one image type of tridiff: planar float channels with a row pitch padded for SIMD, and
// non-owning views of one plane or a rectangle of it. Every blur, diffusion and DOF method
// consumes and produces these.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>
#include <string>
#include <type_traits>

#include "tridiff/solvers/error.hpp"

namespace tridiff {

namespace detail {

// Storage of an Image: a zeroed, 64-byte aligned float array. Large arrays come straight from
// the kernel (already zero) in transparent huge pages where the system allows it: a 4 KiB page
// fault costs microseconds on a virtual machine, and a 4K image plane has 8000 of them.
struct StorageFree {
  std::size_t bytes = 0;  // 0: from aligned_alloc, else the mapped length
  void operator()(float* p) const;
};
using FloatStorage = std::unique_ptr<float, StorageFree>;
FloatStorage allocate_zeroed_floats(std::ptrdiff_t count);

}  // namespace detail

// A rectangle of pixels: columns [x, x + width), rows [y, y + height).
struct Rect {
  std::ptrdiff_t x = 0, y = 0, width = 0, height = 0;

  std::ptrdiff_t area() const { return width * height; }
  bool empty() const { return width <= 0 || height <= 0; }
  bool operator==(const Rect&) const = default;
};

// A non-owning view of one plane (or a rectangle of one): pixel (x, y) is data[y * pitch + x].
// T is float for a writable view and const float for a read-only one.
template <class T>
class PlaneView {
 public:
  PlaneView() = default;
  PlaneView(T* data, std::ptrdiff_t width, std::ptrdiff_t height, std::ptrdiff_t pitch)
      : data_(data), width_(width), height_(height), pitch_(pitch) {}
  // A writable view converts to a read-only one.
  template <class U>
  requires std::is_same_v<T, const U> PlaneView(const PlaneView<U>& other)
      : PlaneView(other.data(), other.width(), other.height(), other.pitch()) {}

  T* data() const { return data_; }
  std::ptrdiff_t width() const { return width_; }
  std::ptrdiff_t height() const { return height_; }
  std::ptrdiff_t pitch() const { return pitch_; }
  Rect bounds() const { return {0, 0, width_, height_}; }

  T* row(std::ptrdiff_t y) const { return data_ + y * pitch_; }
  T& operator()(std::ptrdiff_t x, std::ptrdiff_t y) const { return data_[y * pitch_ + x]; }

  // The view of `area`, which must lie inside this view.
  PlaneView sub(const Rect& area) const {
    if (area.x < 0 || area.y < 0 || area.width < 0 || area.height < 0 ||
        area.x + area.width > width_ || area.y + area.height > height_)
      throw InvalidArgument("area", "rectangle lies outside the plane");
    return {data_ + area.y * pitch_ + area.x, area.width, area.height, pitch_};
  }

 private:
  T* data_ = nullptr;
  std::ptrdiff_t width_ = 0, height_ = 0, pitch_ = 0;
};

using Plane = PlaneView<float>;
using ConstPlane = PlaneView<const float>;

// An owning planar float image. Each row is padded to an odd number of kPitchAlign floats (64
// bytes, one AVX-512 register; see pitch_for) and every plane starts on a 64-byte boundary; padding is zero.
class Image {
 public:
  static constexpr std::ptrdiff_t kPitchAlign = 16;

  Image() = default;
  Image(std::ptrdiff_t width, std::ptrdiff_t height, int channels) {
    reset(width, height, channels);
  }

  Image(Image&&) noexcept = default;
  Image& operator=(Image&&) noexcept = default;
  Image(const Image& other) { *this = other; }
  Image& operator=(const Image& other) {
    if (this == &other) return *this;
    reset(other.width_, other.height_, other.channels_);
    if (size()) std::memcpy(storage_.get(), other.storage_.get(), size() * sizeof(float));
    return *this;
  }

  // Row pitch for `width` floats: whole 64-byte lines, and an odd number of them when there is
  // more than one, so that a walk down a column visits every cache set. With an even count
  // the rows fall into a few sets (a 2048-float pitch puts every row in one set of L1), and
  // the column passes of the solvers and filters, which read 32-64 rows side by side, miss.
  static std::ptrdiff_t pitch_for(std::ptrdiff_t width) {
    const std::ptrdiff_t lines = (width + kPitchAlign - 1) / kPitchAlign;
    return (lines > 1 && lines % 2 == 0 ? lines + 1 : lines) * kPitchAlign;
  }

  // Reallocates as width x height x channels, every value zero.
  void reset(std::ptrdiff_t width, std::ptrdiff_t height, int channels) {
    if (width < 1 || height < 1)
      throw InvalidArgument("size", "image must be at least 1 x 1, got " + std::to_string(width) +
                                        " x " + std::to_string(height));
    if (channels < 1) throw InvalidArgument("channels", "must be at least 1");
    width_ = width;
    height_ = height;
    channels_ = channels;
    pitch_ = pitch_for(width);
    storage_ = detail::allocate_zeroed_floats(size());
  }

  std::ptrdiff_t width() const { return width_; }
  std::ptrdiff_t height() const { return height_; }
  int channels() const { return channels_; }
  std::ptrdiff_t pitch() const { return pitch_; }
  std::ptrdiff_t plane_stride() const { return pitch_ * height_; }
  Rect bounds() const { return {0, 0, width_, height_}; }
  bool empty() const { return storage_ == nullptr; }

  Plane plane(int channel) {
    check_channel(channel);
    return {storage_.get() + channel * plane_stride(), width_, height_, pitch_};
  }
  ConstPlane plane(int channel) const {
    check_channel(channel);
    return {storage_.get() + channel * plane_stride(), width_, height_, pitch_};
  }
  float* data() { return storage_.get(); }
  const float* data() const { return storage_.get(); }

  float& operator()(std::ptrdiff_t x, std::ptrdiff_t y, int channel) {
    return storage_.get()[channel * plane_stride() + y * pitch_ + x];
  }
  float operator()(std::ptrdiff_t x, std::ptrdiff_t y, int channel) const {
    return storage_.get()[channel * plane_stride() + y * pitch_ + x];
  }

 private:
  std::ptrdiff_t size() const { return plane_stride() * channels_; }
  void check_channel(int channel) const {
    if (channel < 0 || channel >= channels_)
      throw InvalidArgument(
          "channel", std::to_string(channel) + " is not in [0, " + std::to_string(channels_) + ")");
  }

  detail::FloatStorage storage_;
  std::ptrdiff_t width_ = 0, height_ = 0, pitch_ = 0;
  int channels_ = 0;
};

// dst = src, pixel for pixel; the views must have the same size.
inline void copy_plane(Plane dst, ConstPlane src) {
  if (src.width() != dst.width() || src.height() != dst.height())
    throw InvalidArgument("dst", "size differs from src");
  for (std::ptrdiff_t y = 0; y < src.height(); ++y)
    std::memcpy(dst.row(y), src.row(y), src.width() * sizeof(float));
}

// Throws unless `image` is width x height (naming `what` in the message).
inline void require_size(const Image& image, std::ptrdiff_t width, std::ptrdiff_t height,
                         const std::string& what) {
  if (image.width() != width || image.height() != height)
    throw InvalidArgument(what, "is " + std::to_string(image.width()) + " x " +
                                    std::to_string(image.height()) + ", expected " +
                                    std::to_string(width) + " x " + std::to_string(height));
}

}  // namespace tridiff
