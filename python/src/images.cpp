// tridiff.blur and tridiff.dof on numpy images (height x width [x channels], float32; float64
// converted in the same pass): one planar copy in, the library's planar image work, one
// interleaved copy out, all with the GIL released.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <optional>
#include <string>

#include "arrays.hpp"
#include "errors.hpp"
#include "tridiff/blur/blur.hpp"
#include "tridiff/dof/lens.hpp"
#include "tridiff/dof/method.hpp"
#include "tridiff/image/image.hpp"
#include "tridiff/threads.hpp"

namespace tridiff::python {

namespace {

// A numpy image: its pixels (byte strides), size, channels, and whether it had a channel axis.
struct ImageArray {
  py::array array;
  std::ptrdiff_t height = 0, width = 0;
  int channels = 1;
  bool channel_axis = false;
  bool is_double = false;
};

ImageArray image_array(py::handle object, const char* name, bool allow_channels) {
  ImageArray image;
  image.array = as_array(object);
  const py::array& a = image.array;
  if (a.dtype().equal(py::dtype::of<double>()))
    image.is_double = true;
  else if (!a.dtype().equal(py::dtype::of<float>()))
    raise_value_error(name, "has dtype " + dtype_name(a) + ", expected float32 (or float64)");
  if (a.ndim() != 2 && !(allow_channels && a.ndim() == 3))
    raise_value_error(name, "has shape " + shape_text(shape_of(a)) + ", expected height x width" +
                                (allow_channels ? " [x channels]" : ""));
  image.height = a.shape(0);
  image.width = a.shape(1);
  image.channel_axis = a.ndim() == 3;
  image.channels = image.channel_axis ? static_cast<int>(a.shape(2)) : 1;
  if (image.channel_axis && a.shape(2) < 1) raise_value_error(name, "has no channels");
  // Unaligned data (rare: a view into a byte buffer) is copied by numpy first.
  if (!(a.flags() & py::detail::npy_api::NPY_ARRAY_ALIGNED_))
    image.array = py::module_::import("numpy").attr("ascontiguousarray")(a);
  return image;
}

bool empty(const ImageArray& image) {
  return image.height == 0 || image.width == 0 || image.channels == 0;
}

// The planar copy of `image`, rows shared among threads (called without the GIL).
template <class S>
void to_planar(const ImageArray& image, Image& planar, int threads) {
  const auto* base = static_cast<const char*>(image.array.data());
  const auto& a = image.array;
  const std::ptrdiff_t sy = a.strides(0), sx = a.strides(1);
  const std::ptrdiff_t sc = image.channel_axis ? a.strides(2) : 0;
#pragma omp parallel for num_threads(resolve_threads(threads)) schedule(static)
  for (std::ptrdiff_t y = 0; y < image.height; ++y)
    for (int c = 0; c < image.channels; ++c) {
      float* target = planar.plane(c).row(y);
      const char* source = base + y * sy + c * sc;
      for (std::ptrdiff_t x = 0; x < image.width; ++x)
        target[x] = static_cast<float>(*reinterpret_cast<const S*>(source + x * sx));
    }
}

Image planar_image(const ImageArray& image, int threads) {
  Image planar(image.width, image.height, image.channels);
  if (image.is_double)
    to_planar<double>(image, planar, threads);
  else
    to_planar<float>(image, planar, threads);
  return planar;
}

// A new float32 array height x width [x channels] for `planar`'s pixels (with the GIL).
py::array new_interleaved(const Image& planar, bool channel_axis) {
  if (channel_axis)
    return py::array_t<float>(
        {planar.height(), planar.width(), static_cast<std::ptrdiff_t>(planar.channels())});
  return py::array_t<float>({planar.height(), planar.width()});
}

// Copies `planar` into `target` from new_interleaved (called without the GIL).
void to_interleaved(const Image& planar, float* target, int threads) {
  const int channels = planar.channels();
  const std::ptrdiff_t width = planar.width();
#pragma omp parallel for num_threads(resolve_threads(threads)) schedule(static)
  for (std::ptrdiff_t y = 0; y < planar.height(); ++y)
    for (int c = 0; c < channels; ++c) {
      const float* source = planar.plane(c).row(y);
      float* row = target + y * width * channels + c;
      for (std::ptrdiff_t x = 0; x < width; ++x) row[x * channels] = source[x];
    }
}

Border border_named(const std::string& name) {
  for (Border border : {Border::replicate, Border::mirror, Border::zero, Border::periodic})
    if (border_name(border) == name) return border;
  raise_value_error("border",
                    "unknown border '" + name + "' (known: replicate, mirror, zero, periodic)");
}

constexpr const char* kBlurDoc = R"(Gaussian blur of an image with one named method of the library.

image: height x width or height x width x channels, float32 (float64 is converted once); the
    result is float32 of the same shape. Each channel is blurred on its own, from one planar
    copy made inside.
sigma: the Gaussian's standard deviation in pixels, within the method's range.
method: a name from blur_methods() (tridiff.blur chooses one for method="auto").
border: "replicate", "mirror", "zero" or "periodic", as the method supports.
threads: 0 for all cores.
Raises ValueError naming the argument at fault. The GIL is released while the image is worked.)";

py::array blur_binding(py::handle image_object, double sigma, const std::string& method_name,
                       const std::string& border, int threads) {
  const ImageArray image = image_array(image_object, "image", true);
  const BlurMethod& method = find_blur_method(method_name);
  BlurOptions options;
  options.sigma = sigma;
  options.border = border_named(border);
  options.threads = threads;
  resolve_threads(threads);
  if (empty(image)) return py::array(py::dtype::of<float>(), shape_of(image.array));
  Image planar_out;
  py::array result;
  {
    py::gil_scoped_release release;
    const Image planar_in = planar_image(image, threads);
    planar_out = Image(image.width, image.height, image.channels);
    blur(planar_out, planar_in, method, options);
  }
  result = new_interleaved(planar_out, image.channel_axis);
  {
    py::gil_scoped_release release;
    to_interleaved(planar_out, static_cast<float*>(result.mutable_data()), threads);
  }
  return result;
}

py::list blur_method_list() {
  py::list methods;
  for (const BlurMethod& method : blur_methods()) {
    py::list borders;
    for (Border border : {Border::replicate, Border::mirror, Border::zero, Border::periodic})
      if (method.borders.contains(border)) borders.append(std::string(border_name(border)));
    py::dict row;
    row["name"] = std::string(method.name);
    row["summary"] = std::string(method.summary);
    row["exact"] = method.exact;
    row["max_error"] = method.max_error;
    row["min_sigma"] = method.min_sigma;
    row["max_sigma"] = method.max_sigma;
    row["borders"] = py::tuple(borders);
    row["cost"] = std::string(method.cost);
    methods.append(row);
  }
  return methods;
}

// The command line's default (dof/cli/tridiff.cpp, kDefaultMethod): closest to the thin-lens
// truth of the built-in scenes among the fast methods (README, Results).
constexpr const char* kDefaultDofMethod = "bokeh";

constexpr const char* kDofDoc =
    R"(Depth of field: `color` as a thin lens focused at `focus` would see it.

color: height x width x channels (or height x width), linear light, float32 (float64 is
    converted once); depth: height x width, the distance in metres of each pixel (finite, > 0).
focus: the focus distance (m); f_number, focal_length (mm), sensor_width (mm; the image width
    maps onto it): the lens; max_coc: the largest circle of confusion, in pixels.
method: a name from dof_methods() ("auto" picks the cheapest whose measured error meets the
    library's PSNR budget); layers: blur the near field as its own layer (None: the method's
    default, on where it has layers); in_focus: |CoC| below this many pixels is sharp.
threads: 0 for all cores.
Returns the image (float32, color's shape), or (image, coc) with return_coc, coc the signed
circle-of-confusion diameter in pixels (height x width; negative in front of the focus).
Raises ValueError naming the argument at fault. The GIL is released while the image is worked.)";

py::object dof_binding(py::handle color_object, py::handle depth_object, float focus,
                       float f_number, float focal_length, float sensor_width, float max_coc,
                       const std::string& method_name, std::optional<bool> layers, float in_focus,
                       int threads, bool return_coc) {
  const ImageArray color = image_array(color_object, "color", true);
  const ImageArray depth = image_array(depth_object, "depth", false);
  if (depth.height != color.height || depth.width != color.width)
    raise_value_error("depth", "is " + shape_text(shape_of(depth.array)) + ", color is " +
                                   shape_text(shape_of(color.array)) + ": the sizes differ");
  if (empty(color)) raise_value_error("color", "is empty");
  const DofMethod& method = find_dof_method(method_name);
  ThinLens lens;
  lens.focus_distance_m = focus;
  lens.f_number = f_number;
  lens.focal_length_mm = focal_length;
  lens.sensor_width_mm = sensor_width;
  lens.max_coc_px = max_coc;
  validate(lens);
  DofOptions options;
  options.threads = threads;
  options.layers = layers.value_or(method.honours_layers);
  options.in_focus_coc_px = in_focus;
  resolve_threads(threads);
  Image result, coc;
  try {
    py::gil_scoped_release release;
    const Image planar_color = planar_image(color, threads);
    const Image planar_depth = planar_image(depth, threads);
    coc = Image(color.width, color.height, 1);
    coc_thin_lens(coc.plane(0), planar_depth.plane(0), lens, threads);
    depth_of_field(result, planar_color, coc.plane(0), method, options);
  } catch (const InvalidArgument& error) {
    // The CoC is made here from depth: a bad CoC value is a bad depth.
    raise_invalid_argument(error, {{{"coc", "depth"}}, {}});
  }
  py::array image = new_interleaved(result, color.channel_axis);
  py::array coc_array = new_interleaved(coc, false);
  {
    py::gil_scoped_release release;
    to_interleaved(result, static_cast<float*>(image.mutable_data()), threads);
    if (return_coc) to_interleaved(coc, static_cast<float*>(coc_array.mutable_data()), threads);
  }
  if (return_coc) return py::make_tuple(image, coc_array);
  return image;
}

py::list dof_method_list() {
  py::list methods;
  for (const DofMethod& method : dof_methods()) {
    py::dict row;
    row["name"] = std::string(method.name);
    row["summary"] = std::string(method.summary);
    row["blurs_foreground"] = method.blurs_foreground;
    row["honours_layers"] = method.honours_layers;
    row["keeps_sharp"] = method.keeps_sharp;
    row["cost"] = std::string(method.cost);
    methods.append(row);
  }
  return methods;
}

}  // namespace

