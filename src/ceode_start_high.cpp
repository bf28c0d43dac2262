// The consistent start for high degrees (docs/theory.md section 6.3): D_3 .. D_{d-1} at t0 by
// Picard iteration of the Taylor polynomial with one wide symmetric stencil.
#include <algorithm>

#include "ceode_impl.hpp"

namespace ceode {

namespace {

// Half width R of the stencil: the q-th derivative of the acceleration on 2R + 1 nodes
// spaced h errs by O(h^(2R+1-q)), so D_k = a^(k-2) errs by O(h^(2R+3-k)); an order-p set
// keeps its order when that is O(h^(p+1-k)), i.e. 2R + 2 >= p. Orders reach d (never d + 1).
int HalfWidth(int d) { return d / 2; }

}  // namespace

// Each sweep evaluates the acceleration on the 2R nodes s = jh, j = -R..R, j != 0, along the
// Taylor polynomial of all current derivatives, and replaces D_3..D_{d-1} by the stencil's
// derivatives of those samples. If the polynomial is right to O(s^m), the samples are right to
// O(s^(m-1)) (the velocity loses one power), and a stencil exact on polynomials of degree 2R
// returns derivatives below m - 1 unchanged by that error: every sweep fixes at least one more
// derivative, so d - 3 sweeps leave only the stencil's own O(h^(2R+1-q)) truncation.
int StartDerivativesHigh(
    CEodeMemRec* ce, sunrealtype t0, N_Vector xs, N_Vector vs, N_Vector as,
    const std::function<int(sunrealtype, N_Vector, N_Vector, N_Vector)>& accel) {
  const int d = ce->degree;
  const sunrealtype h = ce->h;
  const int R = HalfWidth(d);
  const int npts = 2 * R + 1;
  sunrealtype nodes[2 * kMaxDegree + 1];
  sunrealtype wts[kMaxDegree][2 * kMaxDegree + 1];
  for (int j = 0; j < npts; ++j) nodes[j] = (j - R) * h;
  for (int k = 3; k < d; ++k) FornbergWeights(k - 2, npts, nodes, wts[k]);
  for (int k = 3; k < d; ++k) N_VConst(0, ce->D[k]);
  int flag = CE_SUCCESS;
  for (int sweep = 0; sweep < d - 3 && flag == CE_SUCCESS; ++sweep) {
    for (int k = 3; k < d; ++k) N_VScale(wts[k][R], ce->D[2], ce->Dnew[k]);
    for (int j = 0; j < npts && flag == CE_SUCCESS; ++j) {
      if (j == R) continue;
      const sunrealtype s = nodes[j];
      sunrealtype cx[kMaxDegree];
      N_Vector vx[kMaxDegree];
      sunrealtype sp = 1;  // s^i / i!
      for (int i = 0; i < d; ++i) {
        cx[i] = sp;
        vx[i] = (i == 0) ? ce->xcur : ce->D[i];
        sp *= s / (i + 1);
      }
      N_VLinearCombination(d, cx, vx, xs);
      N_VLinearCombination(d - 1, cx, vx + 1, vs);
      flag = accel(t0 + s, xs, vs, as);
      for (int k = 3; flag == CE_SUCCESS && k < d; ++k) {
        N_VLinearSum(1, ce->Dnew[k], wts[k][j], as, ce->Dnew[k]);
      }
    }
    for (int k = 3; flag == CE_SUCCESS && k < d; ++k) N_VScale(1, ce->Dnew[k], ce->D[k]);
  }
  return flag;
}

}  // namespace ceode
