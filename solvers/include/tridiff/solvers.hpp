// tridiff solvers: batched tridiagonal solves (Thomas, cyclic reduction, PCR, their hybrid,
// partial pivoting, periodic systems, the diffusion form) for float, double and complex; factors
// kept for repeated solves, condition estimates, refinement and mixed precision.
#pragma once

#include "tridiff/solvers/error.hpp"
#include "tridiff/solvers/factor.hpp"
#include "tridiff/solvers/layout.hpp"
#include "tridiff/solvers/refine.hpp"
#include "tridiff/solvers/solve.hpp"