void bind_images(py::module_& module) {
  module.def("_blur", &blur_binding, py::arg("image"), py::arg("sigma"), py::arg("method"),
             py::arg("border") = "replicate", py::arg("threads") = 0, kBlurDoc);
  module.def("_blur_methods", &blur_method_list,
             "Every registered blur method as a dict: name, summary, exact, max_error (the stated "
             "bound against the exact Gaussian on images in [0, 1]), min_sigma, max_sigma, "
             "borders, cost.");
  module.def("dof", &dof_binding, py::arg("color"), py::arg("depth"), py::kw_only(),
             py::arg("focus") = 3.2f, py::arg("f_number") = 2.8f, py::arg("focal_length") = 50.f,
             py::arg("sensor_width") = 36.f, py::arg("max_coc") = 64.f,
             py::arg("method") = kDefaultDofMethod, py::arg("layers") = py::none(),
             py::arg("in_focus") = 1.f, py::arg("threads") = 0, py::arg("return_coc") = false,
             kDofDoc);
  module.def("_dof_methods", &dof_method_list,
             "Every registered depth-of-field method as a dict: name, summary, blurs_foreground, "
             "honours_layers, keeps_sharp (a sharp pixel no nearer blur covers keeps its value bit "
             "for bit), "
             "cost.");
}

}  // namespace tridiff::python
