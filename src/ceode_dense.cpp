// Dense output: the interpolant of the step interval [tcur, tcur + h] from the history at tcur
// and the position x(tcur + h) (docs/theory.md section 7); with error control, of the last
// accepted step [tcur - hlast, tcur] and the position x(tcur - hlast) (section 12.4).
#include <cmath>

#include "ceode_adapt.hpp"
#include "ceode_kernels.hpp"

namespace ceode {

namespace {

// p(s) = sum_{i<d} D_i s^i/i! + e s^d, with e fixed by p(h) = x(tcur + h) (error control:
// p(-hlast) = x(tcur - hlast)). Apart from Interpolate so that the copy at s = 0 (every
// CE_ONE_STEP output) does not set up its frame.
__attribute__((noinline)) void InterpolatePolynomial(CEodeMemRec* ce, sunrealtype s, int k,
                                                     N_Vector out) {
  const int d = ce->degree;
  const bool back = AdaptOn(ce) && ce->adapt->hlast > 0;
  const sunrealtype h = back ? -ce->adapt->hlast : ce->h;
  N_Vector xend = back ? ce->xnew : ce->xnext;
  const sunrealtype e = Factorial(d) / Factorial(d - k) * std::pow(s, d - k) / std::pow(h, d);
  sunrealtype ts[kMaxDegree + 1];
  sunrealtype th[kMaxDegree + 1];
  TaylorWeights(s, d, ts);
  TaylorWeights(h, d, th);
  sunrealtype c[kMaxDegree + 2];
  N_Vector X[kMaxDegree + 2];
  int m = 0;
  for (int i = 1; i < d; ++i) {
    c[m] = (i >= k ? ts[i - k] : 0) - e * th[i];
    X[m++] = ce->D[i];
  }
  N_VLinearSum(1, xend, -1, ce->xcur, ce->tmp3);
  c[m] = e;
  X[m++] = ce->tmp3;
  if (k == 0) {
    c[m] = 1;
    X[m++] = ce->xcur;
  }
  Combine(m, c, X, out);
}

}  // namespace

void Interpolate(CEodeMemRec* ce, sunrealtype s, int k, N_Vector out) {
  if (s == 0 && k < ce->degree) {  // exactly the method's own values at tcur
    CopyVector(k == 0 ? ce->xcur : ce->D[k], out);
    return;
  }
  InterpolatePolynomial(ce, s, k, out);
}

// A return at tcur (s = 0, every CE_ONE_STEP call and every output on the step grid) copies the
// method's own values and tests them in the same pass; inside the step the interpolant, then the
// test. Both copies are made before the answer (& rather than &&).
namespace {

__attribute__((noinline)) bool InterpolateState(CEodeMemRec* ce, sunrealtype s, N_Vector xout,
                                                N_Vector vout) {
  InterpolatePolynomial(ce, s, 0, xout);
  InterpolatePolynomial(ce, s, 1, vout);
  return AllFinite(xout) && AllFinite(vout);
}

}  // namespace

bool OutputState(CEodeMemRec* ce, sunrealtype s, N_Vector xout, N_Vector vout) {
  if (s == 0) return CopyPairFinite(ce->xcur, ce->D[1], xout, vout);
  return InterpolateState(ce, s, xout, vout);
}

}  // namespace ceode
