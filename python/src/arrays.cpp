// numpy helpers (arrays.hpp).
#include "arrays.hpp"

#include <algorithm>
#include <cstdlib>
#include <numeric>

#include "errors.hpp"

namespace tridiff::python {

py::array as_array(py::handle object) {
  if (py::isinstance<py::array>(object)) return py::reinterpret_borrow<py::array>(object);
  return py::module_::import("numpy").attr("asarray")(object);
}

std::string dtype_name(const py::array& array) { return dtype_text(array.dtype()); }

std::string dtype_text(const py::dtype& dtype) { return py::str(py::handle(dtype)); }

std::vector<std::ptrdiff_t> shape_of(const py::array& array) {
  return {array.shape(), array.shape() + array.ndim()};
}

std::string shape_text(const std::vector<std::ptrdiff_t>& shape) {
  std::string text = "(";
  for (std::size_t k = 0; k < shape.size(); ++k) text += (k ? ", " : "") + std::to_string(shape[k]);
  return text + (shape.size() == 1 ? ",)" : ")");
}

std::vector<std::ptrdiff_t> element_strides(const py::array& array) {
  const auto itemsize = static_cast<std::ptrdiff_t>(array.itemsize());
  if (!(array.flags() & py::detail::npy_api::NPY_ARRAY_ALIGNED_)) return {};
  std::vector<std::ptrdiff_t> strides(array.ndim(), 0);
  for (py::ssize_t k = 0; k < array.ndim(); ++k) {
    if (array.shape(k) <= 1) continue;
    const std::ptrdiff_t bytes = array.strides(k);
    if (bytes <= 0 || bytes % itemsize != 0) return {};
    strides[k] = bytes / itemsize;
  }
  return strides;
}

py::array empty_with_strides(const py::dtype& dtype, const std::vector<std::ptrdiff_t>& shape,
                             const std::vector<std::ptrdiff_t>& strides) {
  if (std::find(shape.begin(), shape.end(), 0) != shape.end()) return py::array(dtype, shape);
  std::ptrdiff_t extent = 1;
  for (std::size_t k = 0; k < shape.size(); ++k) extent += (shape[k] - 1) * strides[k];
  const std::ptrdiff_t itemsize = dtype.itemsize();
  std::vector<std::ptrdiff_t> byte_strides(strides.size());
  for (std::size_t k = 0; k < strides.size(); ++k) byte_strides[k] = strides[k] * itemsize;
  py::array buffer(dtype, {extent}, {itemsize});
  return py::array(dtype, shape, byte_strides, buffer.data(), buffer);
}

std::vector<std::ptrdiff_t> dense_strides_like(const py::array& like) {
  const auto ndim = static_cast<int>(like.ndim());
  std::vector<int> order(ndim);
  std::iota(order.begin(), order.end(), 0);
  // Largest stride first; axes of one element, whose stride means nothing, last.
  std::stable_sort(order.begin(), order.end(), [&](int p, int q) {
    const auto sp = like.shape(p) > 1 ? std::abs(like.strides(p)) : 0;
    const auto sq = like.shape(q) > 1 ? std::abs(like.strides(q)) : 0;
    return sp > sq;
  });
  std::vector<std::ptrdiff_t> strides(ndim);
  std::ptrdiff_t step = 1;
  for (int k = ndim; k-- > 0;) {
    strides[order[k]] = like.shape(order[k]) > 1 ? step : 0;  // as element_strides
    step *= std::max<std::ptrdiff_t>(like.shape(order[k]), 1);
  }
  return strides;
}

void copy_into(const py::array& destination, const py::array& source) {
  py::module_::import("numpy").attr("copyto")(destination, source);
}

void require_writable(const py::array& array, const char* name) {
  if (!array.writeable()) raise_value_error(name, "is read-only");
}

}  // namespace tridiff::python
