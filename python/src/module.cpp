// The `tridiff._tridiff` extension module (re-exported by the `tridiff` package).
#include <pybind11/pybind11.h>

#include "errors.hpp"

namespace tridiff::python {
void bind_solvers(pybind11::module_& module);
void bind_factors(pybind11::module_& module);
void bind_images(pybind11::module_& module);
}  // namespace tridiff::python

PYBIND11_MODULE(_tridiff, module) {
  module.doc() = "tridiff: tridiagonal solvers, Gaussian blurs and depth of field on numpy arrays";
  tridiff::python::register_errors(module);
  tridiff::python::bind_solvers(module);
  tridiff::python::bind_factors(module);
  tridiff::python::bind_images(module);
}
