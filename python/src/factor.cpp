// tridiff.factor, tridiff.factor_diffusion and tridiff.Factors: the LU factors of a batch of
// tridiagonal systems along one axis of numpy arrays, kept for repeated solves with new
// right-hand sides (tridiff/solvers/factor.hpp), as scipy.linalg.lu_factor / lu_solve do for
// dense matrices.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <complex>
#include <cstddef>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "arrays.hpp"
#include "operands.hpp"
#include "tridiff/solvers/factor.hpp"
#include "tridiff/solvers/refine.hpp"

namespace tridiff::python {

namespace {

// The factors of one call of the plan each (the batch axes that do not nest are looped over).
template <class T>
using Parts = std::vector<TridiagonalFactors<T>>;

// What tridiff.Factors holds: the factors, and the geometry of the arrays they were made from.
// A right-hand side in `geometry.strides` is solved where it lies; another is copied into them.
struct Factors {
  Factors(Geometry geometry_, py::dtype dtype_)
      : geometry(std::move(geometry_)), dtype(std::move(dtype_)) {}
  // Moved, never copied: the factors can be large (and their buffers are not copyable).
  Factors(Factors&&) = default;
  Factors& operator=(Factors&&) = default;
  Factors(const Factors&) = delete;
  Factors& operator=(const Factors&) = delete;

  Geometry geometry;
  BatchPlan plan;
  py::dtype dtype;
  std::variant<Parts<float>, Parts<double>, Parts<std::complex<float>>, Parts<std::complex<double>>>
      parts;

