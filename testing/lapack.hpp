// The LAPACK routines the tests and benchmarks hold tridiff against (Fortran, Debian's
// liblapack-dev; a program including this links LAPACK::LAPACK). ?gtsv: Gaussian elimination
// with partial pivoting on a tridiagonal system, overwriting b with x (info > 0: U(info, info)
// is exactly zero). ?gttrf / ?gttrs: the same LU kept, then solved for new right-hand sides.
// dgtcon: the reciprocal 1-norm condition estimate from those factors. dgtrfs: iterative
// refinement with error bounds. gfortran passes the length of each CHARACTER argument as a
// trailing hidden size_t.
#pragma once

#include <cstddef>

extern "C" {
void sgtsv_(const int* n, const int* nrhs, float* dl, float* d, float* du, float* b, const int* ldb,
            int* info);
void dgtsv_(const int* n, const int* nrhs, double* dl, double* d, double* du, double* b,
            const int* ldb, int* info);
void sgttrf_(const int* n, float* dl, float* d, float* du, float* du2, int* ipiv, int* info);
void dgttrf_(const int* n, double* dl, double* d, double* du, double* du2, int* ipiv, int* info);
void sgttrs_(const char* trans, const int* n, const int* nrhs, const float* dl, const float* d,
             const float* du, const float* du2, const int* ipiv, float* b, const int* ldb,
             int* info, std::size_t trans_length);
void dgttrs_(const char* trans, const int* n, const int* nrhs, const double* dl, const double* d,
             const double* du, const double* du2, const int* ipiv, double* b, const int* ldb,
             int* info, std::size_t trans_length);
void dgtcon_(const char* norm, const int* n, const double* dl, const double* d, const double* du,
             const double* du2, const int* ipiv, const double* anorm, double* rcond, double* work,
             int* iwork, int* info, std::size_t norm_length);
void dgtrfs_(const char* trans, const int* n, const int* nrhs, const double* dl, const double* d,
             const double* du, const double* dlf, const double* df, const double* duf,
             const double* du2, const int* ipiv, const double* b, const int* ldb, double* x,
             const int* ldx, double* ferr, double* berr, double* work, int* iwork, int* info,
             std::size_t trans_length);
}
