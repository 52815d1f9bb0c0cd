// tridiff's exceptions as Python's: InvalidArgument becomes ValueError, NumericalError
// tridiff.LinAlgError (a numpy.linalg.LinAlgError), both naming the argument, the system (as an
// index into the caller's batch axes) and the row.
#pragma once

#include <pybind11/pybind11.h>

#include <cstddef>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "tridiff/solvers/error.hpp"

namespace tridiff::python {

namespace py = pybind11;

// Registers tridiff.LinAlgError in `module` and the translation of tridiff's exceptions that
// escape a binding without more context (the image functions: no batch to map).
void register_errors(py::module_& module);

// What the binding knows about a failed call that the library does not: the Python names of
// the arguments, and where the library's system number lies in the caller's array.
struct ErrorContext {
  std::vector<std::pair<std::string, std::string>> renames;  // library name -> Python name
  // The caller's index (one entry per batch axis) of the library's system `system`; empty for
  // a call on one system.
  std::function<std::vector<std::ptrdiff_t>(std::ptrdiff_t system)> system_index;
};

// Raises the Python exception for `error` (which must be a tridiff::InvalidArgument or
// tridiff::NumericalError) in the caller's terms. Never returns.
[[noreturn]] void raise_invalid_argument(const InvalidArgument& error, const ErrorContext& context);
[[noreturn]] void raise_numerical_error(const NumericalError& error, const ErrorContext& context);

// ValueError("tridiff: argument 'name': message"), with .argument set.
[[noreturn]] void raise_value_error(const std::string& argument, const std::string& message);

}  // namespace tridiff::python