  bool empty() const {
    return std::visit([](const auto& p) { return p.empty(); }, parts);
  }
};

const ErrorContext kFactorNames{{{"sub", "a"}, {"diag", "b"}, {"super", "c"}}, {}};
const ErrorContext kSolveNames{{{"rhs", "d"}, {"x", "out"}}, {}};

FactorOptions factor_options(const std::string& method, int threads) {
  FactorOptions options;
  if (method == "auto")
    options.method = Factorization::Auto;
  else if (method == "no-pivoting")
    options.method = Factorization::NoPivoting;
  else if (method == "pivoting")
    options.method = Factorization::Pivoting;
  else
    raise_value_error("method", "'" + method + "' is not one of 'auto', 'no-pivoting', 'pivoting'");
  options.threads = threads;
  resolve_threads(threads);  // refused before any copy
  return options;
}

// scipy's convention (lu_solve, solve_triangular): 0 or "N" A x = d, 1 or "T" A^T x = d,
// 2 or "C" A^H x = d.
Apply apply_named(const py::object& trans) {
  if (py::isinstance<py::str>(trans)) {
    const std::string name = trans.cast<std::string>();
    if (name == "N") return Apply::Matrix;
    if (name == "T") return Apply::Transpose;
    if (name == "C") return Apply::Adjoint;
  } else if (py::isinstance<py::int_>(trans)) {
    const int code = trans.cast<int>();
    if (code == 0) return Apply::Matrix;
    if (code == 1) return Apply::Transpose;
    if (code == 2) return Apply::Adjoint;
  }
  raise_value_error("trans", std::string(py::repr(trans)) +
                                 " is not one of 0 or 'N' (A x = d), 1 or 'T' (A^T x = d), "
                                 "2 or 'C' (A^H x = d)");
}

// Factors of T over `ops` (geometry and inputs set): factor_call(k, offset, layout) gives the
// factors of call k of the plan.
template <class T, class FactorCall>
Factors factor_over(const Operands& ops, const ErrorContext& names, FactorCall&& factor_call) {
  Factors factors(ops.geometry, py::dtype::of<T>());
  factors.parts = Parts<T>{};
  if (ops.inputs.front().size() == 0) return factors;
  factors.plan = plan_batch(ops.geometry.shape, ops.geometry.strides, ops.geometry.axis);
  Parts<T>& parts = std::get<Parts<T>>(factors.parts);
  parts.resize(factors.plan.calls());
  run_calls(factors.plan, ops.geometry, names, [&](std::ptrdiff_t k) {
    parts[k] = factor_call(factors.plan.call_offset(k), factors.plan.layout);
  });
  return factors;
}

// The arrays' layout for the factors: dense, in the memory order of `like`, so that a
// right-hand side made like the coefficients (numpy's default) needs no copy.
Operands operands_for_factors(const std::vector<Input>& inputs, int axis) {
  Operands ops = check_inputs(inputs, axis);
  ops.geometry.strides = dense_strides_like(inputs.back().array);
  bring_inputs(ops, inputs);
  return ops;
}

template <class T>
Factors factor_typed(const py::array& a, const py::array& b, const py::array& c, int axis,
                     const FactorOptions& options) {
  const py::dtype dtype = py::dtype::of<T>();
  const Operands ops =
      operands_for_factors({{"a", a, dtype}, {"c", c, dtype}, {"b", b, dtype}}, axis);
  const T* sub = data_of<T>(ops.inputs[0]);
  const T* super = data_of<T>(ops.inputs[1]);
  const T* diag = data_of<T>(ops.inputs[2]);
  return factor_over<T>(ops, kFactorNames, [&](std::ptrdiff_t o, const BatchLayout& layout) {
    return factor(sub + o, diag + o, super + o, layout, options);
  });
}

template <class T>
Factors factor_diffusion_typed(const py::array& beta, int axis, const FactorOptions& options) {
  const py::dtype real = py::dtype::of<real_t<T>>();
  if (!beta.dtype().equal(real))
    raise_value_error("beta", "has dtype " + dtype_name(beta) + "; factors of dtype " +
                                  dtype_text(py::dtype::of<T>()) + " need beta of dtype " +
                                  dtype_text(real));
  const Operands ops = operands_for_factors({{"beta", beta, real}}, axis);
  const real_t<T>* conductance = data_of<real_t<T>>(ops.inputs[0]);
  return factor_over<T>(ops, {}, [&](std::ptrdiff_t o, const BatchLayout& layout) {
    return tridiff::factor_diffusion<T>(conductance + o, layout, options);
  });
}

py::array solve_with(const Factors& factors, py::handle d_object, const py::object& trans,
                     int threads, const py::object& out) {
  FactoredSolveOptions options;
  options.apply = apply_named(trans);
  options.threads = threads;
  resolve_threads(threads);
  const py::array d = as_array(d_object);
  if (!d.dtype().equal(factors.dtype))
    raise_value_error("d", "has dtype " + dtype_name(d) + "; the factors are " +
                               dtype_text(factors.dtype) + " (factor in d's dtype, or convert d)");
  if (shape_of(d) != factors.geometry.shape)
    raise_value_error("d", "has shape " + shape_text(shape_of(d)) + ", the factors " +
                               shape_text(factors.geometry.shape));
  const std::vector<Input> inputs{{"d", d, factors.dtype}};
  Operands ops = check_inputs(inputs, factors.geometry.axis);
  choose_result(ops, out, factors.dtype, d, &factors.geometry.strides);
  bring_inputs(ops, inputs);
  if (factors.empty()) return ops.finish();
  std::visit(
      [&]<class T>(const Parts<T>& parts) {
        const T* rhs = data_of<T>(ops.inputs[0]);
        T* x = static_cast<T*>(ops.result.mutable_data());
        const BatchPlan& plan = factors.plan;
        run_calls(plan, ops.geometry, kSolveNames, [&](std::ptrdiff_t k) {
          const std::ptrdiff_t o = plan.call_offset(k);
          solve(parts[k], rhs + o, x + o, plan.layout, options);
        });
      },
      factors.parts);
  return ops.finish();
}

// A batch-shaped array of value(parts, k, s) for system s of call k; `for_empty` for every
// system when there are no factors (systems of no equations).
template <class V, class Value>
py::array_t<V> per_system(const Factors& factors, V for_empty, Value&& value) {
  py::array_t<V> result = new_batch_array<V>(factors.geometry);
  V* data = result.mutable_data();
  if (factors.empty()) {
    std::fill_n(data, result.size(), for_empty);
    return result;
  }
  std::visit(
      [&](const auto& parts) {
        const BatchPlan& plan = factors.plan;
        for (std::ptrdiff_t k = 0; k < plan.calls(); ++k)
          for (std::ptrdiff_t s = 0; s < plan.layout.count; ++s)
            data[batch_position(plan.call_offset(k) + s * plan.layout.system_stride,
                                factors.geometry)] = V(value(parts, k, s));
      },
      factors.parts);
  return result;
}

py::array rcond_of(const Factors& factors, int threads) {
  resolve_threads(threads);
  return std::visit(
      [&]<class T>(const Parts<T>& parts) -> py::array {
        using R = real_t<T>;
        // Estimated per call with the GIL released, then placed by system.
        std::vector<std::vector<R>> estimates(parts.size());
        if (!parts.empty())
          run_calls(factors.plan, factors.geometry, {},
                    [&](std::ptrdiff_t k) { estimates[k] = estimate_rcond(parts[k], threads); });
        // A system of no equations has rcond 1, as ?gtcon returns for n = 0.
        return per_system<R>(factors, R(1), [&](const auto&, std::ptrdiff_t k, std::ptrdiff_t s) {
          return estimates[k][s];
        });
      },
      factors.parts);
}

constexpr const char* kFactorDoc =
    R"(LU factors of tridiagonal systems along one axis, for repeated solves.

For every index of the other axes (the batch), factors the matrix of

