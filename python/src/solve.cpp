// tridiff.solve and tridiff.solve_diffusion: batches of tridiagonal systems along one axis of
// numpy arrays of any dimension, the other axes the batch (batch.hpp maps them to BatchLayout).
#include <pybind11/complex.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <complex>
#include <cstdint>
#include <exception>
#include <string>
#include <vector>

#include "arrays.hpp"
#include "batch.hpp"
#include "errors.hpp"
#include "tridiff/solvers/solve.hpp"

namespace tridiff::python {

namespace {

struct Input {
  const char* name;  // the Python argument
  py::array array;
  py::dtype dtype;  // what it must be
};

// Every array of one solver call, in one layout: `result` (the caller's `out`, or a new array
// in the memory order of the right-hand side) and the inputs, each the caller's array if its
// strides are result's, else one copy in result's strides.
struct Operands {
  std::vector<py::array> inputs;
  py::array result = py::reinterpret_steal<py::array>(py::handle());  // null until chosen
  py::object out;  // null, or the caller's `out` when result is a temporary to copy into it
  std::vector<std::ptrdiff_t> shape, strides;
  int axis = 0;
};

int normalized_axis(int axis, py::ssize_t ndim) {
  if (axis < -ndim || axis >= ndim)
    raise_value_error("axis", std::to_string(axis) + " is out of range for an array of " +
                                  std::to_string(ndim) + " dimension(s)");
  return axis < 0 ? axis + static_cast<int>(ndim) : axis;
}

// Checks dtypes and shapes (the last input, the right-hand side, gives the shape) and brings
// every array into one layout (see Operands).
Operands gather_operands(std::vector<Input> inputs, const py::object& out, const py::dtype& dtype,
                         int axis) {
  const py::array& rhs = inputs.back().array;
  Operands ops;
  ops.shape = shape_of(rhs);
  if (rhs.ndim() == 0) raise_value_error(inputs.back().name, "is 0-dimensional: no equations");
  ops.axis = normalized_axis(axis, rhs.ndim());
  for (const Input& input : inputs) {
    if (!input.array.dtype().equal(input.dtype))
      raise_value_error(input.name, "has dtype " + dtype_name(input.array) + ", expected " +
                                        dtype_text(input.dtype) + " to go with " +
                                        inputs.back().name + "'s " + dtype_name(rhs));
    if (shape_of(input.array) != ops.shape)
      raise_value_error(input.name, "has shape " + shape_text(shape_of(input.array)) + ", " +
                                        inputs.back().name + " has " + shape_text(ops.shape));
  }
  if (!out.is_none()) {
    if (!py::isinstance<py::array>(out)) raise_value_error("out", "is not a numpy array");
    py::array target = py::reinterpret_borrow<py::array>(out);
    require_writable(target, "out");
    if (!target.dtype().equal(dtype))
      raise_value_error("out",
                        "has dtype " + dtype_name(target) + ", expected " + dtype_text(dtype));
    if (shape_of(target) != ops.shape)
      raise_value_error("out", "has shape " + shape_text(shape_of(target)) + ", expected " +
                                   shape_text(ops.shape));
    ops.strides = element_strides(target);
    if (!ops.strides.empty())
      ops.result = target;
    else
      ops.out = out;  // negative or broadcast strides: solved apart, then copied in
  }
  if (!ops.result) {  // a new array, dense in the right-hand side's memory order
    ops.strides = dense_strides_like(rhs);
    ops.result = empty_with_strides(dtype, ops.shape, ops.strides);
  }
  for (Input& input : inputs) {
    if (element_strides(input.array) == ops.strides) {
      ops.inputs.push_back(input.array);
    } else {
      ops.inputs.push_back(empty_with_strides(input.dtype, ops.shape, ops.strides));
      copy_into(ops.inputs.back(), input.array);
    }
  }
  return ops;
}

template <class T>
const T* data_of(const py::array& array) {
  return static_cast<const T*>(array.data());
}

// The status array of `info=True`: one int64 per system, the batch shape (every axis but the
// equations'), C order.
py::array_t<std::int64_t> new_info(const Operands& ops) {
  std::vector<py::ssize_t> batch;
  for (std::size_t k = 0; k < ops.shape.size(); ++k)
    if (static_cast<int>(k) != ops.axis) batch.push_back(ops.shape[k]);
  py::array_t<std::int64_t> info(batch);
  std::fill_n(info.mutable_data(), info.size(), std::int64_t(0));
  return info;
}

// The element of the C-ordered batch-shaped array for the system whose first equation is at
// element `offset`.
std::ptrdiff_t info_position(std::ptrdiff_t offset, const Operands& ops) {
  const std::vector<std::ptrdiff_t> index = batch_index(offset, ops.shape, ops.strides, ops.axis);
  std::ptrdiff_t position = 0, k = 0;
  for (std::size_t axis = 0; axis < ops.shape.size(); ++axis)
    if (static_cast<int>(axis) != ops.axis) position = position * ops.shape[axis] + index[k++];
  return position;
}

// Runs solver(offset, layout, options) for every call of the plan with the GIL released, and
// returns x, or (x, info) when `info`: then each call's per-system codes (SolveOptions::info)
// are copied into the status array (new_info) and no system's failure raises. Otherwise a
// tridiff exception comes back as a Python one naming the system by its index in the batch
// axes.
template <class Solver>
py::object run_plan(const Operands& ops, const ErrorContext& names, const SolveOptions& options,
                    bool info, Solver&& solver) {
  py::object status = info ? py::object(new_info(ops)) : py::none();
  std::int64_t* codes_out =
      info ? py::reinterpret_borrow<py::array_t<std::int64_t>>(status).mutable_data() : nullptr;
  const auto size = static_cast<std::ptrdiff_t>(ops.result.size());
  if (size > 0) {
    const BatchPlan plan = plan_batch(ops.shape, ops.strides, ops.axis);
    std::exception_ptr failure;
    std::ptrdiff_t failed_call = 0;
    {
      py::gil_scoped_release release;
      std::vector<std::ptrdiff_t> codes(info ? plan.layout.systems() : 0);
      SolveOptions call = options;
      call.info = codes;
      for (std::ptrdiff_t k = 0; k < plan.calls() && !failure; ++k) {
        try {
          solver(plan.call_offset(k), plan.layout, call);
          if (info)
            for (std::ptrdiff_t system = 0; system < plan.layout.systems(); ++system)
              codes_out[info_position(plan.call_offset(k) + system * plan.layout.system_stride,
                                      ops)] = codes[system];
        } catch (...) {
          failure = std::current_exception();
          failed_call = k;
        }
      }
    }
    if (failure) {
      ErrorContext context = names;
      if (ops.shape.size() > 1)
        context.system_index = [&](std::ptrdiff_t system) {
          return batch_index(plan.call_offset(failed_call) + system * plan.layout.system_stride,
                             ops.shape, ops.strides, ops.axis);
        };
      try {
        std::rethrow_exception(failure);
      } catch (const InvalidArgument& error) {
        raise_invalid_argument(error, context);
      } catch (const NumericalError& error) {
        raise_numerical_error(error, context);
      }
    }
  }
  py::array x = ops.result;
  if (ops.out) {
    x = py::reinterpret_borrow<py::array>(ops.out);
    copy_into(x, ops.result);
  }
  if (!info) return x;
  return py::make_tuple(x, status);
}

SolveOptions solve_options(const std::string& method, bool periodic, int threads) {
  SolveOptions options;
  options.method = method_named(method);
  options.periodic = periodic;
  options.threads = threads;
  resolve_threads(threads);  // refused before any copy
  return options;
}

const ErrorContext kGeneralNames{
    {{"sub", "a"}, {"diag", "b"}, {"super", "c"}, {"rhs", "d"}, {"x", "out"}}, {}};
const ErrorContext kDiffusionNames{{{"rhs", "d"}, {"x", "out"}}, {}};

template <class T>
py::object solve_typed(const py::array& a, const py::array& b, const py::array& c,
                       const py::array& d, int axis, const SolveOptions& options,
                       const py::object& out, bool info) {
  const py::dtype dtype = py::dtype::of<T>();
  Operands ops = gather_operands(
      {{"a", a, dtype}, {"b", b, dtype}, {"c", c, dtype}, {"d", d, dtype}}, out, dtype, axis);
  const T* sub = data_of<T>(ops.inputs[0]);
  const T* diag = data_of<T>(ops.inputs[1]);
  const T* super = data_of<T>(ops.inputs[2]);
  const T* rhs = data_of<T>(ops.inputs[3]);
  T* x = static_cast<T*>(ops.result.mutable_data());
  return run_plan(ops, kGeneralNames, options, info,
                  [&](std::ptrdiff_t o, const BatchLayout& layout, const SolveOptions& call) {
                    solve(sub + o, diag + o, super + o, rhs + o, x + o, layout, call);
                  });
}

template <class T>
py::object solve_diffusion_typed(const py::array& beta, const py::array& d, int axis,
                                 const SolveOptions& options, const py::object& out, bool info) {
  using R = real_t<T>;
  const py::dtype dtype = py::dtype::of<T>();
  Operands ops =
      gather_operands({{"beta", beta, py::dtype::of<R>()}, {"d", d, dtype}}, out, dtype, axis);
  const R* conductance = data_of<R>(ops.inputs[0]);
  const T* rhs = data_of<T>(ops.inputs[1]);
  T* x = static_cast<T*>(ops.result.mutable_data());
  return run_plan(ops, kDiffusionNames, options, info,
                  [&](std::ptrdiff_t o, const BatchLayout& layout, const SolveOptions& call) {
                    solve_diffusion(conductance + o, rhs + o, x + o, layout, call);
                  });
}

// Calls body.template operator()<T>() for the scalar type of `d`'s dtype.
template <class Body>
py::object dispatch_scalar(const py::array& d, Body&& body) {
  const py::dtype dtype = d.dtype();
  if (dtype.equal(py::dtype::of<double>())) return body.template operator()<double>();
  if (dtype.equal(py::dtype::of<float>())) return body.template operator()<float>();
  if (dtype.equal(py::dtype::of<std::complex<double>>()))
    return body.template operator()<std::complex<double>>();
  if (dtype.equal(py::dtype::of<std::complex<float>>()))
    return body.template operator()<std::complex<float>>();
  raise_value_error("d", "has dtype " + dtype_name(d) +
                             "; tridiff solves float32, float64, complex64 and complex128 "
                             "(convert with d.astype(numpy.float64))");
}

constexpr const char* kSolveDoc = R"(Solves tridiagonal systems along one axis of numpy arrays.

For every index of the other axes (the batch), solves

