/*
 * gac_linalg.c -- dense LDL^T factorisation and solves of small symmetric matrices (I_f and the contact
 * systems N I_f^-1 N^T).  Row-major n x n, in place.
 */
#include "gac_internal.h"

#include <math.h>

/* In-place LDL^T of a symmetric n x n row-major matrix (lower triangle read; L below the diagonal, D on
 * it).  A pivot not above tol * max|A_ii| stops the factorisation (drop = 0: returns -1) or, with drop = 1,
 * is replaced by 1e300 so that its unknown comes out 0 (returns the number replaced).  -1 also when A has
 * no positive diagonal. */
static int gac_ldlt_factor(int n, double *A, double tol, int drop)
{
    int i, j, k, dropped = 0;
    double scale = 0.0;
    for (i = 0; i < n; ++i) {
        if (fabs(A[i*n + i]) > scale) scale = fabs(A[i*n + i]);
    }
    if (!(scale > 0.0)) return -1;
    for (j = 0; j < n; ++j) {
        double d = A[j*n + j];
        for (k = 0; k < j; ++k) d -= A[j*n + k] * A[j*n + k] * A[k*n + k];
        if (!(d > tol * scale)) {
            if (!drop) return -1;
            d = 1e300;
            ++dropped;
        }
        A[j*n + j] = d;
        for (i = j + 1; i < n; ++i) {
            double sum = A[i*n + j];
            for (k = 0; k < j; ++k) sum -= A[i*n + k] * A[j*n + k] * A[k*n + k];
            A[i*n + j] = sum / d;
        }
    }
    return dropped;
}

/* In-place LDL^T of a symmetric positive definite matrix.  Returns 0, or -1 when a pivot is not above
 * tol * max|A_ii|. */
int gac_ldlt(int n, double *A, double tol)
{
    return gac_ldlt_factor(n, A, tol, 0);
}

/* Solve (L D L^T) x = b in place, with the factor of gac_ldlt. */
void gac_ldlt_solve(int n, const double *LD, double *b)
{
    int i, k;
    for (i = 0; i < n; ++i) {
        for (k = 0; k < i; ++k) b[i] -= LD[i*n + k] * b[k];
    }
    for (i = 0; i < n; ++i) b[i] /= LD[i*n + i];
    for (i = n - 1; i >= 0; --i) {
        for (k = i + 1; k < n; ++k) b[i] -= LD[k*n + i] * b[k];
    }
}

/* In-place LDL^T of a symmetric positive definite n x n row-major matrix in long double (as gac_ldlt): 0, or -1
 * when a pivot is not above tol * max|A_ii|.  Then x = A^-1 b in place (gac_ldlt_ld_solve). */
int gac_ldlt_ld(int n, long double *A, double tol)
{
    long double scale = 0.0L;
    int i, j, k;
    for (i = 0; i < n; ++i) {
        if (fabsl(A[i*n + i]) > scale) scale = fabsl(A[i*n + i]);
    }
    if (!(scale > 0.0L)) return -1;
    for (j = 0; j < n; ++j) {
        long double d = A[j*n + j];
        for (k = 0; k < j; ++k) d -= A[j*n + k] * A[j*n + k] * A[k*n + k];
        if (!(d > tol * scale)) return -1;
        A[j*n + j] = d;
        for (i = j + 1; i < n; ++i) {
            long double sum = A[i*n + j];
            for (k = 0; k < j; ++k) sum -= A[i*n + k] * A[j*n + k] * A[k*n + k];
            A[i*n + j] = sum / d;
        }
    }
    return 0;
}

void gac_ldlt_ld_solve(int n, const long double *LD, long double *b)
{
    int i, k;
    for (i = 0; i < n; ++i) {
        for (k = 0; k < i; ++k) b[i] -= LD[i*n + k] * b[k];
    }
    for (i = 0; i < n; ++i) b[i] /= LD[i*n + i];
    for (i = n - 1; i >= 0; --i) {
        for (k = i + 1; k < n; ++k) b[i] -= LD[k*n + i] * b[k];
    }
}

/* LDL^T of the n x n constraint matrix N I_f^-1 N^T, where a pivot not above tol * max|A_ii| (a constraint
 * dependent on the earlier ones, which hold it already) is replaced by 1e300: its multiplier comes out 0
 * and it drops out.  Returns the number of such constraints, or -1 if A has no positive diagonal. */
int gac_ldlt_drop(int n, double *A, double tol)
{
    return gac_ldlt_factor(n, A, tol, 1);
}

/* Solve A x = b in place (x into b) for a general n x n row-major A, by Gaussian elimination with partial
 * pivoting (A is overwritten).  Returns 0, or -1 when a pivot is not above tol * max|A_ij| (singular). */
int gac_lu_solve(int n, double *A, double *b, double tol)
{
    int i, j, k;
    double scale = 0.0;
    for (i = 0; i < n * n; ++i) {
        if (fabs(A[i]) > scale) scale = fabs(A[i]);
    }
    if (!(scale > 0.0)) return -1;
    for (k = 0; k < n; ++k) {
        int pivot = k;
        for (i = k + 1; i < n; ++i) {
            if (fabs(A[i*n + k]) > fabs(A[pivot*n + k])) pivot = i;
        }
        if (!(fabs(A[pivot*n + k]) > tol * scale)) return -1;
        if (pivot != k) {
            double t;
            for (j = 0; j < n; ++j) {
                t = A[k*n + j];
                A[k*n + j] = A[pivot*n + j];
                A[pivot*n + j] = t;
            }
            t = b[k];
            b[k] = b[pivot];
            b[pivot] = t;
        }
        for (i = k + 1; i < n; ++i) {
            const double factor = A[i*n + k] / A[k*n + k];
            if (factor == 0.0) continue;
            for (j = k; j < n; ++j) A[i*n + j] -= factor * A[k*n + j];
            b[i] -= factor * b[k];
        }
    }
    for (i = n - 1; i >= 0; --i) {
        double sum = b[i];
        for (j = i + 1; j < n; ++j) sum -= A[i*n + j] * b[j];
        b[i] = sum / A[i*n + i];
    }
    return 0;
}

double gac_dot(int n, const double *a, const double *b)
{
    double sum = 0.0;
    int i;
    for (i = 0; i < n; ++i) sum += a[i] * b[i];
    return sum;
}
