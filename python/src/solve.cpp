// tridiff.solve and tridiff.solve_diffusion: batches of tridiagonal systems along one axis of
// numpy arrays of any dimension, the other axes the batch (batch.hpp maps them to BatchLayout).
#include <pybind11/complex.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <complex>
#include <cstdint>
#include <string>
#include <vector>

#include "arrays.hpp"
#include "operands.hpp"
#include "tridiff/solvers/solve.hpp"

namespace tridiff::python {

namespace {

// Runs solver(offset, layout, options) for every call of the plan and returns x, or (x, info)
// when `info`: then each call's per-system codes (SolveOptions::info) are copied into the
// status array, of the batch shape, and no system's failure raises.
template <class Solver>
py::object run_plan(const Operands& ops, const ErrorContext& names, const SolveOptions& options,
                    bool info, Solver&& solver) {
  py::object status = py::none();
  std::int64_t* codes_out = nullptr;
  if (info) {
    py::array_t<std::int64_t> codes = new_batch_array<std::int64_t>(ops.geometry);
    std::fill_n(codes.mutable_data(), codes.size(), std::int64_t(0));
    codes_out = codes.mutable_data();
    status = codes;
  }
  if (ops.result.size() > 0) {
    const BatchPlan plan = plan_batch(ops.geometry.shape, ops.geometry.strides, ops.geometry.axis);
    std::vector<std::ptrdiff_t> codes(info ? plan.layout.systems() : 0);
    SolveOptions call = options;
    call.info = codes;
    run_calls(plan, ops.geometry, names, [&](std::ptrdiff_t k) {
      const std::ptrdiff_t offset = plan.call_offset(k);
      solver(offset, plan.layout, call);
      for (std::size_t system = 0; system < codes.size(); ++system)
        codes_out[batch_position(offset + std::ptrdiff_t(system) * plan.layout.system_stride,
                                 ops.geometry)] = codes[system];
    });
  }
  const py::array x = ops.finish();
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
        return dispatch_scalar(rhs.dtype(), "d", [&]<class T>() {
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
        return dispatch_scalar(rhs.dtype(), "d", [&]<class T>() {
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
