// A guaranteed upper bound of omega_max from the assembled stiffness, as explicit
// FE codes give their stable step (docs/theory.md, linear stability): Gershgorin's
// theorem on M^{-1} K (and on the similar, for a symmetric K also symmetric,
// M^{-1/2} K M^{-1/2}) with a lumped (diagonal) M. It never lies below omega_max,
// whatever K is, and costs one pass over K's entries: no f evaluations, no
// iteration, nothing that could stop short of the top mode.
#include <sunmatrix/sunmatrix_band.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "ceode_impl.hpp"

namespace ceode {

namespace {

// Row sums of |K_ij| / m_i and of |K_ij| / sqrt(m_i m_j), accumulated entry by entry.
struct RowSums {
  std::vector<sunrealtype> plain, scaled;
  const sunrealtype* m = nullptr;  // lumped masses (nullptr: M = I)
  bool finite = true;
  void Add(sunindextype i, sunindextype j, sunrealtype kij) {
    if (!std::isfinite(kij)) finite = false;
    const sunrealtype a = std::fabs(kij);
    plain[i] += m != nullptr ? a / m[i] : a;
    scaled[i] += m != nullptr ? a / std::sqrt(m[i] * m[j]) : a;
  }
};

sunindextype Rows(SUNMatrix K) {
  switch (SUNMatGetID(K)) {
    case SUNMATRIX_DENSE:
      return SUNDenseMatrix_Rows(K);
    case SUNMATRIX_BAND:
      return SUNBandMatrix_Rows(K);
    case SUNMATRIX_SPARSE:
      return SUNSparseMatrix_Rows(K);
    default:
      return -1;
  }
}

sunindextype Columns(SUNMatrix K) {
  switch (SUNMatGetID(K)) {
    case SUNMATRIX_DENSE:
      return SUNDenseMatrix_Columns(K);
    case SUNMATRIX_BAND:
      return SUNBandMatrix_Columns(K);
    case SUNMATRIX_SPARSE:
      return SUNSparseMatrix_Columns(K);
    default:
      return -1;
  }
}

void SumDense(SUNMatrix K, RowSums* s) {
  const sunindextype n = SUNDenseMatrix_Rows(K);
  for (sunindextype j = 0; j < n; ++j) {
    const sunrealtype* c = SUNDenseMatrix_Column(K, j);
    for (sunindextype i = 0; i < n; ++i) s->Add(i, j, c[i]);
  }
}

void SumBand(SUNMatrix K, RowSums* s) {
  const sunindextype n = SUNBandMatrix_Columns(K);
  const sunindextype mu = SUNBandMatrix_UpperBandwidth(K);
  const sunindextype ml = SUNBandMatrix_LowerBandwidth(K);
  for (sunindextype j = 0; j < n; ++j) {
    const sunrealtype* c = SUNBandMatrix_Column(K, j);  // c[i - j] is K(i, j)
    for (sunindextype i = std::max<sunindextype>(0, j - mu); i <= std::min(n - 1, j + ml); ++i) {
      s->Add(i, j, c[i - j]);
    }
  }
}

void SumSparse(SUNMatrix K, RowSums* s) {
  const bool csr = SUNSparseMatrix_SparseType(K) == CSR_MAT;
  const sunindextype n = csr ? SUNSparseMatrix_Rows(K) : SUNSparseMatrix_Columns(K);
  const sunindextype* ptr = SUNSparseMatrix_IndexPointers(K);
  const sunindextype* idx = SUNSparseMatrix_IndexValues(K);
  const sunrealtype* v = SUNSparseMatrix_Data(K);
  for (sunindextype a = 0; a < n; ++a) {
    for (sunindextype q = ptr[a]; q < ptr[a + 1]; ++q) {
      if (csr) {
        s->Add(a, idx[q], v[q]);
      } else {
        s->Add(idx[q], a, v[q]);
      }
    }
  }
}

// The masses' checks: one clear message per cause.
int CheckMass(CEodeMemRec* ce, const char* func, N_Vector mass, sunindextype n,
              const sunrealtype** m) {
  *m = nullptr;
  if (mass == nullptr) return CE_SUCCESS;
  if (N_VGetLength(mass) != n) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "mass has %ld entries but K has %ld rows: give one lumped mass per row.",
                        static_cast<long>(N_VGetLength(mass)), static_cast<long>(n));
  }
  *m = N_VGetArrayPointer(mass);
  if (*m == nullptr) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "mass does not expose its data (N_VGetArrayPointer is NULL): pass a "
                        "serial, OpenMP or Pthreads vector.");
  }
  for (sunindextype i = 0; i < n; ++i) {
    if (!((*m)[i] > 0) || !std::isfinite((*m)[i])) {
      return ProcessError(ce, CE_ILL_INPUT, func,
                          "mass[%ld] = %g: every lumped mass must be positive and finite.",
                          static_cast<long>(i), static_cast<double>((*m)[i]));
    }
  }
  return CE_SUCCESS;
}

int CheckMatrix(CEodeMemRec* ce, const char* func, SUNMatrix K, sunindextype* n) {
  if (K == nullptr) return ProcessError(ce, CE_ILL_INPUT, func, "K = NULL.");
  *n = Rows(K);
  if (*n < 0) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "K is neither a dense, a band nor a sparse SUNMatrix: no bound for this "
                        "type; give omega_max with CEodeSetMaxFrequency instead.");
  }
  if (Columns(K) != *n) {
    return ProcessError(ce, CE_ILL_INPUT, func, "K is %ld x %ld: the stiffness must be square.",
                        static_cast<long>(*n), static_cast<long>(Columns(K)));
  }
  return CE_SUCCESS;
}

}  // namespace

}  // namespace ceode

extern "C" {

int CEodeGetFrequencyBound(void* mem, SUNMatrix K, N_Vector mass, sunrealtype* omega_bound) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (omega_bound == nullptr) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__, "omega_bound = NULL.");
  }
  sunindextype n = 0;
  flag = ceode::CheckMatrix(ce, __func__, K, &n);
  ceode::RowSums s;
  if (flag == CE_SUCCESS) flag = ceode::CheckMass(ce, __func__, mass, n, &s.m);
  if (flag != CE_SUCCESS) return flag;
  try {
    s.plain.assign(n, 0);
    s.scaled.assign(n, 0);
  } catch (...) {
    return ceode::ProcessError(ce, CE_MEM_FAIL, __func__, "Out of memory.");
  }
  const SUNMatrix_ID id = SUNMatGetID(K);
  if (id == SUNMATRIX_DENSE) ceode::SumDense(K, &s);
  if (id == SUNMATRIX_BAND) ceode::SumBand(K, &s);
  if (id == SUNMATRIX_SPARSE) ceode::SumSparse(K, &s);
  if (!s.finite) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__, "K contains NaN or Inf.");
  }
  const sunrealtype lam_plain = n > 0 ? *std::max_element(s.plain.begin(), s.plain.end()) : 0;
  const sunrealtype lam_scaled = n > 0 ? *std::max_element(s.scaled.begin(), s.scaled.end()) : 0;
  // Both are Gershgorin bounds of the same spectrum; the smaller one is kept.
  const sunrealtype bound = std::sqrt(std::min(lam_plain, lam_scaled));
  if (!std::isfinite(bound)) {  // finite entries whose row sums over the masses overflow
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "The row sums of M^{-1} K overflow (largest %g): K's entries over "
                               "the lumped masses exceed the floating-point range; rescale K.",
                               static_cast<double>(std::min(lam_plain, lam_scaled)));
  }
  *omega_bound = bound;
  return CE_SUCCESS;
}

}  // extern "C"
