// Dense output: the interpolant of the step interval [tcur, tcur + h] from the history at tcur
// and the position x(tcur + h) (docs/theory.md section 7); with error control, of the last
// accepted step [tcur - hlast, tcur] and the position x(tcur - hlast) (section 12.4). The same
// weights and operations for one derivative (Interpolate: CEodeGetDky, roots) and for both
// outputs of CEodeEvolve (OutputState).
#include <algorithm>
#include <cmath>

#include "ceode_adapt.hpp"
#include "ceode_kernels.hpp"

namespace ceode {

namespace {

// The interval of the dense output: [tcur, tcur + h] and x(tcur + h), or with error control the
// last accepted step [tcur - hlast, tcur] and x(tcur - hlast) (h = -hlast).
struct DenseFrame {
  sunrealtype h;
  N_Vector xend;
  sunrealtype ts[kMaxDegree + 1];  // s^i / i!
  sunrealtype th[kMaxDegree + 1];  // h^i / i!
  sunrealtype hd;                  // h^d
};

DenseFrame Frame(const CEodeMemRec* ce, sunrealtype s) {
  const int d = ce->degree;
  const bool back = AdaptOn(ce) && ce->adapt->hlast > 0;
  DenseFrame f;
  f.h = back ? -ce->adapt->hlast : ce->h;
  f.xend = back ? ce->xnew : ce->xnext;
  TaylorWeights(s, d, f.ts);
  if (!AdaptOn(ce) && ce->co.h == f.h) {  // the fixed step's own weights: TaylorWeights(h, d)
    std::copy(ce->co.tw, ce->co.tw + d, f.th);
  } else {
    TaylorWeights(f.h, d, f.th);
  }
  f.hd = std::pow(f.h, d);
  return f;
}

// p(s) = sum_{i<d} D_i s^i/i! + e s^d, with e fixed by p(h) = x(tcur + h) (error control:
// p(-hlast) = x(tcur - hlast)): the k-th derivative's weights c of D_1 .. D_{d-1}, of
// tmp3 = xend - x(tcur) and (k = 0) of x(tcur), in the vectors X; returns their count.
int InterpolantTerms(CEodeMemRec* ce, sunrealtype s, int k, const DenseFrame& f, sunrealtype* c,
                     N_Vector* X) {
  const int d = ce->degree;
  const sunrealtype e = Factorial(d) / Factorial(d - k) * std::pow(s, d - k) / f.hd;
  int m = 0;
  for (int i = 1; i < d; ++i) {
    c[m] = (i >= k ? f.ts[i - k] : 0) - e * f.th[i];
    X[m++] = ce->D[i];
  }
  c[m] = e;
  X[m++] = ce->tmp3;
  if (k == 0) {
    c[m] = 1;
    X[m++] = ce->xcur;
  }
  return m;
}

// tmp3 = xend - x(tcur) (N_VLinearSum's difference, on raw arrays when serial).
void EndDifference(CEodeMemRec* ce, N_Vector xend, bool serial) {
  if (!serial) {
    N_VLinearSum(1, xend, -1, ce->xcur, ce->tmp3);
    return;
  }
  const sunrealtype* a = SerialData(xend);
  const sunrealtype* b = SerialData(ce->xcur);
  sunrealtype* t = SerialData(ce->tmp3);
  for (sunindextype i = 0; i < ce->n; ++i) t[i] = a[i] - b[i];
}

__attribute__((noinline)) void InterpolatePolynomial(CEodeMemRec* ce, sunrealtype s, int k,
                                                     N_Vector out) {
  const DenseFrame f = Frame(ce, s);
  sunrealtype c[kMaxDegree + 2];
  N_Vector X[kMaxDegree + 2];
  N_VLinearSum(1, f.xend, -1, ce->xcur, ce->tmp3);
  Combine(InterpolantTerms(ce, s, k, f, c, X), c, X, out);
}

// x and x' at tcur + s in one frame (the powers once, the difference once), on the serial backend
// when the run has it and the outputs are serial: CombineSerial gives Combine's values.
__attribute__((noinline)) bool InterpolateState(CEodeMemRec* ce, sunrealtype s, N_Vector xout,
                                                N_Vector vout) {
  const DenseFrame f = Frame(ce, s);
  const bool serial = SerialBackend(ce) && N_VGetVectorID(ce->xcur) == SUNDIALS_NVEC_SERIAL &&
                      N_VGetVectorID(xout) == SUNDIALS_NVEC_SERIAL &&
                      N_VGetVectorID(vout) == SUNDIALS_NVEC_SERIAL;
  EndDifference(ce, f.xend, serial);
  sunrealtype c[kMaxDegree + 2];
  N_Vector X[kMaxDegree + 2];
  for (int k = 0; k <= 1; ++k) {
    N_Vector out = k == 0 ? xout : vout;
    const int m = InterpolantTerms(ce, s, k, f, c, X);
    if (serial) {
      CombineSerial(ce->n, m, c, X, SerialData(out));
    } else {
      Combine(m, c, X, out);
    }
  }
  return AllFinite(xout) && AllFinite(vout);
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
// test.
bool OutputState(CEodeMemRec* ce, sunrealtype s, N_Vector xout, N_Vector vout) {
  if (s == 0) return CopyPairFinite(ce->xcur, ce->D[1], xout, vout);
  return InterpolateState(ce, s, xout, vout);
}

}  // namespace ceode
