// What every solver binding does with its numpy arrays: check dtypes and shapes, bring the
// arrays into one layout (copying only those that are not in it), and run the library over
// the plan's calls with the GIL released, its exceptions raised in the caller's terms.
#pragma once

#include <pybind11/complex.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <complex>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "batch.hpp"
#include "errors.hpp"

namespace tridiff::python {

// The shape of the arrays of a call, their common element strides, and the equations' axis.
struct Geometry {
  std::vector<std::ptrdiff_t> shape, strides;
  int axis = 0;
};

struct Input {
  const char* name;  // the Python argument
  py::array array;
  py::dtype dtype;  // what it must be
};

// Every array of one call, in one layout: `result` (the caller's `out`, or a new array) and
// the inputs, each the caller's array if its strides are `geometry.strides`, else one copy in
// those strides.
struct Operands {
  Geometry geometry;
  std::vector<py::array> inputs;
  py::array result = py::reinterpret_steal<py::array>(py::handle());  // null until chosen
  py::object out;  // null, or the caller's `out` when result is a temporary to copy into it

  // The caller's array: result, or `out` with result copied into it.
  py::array finish() const;
};

// `axis` in [0, ndim), numpy's negative axes included; ValueError otherwise.
int normalized_axis(int axis, py::ssize_t ndim);

// Checks that every input has its dtype and the shape of the last one (the right-hand side,
// named in the errors), and sets geometry.shape and geometry.axis.
Operands check_inputs(const std::vector<Input>& inputs, int axis);

// Sets result and geometry.strides: the caller's `out` (checked: writable, `dtype`, the shape)
// if it has usable strides and, when `strides` is given, exactly those; otherwise a new array
// in `strides`, or dense in the memory order of `like`, copied into `out` by finish().
void choose_result(Operands& ops, const py::object& out, const py::dtype& dtype,
                   const py::array& like, const std::vector<std::ptrdiff_t>* strides = nullptr);

// Appends each input to ops.inputs, copied into geometry.strides where its own differ.
void bring_inputs(Operands& ops, const std::vector<Input>& inputs);

// check_inputs, choose_result (a new result like the last input), bring_inputs.
Operands gather_operands(const std::vector<Input>& inputs, const py::object& out,
                         const py::dtype& dtype, int axis);

// Whether `dtype` is one the solvers take: float32, float64, complex64, complex128.
inline bool is_solver_dtype(const py::dtype& dtype) {
  return dtype.equal(py::dtype::of<float>()) || dtype.equal(py::dtype::of<double>()) ||
         dtype.equal(py::dtype::of<std::complex<float>>()) ||
         dtype.equal(py::dtype::of<std::complex<double>>());
}

// Calls body.template operator()<T>() for the scalar type T of `dtype`, the dtype of the
// argument `name`.
template <class Body>
py::object dispatch_scalar(const py::dtype& dtype, const char* name, Body&& body) {
  if (dtype.equal(py::dtype::of<double>())) return body.template operator()<double>();
  if (dtype.equal(py::dtype::of<float>())) return body.template operator()<float>();
  if (dtype.equal(py::dtype::of<std::complex<double>>()))
    return body.template operator()<std::complex<double>>();
  if (dtype.equal(py::dtype::of<std::complex<float>>()))
    return body.template operator()<std::complex<float>>();
  raise_value_error(name, "has dtype " + std::string(py::str(py::handle(dtype))) +
                              "; tridiff solves float32, float64, complex64 and complex128 "
                              "(convert with " +
                              name + ".astype(numpy.float64))");
}

template <class T>
const T* data_of(const py::array& array) {
  return static_cast<const T*>(array.data());
}

// A new C-ordered array of the batch shape (every axis but the equations').
template <class T>
py::array_t<T> new_batch_array(const Geometry& geometry) {
  std::vector<py::ssize_t> batch;
  for (std::size_t k = 0; k < geometry.shape.size(); ++k)
    if (static_cast<int>(k) != geometry.axis) batch.push_back(geometry.shape[k]);
  return py::array_t<T>(batch);
}

// The element of a new_batch_array for the system whose first equation is at element
// `offset` of the arrays.
std::ptrdiff_t batch_position(std::ptrdiff_t offset, const Geometry& geometry);

// Runs body(k) for every call k of `plan` with the GIL released, stopping at the first
// exception. An InvalidArgument or NumericalError comes back as the Python exception in the
// caller's terms: the arguments renamed by `names`, the system given by its index in the
// batch axes.
void run_calls(const BatchPlan& plan, const Geometry& geometry, const ErrorContext& names,
               const std::function<void(std::ptrdiff_t)>& body);

}  // namespace tridiff::python
