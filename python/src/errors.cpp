// The translation of tridiff's exceptions into Python's (errors.hpp).
#include "errors.hpp"

#include <Python.h>

#include <string>
#include <utility>

namespace tridiff::python {

namespace {

// tridiff.LinAlgError, created once by register_errors.
py::handle lin_alg_error;

// What the solvers' messages suggest in C++ terms, as a Python caller writes it.
constexpr std::pair<const char*, const char*> kPythonSpellings[] = {
    {"use Method::Pivoting or Method::Auto", "use method='pivoting' or method='auto'"},
    {"use Factorization::Pivoting or Auto", "use method='pivoting' or method='auto'"},
};

std::string renamed(std::string text, const ErrorContext& context) {
  for (const auto& [from, to] : context.renames)
    if (text == from) return to;
  for (const auto& [from, to] : kPythonSpellings)
    if (const auto at = text.find(from); at != std::string::npos)
      text.replace(at, std::string(from).size(), to);
  // Names quoted inside a message ("overlaps 'sub'") as well.
  for (const auto& [from, to] : context.renames) {
    const std::string quoted = "'" + from + "'";
    for (auto at = text.find(quoted); at != std::string::npos; at = text.find(quoted, at))
      text.replace(at, quoted.size(), "'" + to + "'"), at += to.size() + 2;
  }
  return text;
}

py::object system_tuple(std::ptrdiff_t system, const ErrorContext& context) {
  if (system < 0 || !context.system_index) return py::none();
  std::vector<std::ptrdiff_t> at = context.system_index(system);
  py::tuple result(at.size());
  for (std::size_t k = 0; k < at.size(); ++k) result[k] = at[k];
  return result;
}

// "argument 'd', system (3, 1), row 7": the system omitted when the call has one.
std::string where(const std::string& argument, py::handle system, std::ptrdiff_t row) {
  std::string text = argument.empty() ? "" : "argument '" + argument + "'";
  if (!system.is_none() && py::len(system) > 0) {
    std::string index = py::str(system);
    if (py::len(system) == 1) index = std::to_string(system[py::int_(0)].cast<std::ptrdiff_t>());
    text += (text.empty() ? "system " : ", system ") + index;
  }
  if (row >= 0) text += (text.empty() ? "row " : ", row ") + std::to_string(row);
  return text;
}

// Sets Python's error indicator to type(message) carrying argument, system and row.
void set_error(py::handle type, const std::string& message, const std::string& argument,
               py::object system, std::ptrdiff_t row) {
  py::object error = type(message);
  if (!argument.empty()) error.attr("argument") = argument;
  error.attr("system") = system;
  error.attr("row") = row >= 0 ? py::object(py::int_(row)) : py::none();
  PyErr_SetObject(type.ptr(), error.ptr());
}

void set_invalid_argument(const InvalidArgument& error, const ErrorContext& context) {
  const std::string argument = renamed(error.argument(), context);
  py::object system = system_tuple(error.system(), context);
  set_error(
      PyExc_ValueError,
      "tridiff: " + where(argument, system, error.row()) + ": " + renamed(error.message(), context),
      argument, system, error.row());
}

void set_numerical_error(const NumericalError& error, const ErrorContext& context) {
  // what() is "tridiff: system S, row R: message"; the message alone follows the first ": "
  // after the location, which is absent when the error names neither.
  std::string message = error.what();
  const std::string prefix = "tridiff: ";
  if (message.rfind(prefix, 0) == 0) message.erase(0, prefix.size());
  if (error.system() >= 0 || error.row() >= 0) message.erase(0, message.find(": ") + 2);
  py::object system = system_tuple(error.system(), context);
  const std::string location = where("", system, error.row());
  set_error(lin_alg_error,
            "tridiff: " + (location.empty() ? "" : location + ": ") + renamed(message, context), "",
            system, error.row());
}

}  // namespace

void raise_invalid_argument(const InvalidArgument& error, const ErrorContext& context) {
  set_invalid_argument(error, context);
  throw py::error_already_set();
}

void raise_numerical_error(const NumericalError& error, const ErrorContext& context) {
  set_numerical_error(error, context);
  throw py::error_already_set();
}

void raise_value_error(const std::string& argument, const std::string& message) {
  set_error(PyExc_ValueError, "tridiff: argument '" + argument + "': " + message, argument,
            py::none(), -1);
  throw py::error_already_set();
}

void register_errors(py::module_& module) {
  const py::object base = py::module_::import("numpy.linalg").attr("LinAlgError");
  py::object type = py::reinterpret_steal<py::object>(
      PyErr_NewExceptionWithDoc("tridiff.LinAlgError",
                                "A system tridiff could not solve: singular to working precision, "
                                "an overflow, or unsafe for the method asked for. `system` is "
                                "the index of the system in the batch axes, `row` the row.",
                                base.ptr(), nullptr));
  if (!type) throw py::error_already_set();
  module.attr("LinAlgError") = type;
  lin_alg_error = type.release();  // lives as long as the interpreter
  // The translator reports through Python's error indicator.
  py::register_exception_translator([](std::exception_ptr thrown) {
    try {
      if (thrown) std::rethrow_exception(thrown);
    } catch (const InvalidArgument& error) {
      set_invalid_argument(error, {});
    } catch (const NumericalError& error) {
      set_numerical_error(error, {});
    }
  });
}

}  // namespace tridiff::python