    a[i] x[i-1] + b[i] x[i] + c[i] x[i+1] = d[i],   i = 0 .. n-1 along `axis`

(a[0] and c[n-1] are not read) and returns a tridiff.Factors: Factors.solve(d) then solves for
any number of right-hand sides in turn, without solve()'s divisions and checks of the matrix
(1.2-1.5x faster on 4096 x 4096 float64: both are bound by reading three n-long arrays per
system). Periodic systems are not factored.

a, b, c: arrays of one shape and one dtype: float32, float64, complex64 or complex128.
method: "auto" (without pivoting for each chunk of diagonally dominant systems, partial
    pivoting as LAPACK's ?gttrf for the others), "no-pivoting" (refuses a system that is not
    diagonally dominant) or "pivoting".
threads: 0 for all cores.

Memory: 3 n values per system without pivoting, 4 n values and n bytes with it. Right-hand
sides laid out as b (dense, in b's memory order) are solved where they lie.

Raises ValueError naming the argument (and system and row for a non-finite value) and
tridiff.LinAlgError for a singular system (an exactly zero pivot with pivoting), a system
"no-pivoting" cannot take, or factors that overflow.)";

constexpr const char* kFactorDiffusionDoc =
    R"(LU factors of the implicit diffusion systems of solve_diffusion (insulated ends):

    -beta[i-1] x[i-1] + (1 + beta[i-1] + beta[i]) x[i] - beta[i] x[i+1] = d[i].

beta (finite, >= 0): float32 or float64. dtype: the factors' (and the right-hand sides')
dtype, beta's by default, or the complex type of the same precision. The matrices are strictly
diagonally dominant: factored without pivoting. Returns a tridiff.Factors.)";

constexpr const char* kSolveDoc = R"(Solves op(A) x = d for every system with these factors.

d: an array of the factors' shape and dtype. One laid out as the coefficients were (dense, in
    their memory order) is read where it lies; another is copied once.
trans: 0 or "N" (A x = d), 1 or "T" (A^T x = d), 2 or "C" (A^H x = d), as scipy's lu_solve.
threads: 0 for all cores.
out: an array of d's shape and dtype to write x into; may be d itself (in place).

