// The operands of the solver bindings and the loop over a plan's calls (operands.hpp).
#include "operands.hpp"

#include <exception>
#include <string>

#include "arrays.hpp"

namespace tridiff::python {

py::array Operands::finish() const {
  if (!out) return result;
  py::array target = py::reinterpret_borrow<py::array>(out);
  copy_into(target, result);
  return target;
}

int normalized_axis(int axis, py::ssize_t ndim) {
  if (axis < -ndim || axis >= ndim)
    raise_value_error("axis", std::to_string(axis) + " is out of range for an array of " +
                                  std::to_string(ndim) + " dimension(s)");
  return axis < 0 ? axis + static_cast<int>(ndim) : axis;
}

Operands check_inputs(const std::vector<Input>& inputs, int axis) {
  const Input& last = inputs.back();
  Operands ops;
  ops.geometry.shape = shape_of(last.array);
  if (last.array.ndim() == 0) raise_value_error(last.name, "is 0-dimensional: no equations");
  ops.geometry.axis = normalized_axis(axis, last.array.ndim());
  for (const Input& input : inputs) {
    if (!input.array.dtype().equal(input.dtype))
      raise_value_error(input.name, "has dtype " + dtype_name(input.array) + ", expected " +
                                        dtype_text(input.dtype) + " to go with " + last.name +
                                        "'s " + dtype_name(last.array));
    if (shape_of(input.array) != ops.geometry.shape)
      raise_value_error(input.name, "has shape " + shape_text(shape_of(input.array)) + ", " +
                                        last.name + " has " + shape_text(ops.geometry.shape));
  }
  return ops;
}

void choose_result(Operands& ops, const py::object& out, const py::dtype& dtype,
                   const py::array& like, const std::vector<std::ptrdiff_t>* strides) {
  std::vector<std::ptrdiff_t>& chosen = ops.geometry.strides;
  if (!out.is_none()) {
    if (!py::isinstance<py::array>(out)) raise_value_error("out", "is not a numpy array");
    py::array target = py::reinterpret_borrow<py::array>(out);
    require_writable(target, "out");
    if (!target.dtype().equal(dtype))
      raise_value_error("out",
                        "has dtype " + dtype_name(target) + ", expected " + dtype_text(dtype));
    if (shape_of(target) != ops.geometry.shape)
      raise_value_error("out", "has shape " + shape_text(shape_of(target)) + ", expected " +
                                   shape_text(ops.geometry.shape));
    const std::vector<std::ptrdiff_t> own = element_strides(target);
    if (!own.empty() && (!strides || own == *strides)) {
      chosen = own;
      ops.result = target;
      return;
    }
    ops.out = out;  // strides the solvers cannot take, or not the required ones
  }
  chosen = strides ? *strides : dense_strides_like(like);
  ops.result = empty_with_strides(dtype, ops.geometry.shape, chosen);
}

void bring_inputs(Operands& ops, const std::vector<Input>& inputs) {
  for (const Input& input : inputs) {
    if (element_strides(input.array) == ops.geometry.strides) {
      ops.inputs.push_back(input.array);
    } else {
      ops.inputs.push_back(
          empty_with_strides(input.dtype, ops.geometry.shape, ops.geometry.strides));
      copy_into(ops.inputs.back(), input.array);
    }
  }
}

Operands gather_operands(const std::vector<Input>& inputs, const py::object& out,
                         const py::dtype& dtype, int axis) {
  Operands ops = check_inputs(inputs, axis);
  choose_result(ops, out, dtype, inputs.back().array);
  bring_inputs(ops, inputs);
  return ops;
}

std::ptrdiff_t batch_position(std::ptrdiff_t offset, const Geometry& geometry) {
  const std::vector<std::ptrdiff_t> index =
      batch_index(offset, geometry.shape, geometry.strides, geometry.axis);
  std::ptrdiff_t position = 0, k = 0;
  for (std::size_t axis = 0; axis < geometry.shape.size(); ++axis)
    if (static_cast<int>(axis) != geometry.axis)
      position = position * geometry.shape[axis] + index[k++];
  return position;
}

void run_calls(const BatchPlan& plan, const Geometry& geometry, const ErrorContext& names,
               const std::function<void(std::ptrdiff_t)>& body) {
  std::exception_ptr failure;
  std::ptrdiff_t failed_call = 0;
  {
    py::gil_scoped_release release;
    for (std::ptrdiff_t k = 0; k < plan.calls() && !failure; ++k) {
      try {
        body(k);
      } catch (...) {
        failure = std::current_exception();
        failed_call = k;
      }
    }
  }
  if (!failure) return;
  ErrorContext context = names;
  if (geometry.shape.size() > 1)
    context.system_index = [&](std::ptrdiff_t system) {
      return batch_index(plan.call_offset(failed_call) + system * plan.layout.system_stride,
                         geometry.shape, geometry.strides, geometry.axis);
    };
  try {
    std::rethrow_exception(failure);
  } catch (const InvalidArgument& error) {
    raise_invalid_argument(error, context);
  } catch (const NumericalError& error) {
    raise_numerical_error(error, context);
  }
}

}  // namespace tridiff::python
