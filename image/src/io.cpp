// Image files through OpenImageIO: colour read into linear light, depth read as distance, and
// writes that leave either the whole new file or the old one (temporary file + rename).
#include "tridiff/image/io.hpp"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/half.h>
#include <OpenImageIO/imageio.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <system_error>
#include <type_traits>
#include <utility>

#include "tridiff/image/color.hpp"
#include "tridiff/image/output_files.hpp"
#include "tridiff/threads.hpp"

namespace tridiff {
namespace {

namespace fs = std::filesystem;

[[noreturn]] void fail(const std::string& path, const std::string& message) {
  throw ImageIoError("tridiff: " + path + ": " + message);
}

std::string lowercase(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

std::string join(const std::vector<std::string>& names) {
  std::string joined;
  for (const std::string& name : names) joined += (joined.empty() ? "" : ", ") + name;
  return joined;
}

std::string quote(const std::string& text) { return "'" + text + "'"; }

// The lowercase extension without its dot ("png"), empty when there is none.
std::string extension_of(const std::string& path) {
  const std::string extension = fs::path(path).extension().string();
  return extension.empty() ? extension : lowercase(extension.substr(1));
}

// OpenImageIO keeps errors both on the object and per thread; reading (and so clearing) both
// keeps a stale message from showing up in a later, unrelated error.
// On one line: a plugin's message may hold several, one per layer of the library.
std::string oiio_error(const std::string& object_error = {}) {
  const std::string global = OIIO::geterror();
  std::string text = object_error.empty() ? global : object_error;
  if (text.empty()) return "no reason given";
  while (!text.empty() && text.back() == '\n') text.pop_back();
  for (auto at = text.find('\n'); at != std::string::npos; at = text.find('\n', at))
    text.replace(at, 1, "; ");
  return text;
}

// Whether OpenImageIO has a reader registered for the extension of `path`.
bool known_read_extension(const std::string& path) {
  const std::string extension = extension_of(path);
  if (extension.empty()) return false;
  // "extension_list" is "format:ext,ext;format:ext,...".
  std::stringstream formats(OIIO::get_string_attribute("extension_list"));
  std::string format;
  while (std::getline(formats, format, ';')) {
    std::stringstream extensions(format.substr(format.find(':') + 1));
    std::string candidate;
    while (std::getline(extensions, candidate, ','))
      if (candidate == extension) return true;
  }
  return false;
}

std::string first_line(const std::string& text) { return text.substr(0, text.find('\n')); }

// `count` values, or an ImageIoError naming the file instead of a bare std::bad_alloc.
template <class T>
std::vector<T> allocate(const std::string& path, std::size_t count) {
  try {
    return std::vector<T>(count);
  } catch (const std::bad_alloc&) {
    fail(path, "not enough memory for its " + std::to_string(count) + " values (" +
                   std::to_string(count * sizeof(T) >> 20) + " MiB)");
  }
}

// body(), with std::bad_alloc turned into an ImageIoError naming the file.
template <class Body>
auto with_memory_named(const std::string& path, Body&& body) {
  try {
    return body();
  } catch (const std::bad_alloc&) {
    fail(path, "not enough memory to read it");
  }
}

// ---------------------------------------------------------------------------------------------
// Reading

// Reads a NUL-terminated name; false at the end of the file or past `longest` characters.
bool read_name(std::ifstream& in, std::string& name, std::size_t longest) {
  name.clear();
  for (char c; in.get(c);) {
    if (c == '\0') return true;
    if (name.size() == longest) return false;
    name += c;
  }
  return false;
}

// OpenEXR allocates each header attribute at the size the file declares before reading it, so
// a few bytes can ask for gigabytes (found by fuzz_image_read). An attribute larger than the
// rest of the file can only be damage: refused here, reading no more than the header's names
// and sizes. Files that are not OpenEXR, or that end inside the header, are left to the reader.
void check_exr_header(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char start[8];
  if (!in.read(reinterpret_cast<char*>(start), sizeof start)) return;
  if (start[0] != 0x76 || start[1] != 0x2f || start[2] != 0x31 || start[3] != 0x01) return;
  const bool multipart = (start[5] & 0x10) != 0;  // bit 12 of the version field
  // Names are at most 31 characters unless bit 10 allows 255. OpenEXR reads no further, so a
  // longer name would make it take the rest as the type and size (found by fuzz_image_read:
  // ASCII read as a 1.9 GB size): damage, refused.
  const std::size_t longest = (start[5] & 0x04) != 0 ? 255 : 31;
  in.seekg(0, std::ios::end);
  const std::int64_t size = in.tellg();
  in.seekg(sizeof start);
  std::string name, type;
  for (int header = 0;; ++header) {
    for (int attribute = 0;; ++attribute) {
      if (!read_name(in, name, longest)) {
        if (in)
          fail(path, "is damaged: a header name is longer than " + std::to_string(longest) +
                         " characters");
        return;
      }
      if (name.empty()) {
        // An empty header ends the list of a multi-part file; one header is all of the other.
        if (!multipart || attribute == 0) return;
        break;
      }
      unsigned char length_bytes[4];
      if (!read_name(in, type, longest) || !in.read(reinterpret_cast<char*>(length_bytes), 4))
        return;
      const std::int64_t length =
          std::int32_t(std::uint32_t(length_bytes[0]) | std::uint32_t(length_bytes[1]) << 8 |
                       std::uint32_t(length_bytes[2]) << 16 | std::uint32_t(length_bytes[3]) << 24);
      const std::int64_t left = size - std::int64_t(in.tellg());
      if (length < 0 || length > left)
        fail(path, "is damaged: its header's attribute " + quote(name) + " declares " +
                       std::to_string(length) + " bytes, more than the " + std::to_string(left) +
                       " left in the file");
      in.seekg(length, std::ios::cur);
    }
  }
}

std::unique_ptr<OIIO::ImageInput> open_input(const std::string& path, std::int64_t max_pixels) {
  std::error_code error;
  const fs::file_status status = fs::status(path, error);
  if (status.type() == fs::file_type::not_found) fail(path, "file not found");
  if (error) fail(path, "cannot access (" + error.message() + ")");
  if (fs::is_directory(status)) fail(path, "is a folder, not an image file");
  check_exr_header(path);

  // Keep straight (unassociated) alpha as stored: otherwise OpenImageIO multiplies PNG and TIFF
  // colour by alpha on reading, which would also change colour under zero alpha for good.
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto input = OIIO::ImageInput::open(path, &config);
  if (!input) {
    const std::string why = oiio_error();
    if (!known_read_extension(path)) fail(path, "unknown image format (" + why + ")");
    fail(path, "cannot read (" + why + ")");
  }
  const OIIO::ImageSpec& spec = input->spec();
  if (spec.deep) fail(path, "deep images are not supported");
  if (spec.depth > 1) fail(path, "volume images are not supported");
  if (spec.width < 1 || spec.height < 1 || spec.nchannels < 1) fail(path, "has no pixels");
  // From the header, before a byte of pixels is allocated: a few bytes of file can declare
  // gigapixels.
  const std::int64_t pixels = std::int64_t(spec.width) * spec.height;
  if (pixels > max_pixels)
    fail(path, "is " + std::to_string(spec.width) + " x " + std::to_string(spec.height) + " = " +
                   std::to_string(pixels) + " pixels, more than the limit of " +
                   std::to_string(max_pixels) +
                   " (max_pixels; the tridiff command's --max-pixels)");
  return input;
}

// Channels [begin, end) of the first subimage as interleaved floats. Integer data arrives
// scaled to [0, 1]. The data window is read whatever its offset: tridiff has no use for
// OpenEXR's display window.
std::vector<float> read_interleaved(OIIO::ImageInput& input, const std::string& path, int begin,
                                    int end) {
  const OIIO::ImageSpec& spec = input.spec();
  const std::size_t values = static_cast<std::size_t>(spec.width) *
                             static_cast<std::size_t>(spec.height) *
                             static_cast<std::size_t>(end - begin);
  std::vector<float> pixels = allocate<float>(path, values);
  if (!input.read_image(0, 0, begin, end, OIIO::TypeDesc::FLOAT, pixels.data()))
    fail(path, "cannot read the pixels (" + oiio_error(input.geterror()) + ")");
  // Some readers (TIFF) report missing strips only here and return success with the pixels
  // they could not read left black.
  if (const std::string damage = input.geterror(); !damage.empty())
    fail(path,
         "cannot read the pixels (the file is damaged or truncated: " + first_line(damage) + ")");
  return pixels;
}

// "pixel (x, y) of channel 'C'", as every error about one value of a file begins.
std::string pixel_of_channel(std::ptrdiff_t x, std::ptrdiff_t y, const std::string& channel) {
  return "pixel (" + std::to_string(x) + ", " + std::to_string(y) + ") of channel " +
         quote(channel);
}

[[noreturn]] void fail_not_finite(const std::string& path, const std::string& channel,
                                  std::ptrdiff_t x, std::ptrdiff_t y, float value) {
  fail(path, pixel_of_channel(x, y, channel) + " is " + (std::isnan(value) ? "NaN" : "infinite") +
                 "; colour must be finite");
}

// Where the first NaN or infinity of `plane` is, by rows, if it has one.
std::optional<std::pair<std::ptrdiff_t, std::ptrdiff_t>> first_not_finite(ConstPlane plane) {
  for (std::ptrdiff_t y = 0; y < plane.height(); ++y)
    for (std::ptrdiff_t x = 0; x < plane.width(); ++x)
      if (!std::isfinite(plane(x, y))) return std::pair{x, y};
  return std::nullopt;
}

// dst(x, y) = pixels[(y * width + x) * stride + offset], refusing NaN and infinity: the DOF
// methods skip in-focus tiles unread, so a bad value would otherwise reach the output unseen.
// The check rides on the copy (a sum of 0 * value per row) rather than a pass of its own.
void deinterleave_finite(const std::vector<float>& pixels, int stride, int offset, Plane dst,
                         const std::string& path, const std::string& channel) {
  const float* source = pixels.data() + offset;
  for (std::ptrdiff_t y = 0; y < dst.height(); ++y) {
    float* row = dst.row(y);
    float probe = 0.f;  // zero unless a value of the row is NaN or infinite
    for (std::ptrdiff_t x = 0; x < dst.width(); ++x, source += stride) {
      row[x] = *source;
      probe += 0.f * row[x];
    }
    if (probe == 0.f) continue;
    for (std::ptrdiff_t x = 0; x < dst.width(); ++x)
      if (!std::isfinite(row[x])) fail_not_finite(path, channel, x, y, row[x]);
  }
}

int find_channel(const OIIO::ImageSpec& spec, const std::string& name) {
  const auto& names = spec.channelnames;
  const auto found = std::find(names.begin(), names.end(), name);
  return found == names.end() ? -1 : static_cast<int>(found - names.begin());
}

// Which file channels become R, G, B (and A, -1 when there is none).
struct ColorChannels {
  int rgb[3];
  int alpha;
};

// The alpha channel the file declares, else one named "A", else -1.
int alpha_channel_of(const OIIO::ImageSpec& spec) {
  return spec.alpha_channel >= 0 && spec.alpha_channel < spec.nchannels ? spec.alpha_channel
                                                                        : find_channel(spec, "A");
}

ColorChannels choose_color_channels(const OIIO::ImageSpec& spec) {
  const int n = spec.nchannels;
  const int r = find_channel(spec, "R"), g = find_channel(spec, "G"), b = find_channel(spec, "B");
  int alpha = alpha_channel_of(spec);
  if (r >= 0 && g >= 0 && b >= 0) return {{r, g, b}, alpha};
  if (n >= 3) {
    // Unnamed (or oddly named) channels: the first three are colour, a fourth is alpha.
    if (alpha < 3 && n >= 4) alpha = 3;
    return {{0, 1, 2}, alpha >= 3 ? alpha : -1};
  }
  // One channel is grey; two are grey and alpha, in whichever order the file says.
  if (n == 1) return {{0, 0, 0}, -1};
  const int grey = alpha == 0 ? 1 : 0;
  return {{grey, grey, grey}, 1 - grey};
}

bool names_linear_space(std::string space) {
  space = lowercase(space);
  return space == "raw" || space.starts_with("lin") || space.find("linear") != std::string::npos;
}

// Auto: floating-point data is linear light; integer data is sRGB unless the file says linear
// (a PNG with gAMA 1.0, anything tagged "Linear" / "scene_linear" / "lin_rec709" ...).
ColorEncoding detect_encoding(const OIIO::ImageSpec& spec, int channel) {
  if (spec.channelformat(channel).is_floating_point()) return ColorEncoding::Linear;
  return names_linear_space(spec.get_string_attribute("oiio:ColorSpace")) ? ColorEncoding::Linear
                                                                          : ColorEncoding::Srgb;
}

std::string channel_list(const OIIO::ImageSpec& spec) {
  return "(channels: " + join(spec.channelnames) + ")";
}

// The depth channel that its name (or being alone) decides: the one asked for, else "Z", else
// "depth" (any case), else the only channel; -1 when none does.
int named_depth_channel(const std::string& path, const OIIO::ImageSpec& spec,
                        const std::string& wanted) {
  if (!wanted.empty()) {
    const int channel = find_channel(spec, wanted);
    if (channel < 0) fail(path, "channel " + quote(wanted) + " not found " + channel_list(spec));
    return channel;
  }
  if (const int z = find_channel(spec, "Z"); z >= 0) return z;
  for (int c = 0; c < spec.nchannels; ++c)
    if (lowercase(spec.channelnames[c]) == "depth") return c;
  return spec.nchannels == 1 ? 0 : -1;
}

// Equal, counting NaN as equal to NaN: a NaN in a grey depth map is for the depth check to
// name, not a sign that the channels differ.
bool same_value(float a, float b) { return a == b || (std::isnan(a) && std::isnan(b)); }

// The first colour channel of a grey image stored as several channels (all but alpha equal at
// every pixel, as in a depth map saved as RGB PNG). Any other unnamed choice would be a guess,
// and a guess of R from a colour image makes a plausible-looking but wrong depth: refused.
int grey_channel(const std::string& path, const OIIO::ImageSpec& spec,
                 const std::vector<float>& pixels) {
  const int n = spec.nchannels, alpha = alpha_channel_of(spec);
  std::vector<int> colour;
  for (int c = 0; c < n; ++c)
    if (c != alpha) colour.push_back(c);
  for (std::size_t pixel = 0; pixel < pixels.size(); pixel += static_cast<std::size_t>(n))
    for (const int c : colour)
      if (!same_value(pixels[pixel + c], pixels[pixel + colour[0]]))
        fail(path,
             "cannot tell which channel holds depth: none is named Z or depth, and the "
             "channels are not one grey image " +
                 channel_list(spec) + "; choose one with --depth-channel NAME");
  return colour[0];
}

// The stored values of the depth channel: pixels[i * stride + offset] for pixel i.
struct DepthValues {
  int channel;  // in the file
  std::vector<float> pixels;
  int stride, offset;
};

constexpr int kMaxGreyChannels = 4;

DepthValues read_depth_values(OIIO::ImageInput& input, const std::string& path,
                              const std::string& wanted) {
  const OIIO::ImageSpec& spec = input.spec();
  if (const int channel = named_depth_channel(path, spec, wanted); channel >= 0)
    return {channel, read_interleaved(input, path, channel, channel + 1), 1, 0};
  // Only the pixels can tell whether the file is grey: read every channel, once. A grey image
  // stored as colour has at most four (RGBA); more would cost memory in proportion for a
  // guess (1024 channels of a 512 x 512 file: 1 GiB).
  if (spec.nchannels > kMaxGreyChannels)
    fail(path, "cannot tell which channel holds depth: none is named Z or depth " +
                   channel_list(spec) + "; choose one with --depth-channel NAME");
  std::vector<float> pixels = read_interleaved(input, path, 0, spec.nchannels);
  const int channel = grey_channel(path, spec, pixels);
  return {channel, std::move(pixels), spec.nchannels, channel};
}

std::string format_value(float value) {
  std::ostringstream text;
  text.precision(std::numeric_limits<float>::max_digits10);
  text << value;
  return text.str();
}

void check_depth_options(const DepthOptions& options) {
  if (options.convention != DepthConvention::Normalized) return;
  const float near = options.near_plane, far = options.far_plane;
  if (!(std::isfinite(near) && near >= 0.f))
    throw InvalidArgument(
        "near_plane", "must be finite and >= 0 for normalized depth, got " + format_value(near));
  if (!(std::isfinite(far) && far > near))
    throw InvalidArgument("far_plane", "must be finite and greater than near_plane (" +
                                           format_value(near) + ") for normalized depth, got " +
                                           format_value(far));
}

float to_distance(float value, const DepthOptions& options) {
  switch (options.convention) {
    case DepthConvention::Normalized:
      return options.near_plane + value * (options.far_plane - options.near_plane);
    case DepthConvention::Inverse: return 1.f / value;
    case DepthConvention::Linear: break;
  }
  return value;
}

// "NaN", "infinite", "negative (-2)" or "zero": why a distance is unusable.
std::string describe_bad(float value) {
  if (std::isnan(value)) return "NaN";
  if (std::isinf(value)) return value > 0 ? "infinite" : "infinite (negative)";
  if (value < 0) return "negative (" + format_value(value) + ")";
  return "zero";
}

const char* convention_name(DepthConvention convention) {
  switch (convention) {
    case DepthConvention::Normalized: return "normalized";
    case DepthConvention::Inverse: return "inverse";
    case DepthConvention::Linear: break;
  }
  return "linear";
}

// Outside [0, 1] a normalized value lies before the near plane or beyond the far one: the
// planes were wrong for this file, and the mapping would hide it (or make a negative distance).
bool normalized_in_range(float value) { return value >= 0.f && value <= 1.f; }

bool usable_depth(float value, float distance, DepthConvention convention) {
  if (convention == DepthConvention::Normalized && !normalized_in_range(value)) return false;
  return std::isfinite(distance) && distance > 0.f;
}

[[noreturn]] void fail_depth(const std::string& path, const std::string& channel, std::ptrdiff_t x,
                             std::ptrdiff_t y, float value, float distance,
                             DepthConvention convention) {
  const std::string pixel = pixel_of_channel(x, y, channel) + " is ";
  // Name the stored value when it is itself the problem, else what the conversion made of it.
  if (convention == DepthConvention::Linear || std::isnan(value) || std::isinf(value))
    fail(path, pixel + describe_bad(value) + "; depth must be finite and > 0");
  if (convention == DepthConvention::Normalized && !normalized_in_range(value))
    fail(path, pixel + format_value(value) +
                   "; under the normalized convention a depth value must lie in [0, 1] (0 at "
                   "the near plane, 1 at the far plane)");
  fail(path, pixel + format_value(value) + ", a distance that is " + describe_bad(distance) +
                 " under the " + convention_name(convention) +
                 " convention; depth must be finite and > 0");
}

// ---------------------------------------------------------------------------------------------
// Writing

// How an output file stores its numbers.
struct OutputFormat {
  OIIO::TypeDesc type;
  bool srgb;  // whether colour planes are sRGB-encoded (integer formats) or linear
};

constexpr float kHalfMax = 65504.f;

bool exceeds_half(const Image& image) {
  for (int c = 0; c < image.channels(); ++c) {
    const ConstPlane plane = image.plane(c);
    for (std::ptrdiff_t y = 0; y < plane.height(); ++y)
      for (std::ptrdiff_t x = 0; x < plane.width(); ++x)
        if (std::isfinite(plane(x, y)) && std::abs(plane(x, y)) > kHalfMax) return true;
  }
  return false;
}

// PNG and JPEG 8-bit, TIFF 16-bit (enough for smooth gradients after blurring), OpenEXR half
// unless a value would overflow it, other float formats float, anything else 8-bit.
OutputFormat choose_output_format(const std::string& extension, const Image& image,
                                  const WriteOptions& options) {
  const ColorEncoding encoding = options.encoding;
  if (extension == "exr" || extension == "sxr" || extension == "mxr")
    return {options.float32 || exceeds_half(image) ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::HALF,
            false};
  if (extension == "hdr" || extension == "rgbe" || extension == "pfm")
    return {OIIO::TypeDesc::FLOAT, false};
  const bool srgb = encoding != ColorEncoding::Linear;
  if (extension == "tif" || extension == "tiff") return {OIIO::TypeDesc::UINT16, srgb};
  return {OIIO::TypeDesc::UINT8, srgb};
}

bool is_rgbe(const std::string& extension) { return extension == "hdr" || extension == "rgbe"; }

int color_plane_count(int channels) { return channels == 2 ? 1 : std::min(3, channels); }

// Refuses, without touching the disk, a path whose format cannot be written: the extension
// picks OpenImageIO's writer, and it must be able to encode into memory, where its result can
// be checked and written with checked writes (see OutputFiles): some writers ignore a full
// disk, and libjpeg ends the process on a failed write.
void check_path(const std::string& path, const std::string& extension) {
  if (extension.empty())
    fail(path, "has no extension to choose the image format from (.png, .jpg, .tif, .exr ...)");
  const auto output = OIIO::ImageOutput::create(path);
  if (!output) {
    oiio_error();  // clear it: our message says the same
    // OpenImageIO 2.4 reads PFM (its pnm plugin) but has no PFM writer.
    const std::string hint = extension == "pfm" ? "; .exr keeps floating-point values" : "";
    fail(path, "unknown image format '." + extension + "' (OpenImageIO has no writer for it" +
                   hint + ")");
  }
  if (!output->supports("ioproxy"))
    fail(path, "tridiff cannot write the '" + std::string(output->format_name()) +
                   "' format (its writer cannot encode into memory, where tridiff checks a "
                   "write before it replaces a file); use .exr, .png, .tif, .jpg, .hdr ...");
}

void check_output(const std::string& path, const std::string& extension, const Image& image) {
  if (image.empty()) throw InvalidArgument("image", "is empty");
  check_path(path, extension);
  if (extension == "jpg" || extension == "jpeg" || extension == "jpe" || extension == "jfif") {
    // libjpeg ends the whole process on an oversized image instead of returning an error.
    if (image.width() > 65500 || image.height() > 65500)
      fail(path, "JPEG images are at most 65500 pixels wide and high");
    // The JPEG writer would silently make three channels of two, or drop all past three.
    if (image.channels() != 1 && image.channels() != 3 && image.channels() != 4)
      fail(path, "JPEG holds 1 or 3 channels (4: alpha is dropped), not " +
                     std::to_string(image.channels()));
  }
  if (is_rgbe(extension) && image.channels() > 4)
    fail(path, "Radiance HDR holds RGB (grey is expanded, alpha left out), not " +
                   std::to_string(image.channels()) + " channels");
}

// Radiance's writer takes exactly three channels: grey (and grey + alpha) as three equal
// channels, RGB as it is, RGBA without its alpha.
Image as_rgb(const Image& image) {
  Image rgb(image.width(), image.height(), 3);
  const int colour = color_plane_count(image.channels());
  for (int c = 0; c < 3; ++c) copy_plane(rgb.plane(c), image.plane(std::min(c, colour - 1)));
  return rgb;
}

OIIO::ImageSpec output_spec(const Image& image, const OutputFormat& format,
                            const std::string& extension) {
  const int channels = image.channels();
  OIIO::ImageSpec spec(static_cast<int>(image.width()), static_cast<int>(image.height()), channels,
                       format.type);
  // read_color's conventions in reverse: one channel is grey, two are grey and alpha, the
  // fourth is alpha. (A fresh vector: assigning a literal to channelnames[i] trips GCC 12's
  // false -Wrestrict warning.)
  if (channels <= 2)
    spec.channelnames =
        channels == 1 ? std::vector<std::string>{"Y"} : std::vector<std::string>{"Y", "A"};
  spec.alpha_channel = channels == 2 ? 1 : channels >= 4 ? 3 : -1;
  // OpenImageIO 2.4's TIFF writer, encoding into memory, emits a directory without its
  // image size when told "sRGB" (it adds an EXIF block); integer TIFF means sRGB to readers
  // (read_color's Auto among them) anyway.
  if (!(format.srgb && (extension == "tif" || extension == "tiff")))
    spec.attribute("oiio:ColorSpace", format.srgb ? "sRGB" : "Linear");
  // Our alpha is straight: tell the writer not to divide colour by it.
  if (spec.alpha_channel >= 0) spec.attribute("oiio:UnassociatedAlpha", 1);
  return spec;
}

// The planes interleaved as T, each value passed through store(value, is_colour_plane). The
// array is left uninitialised (not a std::vector, which zero-fills it on one thread): the
// threads that write it touch its fresh pages first, each its own rows.
template <class T, class Store>
std::unique_ptr<T[]> interleave(const Image& image, int threads, Store store) {
  static_assert(std::is_trivially_default_constructible_v<T>);
  const int team = resolve_threads(threads);
  const std::ptrdiff_t width = image.width(), height = image.height();
  const int channels = image.channels(), colour = color_plane_count(channels);
  std::unique_ptr<T[]> pixels(new T[static_cast<std::size_t>(width * height * channels)]);
#pragma omp parallel for num_threads(team) schedule(static) if (team > 1)
  for (std::ptrdiff_t y = 0; y < height; ++y) {
    for (int c = 0; c < channels; ++c) {
      const float* row = image.plane(c).row(y);
      T* out = pixels.get() + y * width * channels + c;
      for (std::ptrdiff_t x = 0; x < width; ++x) out[x * channels] = store(row[x], c < colour);
    }
  }
  return pixels;
}

// sRGB-encodes (when asked) and rounds to T's full range; NaN and negatives become 0.
template <class T>
std::unique_ptr<T[]> quantise(const Image& image, bool srgb, int threads) {
  constexpr float kMax = static_cast<float>(std::numeric_limits<T>::max());
  return interleave<T>(image, threads, [srgb](float value, bool colour) {
    if (srgb && colour) value = linear_to_srgb(value);
    if (!(value > 0.f)) return T(0);
    return static_cast<T>(std::min(value, 1.f) * kMax + 0.5f);
  });
}

// Refuses encoded bytes whose header does not read back as the image written: a writer
// encoding into memory is a less travelled path of some formats (see output_spec).
void check_encoded(const std::string& path, const OIIO::ImageSpec& spec,
                   const std::vector<unsigned char>& bytes) {
  OIIO::Filesystem::IOMemReader memory(bytes.data(), bytes.size());
  void* proxy = &memory;
  OIIO::ImageSpec config;
  config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
  const auto input = OIIO::ImageInput::open(path, &config);
  if (!input)
    fail(path, "the encoded file does not read back (" + first_line(oiio_error()) +
                   "); nothing was written");
  if (input->spec().width != spec.width || input->spec().height != spec.height)
    fail(path, "the encoded file reads back as " + std::to_string(input->spec().width) + " x " +
                   std::to_string(input->spec().height) + "; nothing was written");
}

// The file's bytes as the writer for `path`'s format encodes them.
std::vector<unsigned char> encode(const std::string& path, const OIIO::ImageSpec& spec,
                                  OIIO::TypeDesc type, const void* pixels) {
  // Room for the raw pixels up front: the writer appends in small pieces, and growing the
  // vector step by step copies it and touches fresh pages each time (untouched capacity
  // costs nothing).
  std::vector<unsigned char> bytes;
  bytes.reserve(spec.image_bytes() + (std::size_t(1) << 16));
  OIIO::Filesystem::IOVecOutput memory(bytes);
  auto output = OIIO::ImageOutput::create(path);
  if (!output) fail(path, "unknown image format (" + oiio_error() + ")");
  output->set_ioproxy(&memory);
  if (!output->open(path, spec))
    fail(path, "cannot encode (" + oiio_error(output->geterror()) + ")");
  bool written = output->write_image(type, pixels);
  written = output->close() && written;
  if (!written) fail(path, "cannot encode (" + oiio_error(output->geterror()) + ")");
  check_encoded(path, spec, bytes);
  return bytes;
}

ColorImage read_color_image(const std::string& path, const ReadOptions& options) {
  const auto input = open_input(path, options.max_pixels);
  const OIIO::ImageSpec& spec = input->spec();
  const ColorChannels chosen = choose_color_channels(spec);

  // Read only the span of channels we use (an EXR may carry many more).
  int first = std::min({chosen.rgb[0], chosen.rgb[1], chosen.rgb[2]});
  int last = std::max({chosen.rgb[0], chosen.rgb[1], chosen.rgb[2]});
  if (chosen.alpha >= 0) first = std::min(first, chosen.alpha), last = std::max(last, chosen.alpha);
  // A span of other channels between them (an EXR's layers sort between A and R) would cost
  // memory for nothing: beyond four, each channel is read on its own.
  const int stride = last + 1 - first;
  const bool one_read = stride <= 4;
  const std::vector<float> pixels =
      one_read ? read_interleaved(*input, path, first, last + 1) : std::vector<float>{};
  Image image(spec.width, spec.height, chosen.alpha >= 0 ? 4 : 3);
  const auto copy = [&](int channel, int plane) {
    const std::string& name = spec.channelnames[channel];
    if (one_read)
      deinterleave_finite(pixels, stride, channel - first, image.plane(plane), path, name);
    else
      deinterleave_finite(read_interleaved(*input, path, channel, channel + 1), 1, 0,
                          image.plane(plane), path, name);
  };
  for (int c = 0; c < 3; ++c) copy(chosen.rgb[c], c);
  if (chosen.alpha >= 0) copy(chosen.alpha, 3);

  const ColorEncoding held = options.encoding == ColorEncoding::Auto
                                 ? detect_encoding(spec, chosen.rgb[0])
                                 : options.encoding;
  if (held == ColorEncoding::Srgb) {
    srgb_to_linear(image, options.threads);
    // Float data forced through the sRGB curve overflows it above about 1e16.
    if (spec.format.is_floating_point())
      for (int c = 0; c < 3; ++c)
        if (const auto at = first_not_finite(image.plane(c)))
          fail(path, pixel_of_channel(at->first, at->second, spec.channelnames[chosen.rgb[c]]) +
                         " is too large for the sRGB curve (it decodes to infinity)");
  }
  return {std::move(image), held};
}

Image read_depth_image(const std::string& path, const DepthOptions& options) {
  check_depth_options(options);
  const auto input = open_input(path, options.max_pixels);
  const OIIO::ImageSpec& spec = input->spec();
  const DepthValues values = read_depth_values(*input, path, options.channel);

  Image depth(spec.width, spec.height, 1);
  const Plane plane = depth.plane(0);
  const float* value = values.pixels.data() + values.offset;
  for (std::ptrdiff_t y = 0; y < plane.height(); ++y)
    for (std::ptrdiff_t x = 0; x < plane.width(); ++x, value += values.stride) {
      const float distance = to_distance(*value, options);
      if (!usable_depth(*value, distance, options.convention))
        fail_depth(path, spec.channelnames[values.channel], x, y, *value, distance,
                   options.convention);
      plane(x, y) = distance;
    }
  return depth;
}

}  // namespace

// ---------------------------------------------------------------------------------------------

ColorImage read_color(const std::string& path, const ReadOptions& options) {
  resolve_threads(options.threads);  // a bad count is refused before the file is opened
  return with_memory_named(path, [&] { return read_color_image(path, options); });
}

Image read_depth(const std::string& path, const DepthOptions& options) {
  return with_memory_named(path, [&] { return read_depth_image(path, options); });
}
void check_image_path(const std::string& path) { check_path(path, extension_of(path)); }

std::vector<unsigned char> encode_image(const std::string& path, const Image& image,
                                        const WriteOptions& options) {
  resolve_threads(options.threads);
  const std::string extension = extension_of(path);
  check_output(path, extension, image);
  if (is_rgbe(extension) && image.channels() != 3)
    return encode_image(path, as_rgb(image), options);
  const OutputFormat format = choose_output_format(extension, image, options);
  const OIIO::ImageSpec spec = output_spec(image, format, extension);
  if (format.type == OIIO::TypeDesc::UINT8)
    return encode(path, spec, format.type,
                  quantise<std::uint8_t>(image, format.srgb, options.threads).get());
  if (format.type == OIIO::TypeDesc::UINT16)
    return encode(path, spec, format.type,
                  quantise<std::uint16_t>(image, format.srgb, options.threads).get());
  // Float formats take linear values as they are. Half is rounded here, on the threads (the
  // writer's own conversion runs on one).
  if (format.type == OIIO::TypeDesc::HALF) {
    const auto pixels = interleave<Imath::half>(
        image, options.threads, [](float value, bool) { return Imath::half(value); });
    return encode(path, spec, OIIO::TypeDesc::HALF, pixels.get());
  }
  const auto pixels =
      interleave<float>(image, options.threads, [](float value, bool) { return value; });
  return encode(path, spec, OIIO::TypeDesc::FLOAT, pixels.get());
}

void write_image(const std::string& path, const Image& image, const WriteOptions& options) {
  OutputFiles file;
  file.claim("", path);
  file.stage("", encode_image(path, image, options));
  file.commit();
}

std::vector<std::string> channel_names(const std::string& path) {
  return open_input(path, std::numeric_limits<std::int64_t>::max())->spec().channelnames;
}

}  // namespace tridiff
