// numpy helpers the bindings share: argument checks that name the argument, element strides,
// and arrays allocated in another array's layout.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstddef>
#include <string>
#include <vector>

namespace tridiff::python {

namespace py = pybind11;

// `object` as an ndarray (a list or other array-like is converted, as numpy.asarray does).
py::array as_array(py::handle object);

std::string dtype_name(const py::array& array);
std::string dtype_text(const py::dtype& dtype);
std::vector<std::ptrdiff_t> shape_of(const py::array& array);
std::string shape_text(const std::vector<std::ptrdiff_t>& shape);

// The strides in elements if every axis of more than one element has a positive stride that is
// a whole number of elements and the data is aligned; empty otherwise (negative, broadcast or
// unaligned strides: the array needs a copy). Axes of one element get stride 0.
std::vector<std::ptrdiff_t> element_strides(const py::array& array);

// A new array of `dtype` and `shape` whose element strides are `strides` (positive, from
// element_strides): a buffer of the extent they span, viewed with those strides.
py::array empty_with_strides(const py::dtype& dtype, const std::vector<std::ptrdiff_t>& shape,
                             const std::vector<std::ptrdiff_t>& strides);

// Contiguous element strides for `shape` with the axes in the memory order of `like` (numpy's
// order "K": a Fortran-ordered array gives Fortran-ordered strides); 0 for axes of one element,
// as element_strides gives them, so that the two compare equal for a dense array.
std::vector<std::ptrdiff_t> dense_strides_like(const py::array& like);

// numpy.copyto(destination, source).
void copy_into(const py::array& destination, const py::array& source);

// ValueError naming `name` unless `array` is writable.
void require_writable(const py::array& array, const char* name);

}  // namespace tridiff::python