    a[i] x[i-1] + b[i] x[i] + c[i] x[i+1] = d[i],   i = 0 .. n-1 along `axis`,

and returns x (a new array in d's memory order, or `out`). a[0] and c[n-1] are not read
unless `periodic`, where they are the corner entries (0, n-1) and (n-1, 0).

a, b, c, d: arrays of one shape and one dtype: float32, float64, complex64 or complex128.
    Strided and Fortran-ordered arrays are used where they lie when a, b, c, d and the result
    share their strides; an array with other strides is copied once.
axis: the axis of the equations (default: the last).
method: "auto" (Thomas, vectorised across systems, for diagonally dominant systems, partial
    pivoting for the others), "thomas", "cr", "pcr", "cr-pcr" or "pivoting" (LAPACK's ?gtsv
    algorithm). The pivot-free methods refuse a matrix that is not diagonally dominant.
periodic: cyclic systems (see above).
threads: 0 for all cores.
out: an array of d's shape and dtype to write x into; may be d itself (in place).
info: if True, returns (x, info) and raises nothing for a system that fails: info is an int64
    array of the batch shape (d's shape without `axis`) holding each system's status, as
    LAPACK's: 0 solved; k > 0 the method broke down at row k - 1 (singular, not diagonally
    dominant for a pivot-free method, or an overflowing solution); -1, -2, -3, -4 a non-finite
    a, b, c, d (-5: beta of solve_diffusion not finite or negative). Every other system is
    solved; x of a failing system is unspecified.

Raises ValueError for a bad argument (naming it, and the system and row for a bad value:
`argument`, `system` (the index in the batch axes) and `row` attributes), and
tridiff.LinAlgError (a numpy.linalg.LinAlgError) for a singular or unsolvable system. The GIL
is released while the systems are solved.)";

constexpr const char* kSolveDiffusionDoc =
    R"(Solves the implicit diffusion systems along one axis (seed 000 eq. 3.10):