Raises ValueError for a bad argument or a non-finite d (naming system and row) and
tridiff.LinAlgError if a solution overflows. The GIL is released while the systems are
solved.)";

}  // namespace

void bind_factors(py::module_& module) {
  py::class_<Factors>(module, "Factors",
                      "LU factors of a batch of tridiagonal systems (from tridiff.factor or "
                      "tridiff.factor_diffusion).")
      .def("solve", &solve_with, py::arg("d"), py::arg("trans") = "N", py::arg("threads") = 0,
           py::arg("out") = py::none(), kSolveDoc)
      .def("rcond", &rcond_of, py::arg("threads") = 0,
           "Estimates of each system's reciprocal condition number 1 / (||A||_1 ||A^-1||_1), "
           "as LAPACK's ?gtcon: an array of the batch shape, in the real dtype of the factors.")
      .def_property_readonly(
          "shape",
          [](const Factors& f) {
            py::tuple shape(f.geometry.shape.size());
            for (std::size_t k = 0; k < f.geometry.shape.size(); ++k)
              shape[k] = py::int_(f.geometry.shape[k]);
            return shape;
          },
          "The coefficients' shape: the shape every right-hand side must have.")
      .def_property_readonly(
          "axis", [](const Factors& f) { return f.geometry.axis; }, "The equations' axis.")
      .def_property_readonly(
          "dtype", [](const Factors& f) { return f.dtype; }, "The factors' dtype.")
      .def_property_readonly(
          "pivoted",
          [](const Factors& f) {
            return per_system<bool>(f, false,
                                    [](const auto& parts, std::ptrdiff_t k, std::ptrdiff_t s) {
                                      return parts[k].pivoted(s);
                                    });
          },
          "Whether each system was factored with partial pivoting (an array of the batch "
          "shape).")
      .def_property_readonly(
          "nbytes",
          [](const Factors& f) {
            std::ptrdiff_t total = 0;
            std::visit(
                [&](const auto& parts) {
                  for (const auto& part : parts) total += part.bytes();
                },
                f.parts);
            return total;
          },
          "Bytes of factor storage.")
      .def("__repr__", [](const Factors& f) {
        return "<tridiff.Factors of shape " + shape_text(f.geometry.shape) + ", axis " +
               std::to_string(f.geometry.axis) + ", " + dtype_text(f.dtype) + ">";
      });
  module.def(
      "factor",
      [](py::handle a, py::handle b, py::handle c, int axis, const std::string& method,
         int threads) {
        const FactorOptions options = factor_options(method, threads);
        const py::array sub = as_array(a), diag = as_array(b), super = as_array(c);
        return dispatch_scalar(diag.dtype(), "b", [&]<class T>() {
          return py::cast(factor_typed<T>(sub, diag, super, axis, options));
        });
      },
      py::arg("a"), py::arg("b"), py::arg("c"), py::arg("axis") = -1, py::arg("method") = "auto",
      py::arg("threads") = 0, kFactorDoc);
  module.def(
      "factor_diffusion",
      [](py::handle beta, int axis, const py::object& dtype, int threads) {
        const FactorOptions options = factor_options("no-pivoting", threads);
        const py::array conductance = as_array(beta);
        const py::dtype type = dtype.is_none() ? conductance.dtype() : py::dtype::from_args(dtype);
        if (!dtype.is_none() && !is_solver_dtype(type))
          raise_value_error(
              "dtype", dtype_text(type) + " is not one of float32, float64, complex64, complex128");
        return dispatch_scalar(type, "beta", [&]<class T>() {
          return py::cast(factor_diffusion_typed<T>(conductance, axis, options));
        });
      },
      py::arg("beta"), py::arg("axis") = -1, py::arg("dtype") = py::none(), py::arg("threads") = 0,
      kFactorDiffusionDoc);
}

}  // namespace tridiff::python
