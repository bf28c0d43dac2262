// The adaptive step's vector operations (AdaptKernels, ceode_kernels.hpp): the N_Vector
// reference and the serial loops beside it, operation for operation, so that both give the
// same numbers (the N_Vector forms are those of SUNDIALS' serial vector, special cases
// included).
#include <algorithm>
#include <cmath>

#include "ceode_kernels.hpp"

namespace ceode {

void AdaptKernels::Lin(int m, const sunrealtype* c, N_Vector* X, N_Vector out) const {
  if (serial && m == 2 && c[1] == -c[0]) {
    // The divided differences' form, r (x - y): N_VLinearSum's arithmetic for a = -b (with
    // a = +-1 the difference itself, the same values).
    const sunrealtype* x = NV_DATA_S(X[0]);
    const sunrealtype* y = NV_DATA_S(X[1]);
    sunrealtype* z = NV_DATA_S(out);
    for (sunindextype i = 0; i < n; ++i) z[i] = c[0] * (x[i] - y[i]);
    return;
  }
  if (serial) {
    CombineSerial(n, m, c, X, NV_DATA_S(out));
  } else {
    Combine(m, c, X, out);
  }
}

void AdaptKernels::Axpy(sunrealtype c, N_Vector y, N_Vector x) const {
  if (!serial) {
    N_VLinearSum(1, x, c, y, x);
    return;
  }
  sunrealtype* xd = NV_DATA_S(x);
  const sunrealtype* yd = NV_DATA_S(y);
  for (sunindextype i = 0; i < n; ++i) xd[i] += c * yd[i];
}

void AdaptKernels::Scale(sunrealtype c, N_Vector x) const {
  if (!serial) {
    N_VScale(c, x, x);
    return;
  }
  sunrealtype* xd = NV_DATA_S(x);
  for (sunindextype i = 0; i < n; ++i) xd[i] *= c;
}

sunrealtype AdaptKernels::WrmsNorm(N_Vector x, N_Vector w) const {
  if (!serial) return N_VWrmsNorm(x, w);
  const sunrealtype* xd = NV_DATA_S(x);
  const sunrealtype* wd = NV_DATA_S(w);
  sunrealtype sum = 0;
  for (sunindextype i = 0; i < n; ++i) {
    const sunrealtype p = xd[i] * wd[i];
    sum += p * p;
  }
  return std::sqrt(sum / static_cast<sunrealtype>(n));
}

sunrealtype AdaptKernels::L1Norm(N_Vector x) const {
  if (!serial) return N_VL1Norm(x);
  const sunrealtype* xd = NV_DATA_S(x);
  sunrealtype sum = 0;
  for (sunindextype i = 0; i < n; ++i) sum += std::fabs(xd[i]);
  return sum;
}

sunrealtype AdaptKernels::Weights(N_Vector x, sunrealtype rtol, sunrealtype atol, N_Vector atolv,
                                  N_Vector ewt) const {
  if (!serial) {
    N_VAbs(x, ewt);
    if (atolv != nullptr) {
      N_VLinearSum(rtol, ewt, 1, atolv, ewt);
    } else {
      N_VScale(rtol, ewt, ewt);
      N_VAddConst(ewt, atol, ewt);
    }
    const sunrealtype dmin = N_VMin(ewt);
    if (dmin > 0) N_VInv(ewt, ewt);
    return dmin;
  }
  const sunrealtype* xd = NV_DATA_S(x);
  const sunrealtype* ad = atolv != nullptr ? NV_DATA_S(atolv) : nullptr;
  sunrealtype* wd = NV_DATA_S(ewt);
  for (sunindextype i = 0; i < n; ++i)
    wd[i] = rtol * std::fabs(xd[i]) + (ad != nullptr ? ad[i] : atol);
  sunrealtype dmin = wd[0];  // as N_VMin: a NaN first entry stays the minimum
  for (sunindextype i = 1; i < n; ++i) {
    if (wd[i] < dmin) dmin = wd[i];
  }
  if (!(dmin > 0)) return dmin;
  for (sunindextype i = 0; i < n; ++i) wd[i] = 1 / wd[i];
  return dmin;
}

}  // namespace ceode