    -beta[i-1] x[i-1] + (1 + beta[i-1] + beta[i]) x[i] - beta[i] x[i+1] = d[i],

with beta[-1] = beta[n-1] = 0 (insulated ends) or, when `periodic`, beta[n-1] linking x[n-1]
to x[0]. beta (the conductance of the link from i to i+1, finite and >= 0) has d's shape and
the real dtype of d's (float32 for complex64). The matrix is strictly diagonally dominant, so
every method is safe; only beta and d are read, a third of the traffic of `solve`.
Other arguments, the result and the errors as for `solve`.)";

}  // namespace

void bind_solvers(py::module_& module) {
  module.def(
      "solve",
      [](py::handle a, py::handle b, py::handle c, py::handle d, int axis,
         const std::string& method, bool periodic, int threads, py::object out, bool info) {
        const SolveOptions options = solve_options(method, periodic, threads);
        const py::array rhs = as_array(d);
        const py::array sub = as_array(a), diag = as_array(b), super = as_array(c);
        return dispatch_scalar(rhs, [&]<class T>() {
          return solve_typed<T>(sub, diag, super, rhs, axis, options, out, info);
        });
      },
      py::arg("a"), py::arg("b"), py::arg("c"), py::arg("d"), py::arg("axis") = -1,
      py::arg("method") = "auto", py::arg("periodic") = false, py::arg("threads") = 0,
      py::arg("out") = py::none(), py::arg("info") = false, kSolveDoc);
  module.def(
      "solve_diffusion",
      [](py::handle beta, py::handle d, int axis, const std::string& method, bool periodic,
         int threads, py::object out, bool info) {
        const SolveOptions options = solve_options(method, periodic, threads);
        const py::array rhs = as_array(d);
        const py::array conductance = as_array(beta);
        return dispatch_scalar(rhs, [&]<class T>() {
          return solve_diffusion_typed<T>(conductance, rhs, axis, options, out, info);
        });
      },
      py::arg("beta"), py::arg("d"), py::arg("axis") = -1, py::arg("method") = "auto",
      py::arg("periodic") = false, py::arg("threads") = 0, py::arg("out") = py::none(),
      py::arg("info") = false, kSolveDiffusionDoc);
  py::list methods;
  for (const MethodRow& row : kMethodTable) methods.append(row.name);
  module.attr("solver_methods") = py::tuple(methods);
}

}  // namespace tridiff::python
