// tridiff solvers: batched tridiagonal solves (Thomas, cyclic reduction, PCR, their hybrid,
// partial pivoting, periodic systems, the diffusion form) for float, double and complex.
#pragma once

#include "tridiff/solvers/error.hpp"
#include "tridiff/solvers/layout.hpp"
#include "tridiff/solvers/solve.hpp"
