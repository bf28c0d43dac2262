// The consistent start for high degrees (docs/theory.md section 6.3): D_3 .. D_{d-1} at t0 by
// Picard iteration of the Taylor polynomial with one wide symmetric stencil.
#include <algorithm>

#include "ceode_fused.hpp"

namespace ceode {

namespace {

// Half width R of the stencil: the q-th derivative of the acceleration on 2R + 1 nodes
// spaced h errs by O(h^(2R+1-q)), so D_k = a^(k-2) errs by O(h^(2R+3-k)); an order-p set
// keeps its order when that is O(h^(p+1-k)), i.e. 2R + 2 >= p. Orders reach d (never d + 1).
int HalfWidth(int d) { return d / 2; }

// Sweeps until only the stencil's truncation is left (see StartDerivativesHigh): d - 3 when f
// reads the velocity (the samples lose one power of s to it); when it does not, the samples are
// as accurate as the polynomial and a sweep gains two powers (x'' = a), so R sweeps reach the
// same O(h^(2R+3-k)) (docs/theory.md section 6.3).
int Sweeps(int d, bool vel_dependent) {
  return vel_dependent ? d - 3 : std::min(d - 3, HalfWidth(d));
}

// The start's linear combinations go through the step's kernel: on serial vectors the fused
// backend when the fused kernel is on (one call per plan instead of one N_Vector operation per
// term), elsewhere the N_Vector reference; the two give the same numbers (ceode_fused.hpp).
struct StartPlan {
  UpdatePlan plan;
  FusedPlan fused;
  bool serial = false;
};

void Prepare(const CEodeMemRec* ce, StartPlan* sp) {
  sp->serial = ce->fused && N_VGetVectorID(ce->xcur) == SUNDIALS_NVEC_SERIAL &&
               BuildFusedPlan(sp->plan, {}, &sp->fused);
}

void Run(const StartPlan& sp, sunindextype n) {
  if (sp.serial) {
    UpdateSerial(sp.fused, n);
  } else {
    UpdateReference(sp.plan, {});
  }
}

// The Taylor curve at s: xs = sum_{i<d} D_i s^i/i! (D_0 = x), vs its derivative (the same
// weights, shifted).
void TaylorPlan(const CEodeMemRec* ce, sunrealtype s, N_Vector xs, N_Vector vs, StartPlan* sp) {
  const int d = ce->degree;
  UpdatePlan& p = sp->plan;
  p.n = 2;
  p.combos[0] = Combo{};
  p.combos[1] = Combo{};
  sunrealtype w = 1;  // s^i / i!
  for (int i = 0; i < d; ++i) {
    p.combos[0].Add(w, i == 0 ? ce->xcur : ce->D[i]);
    if (i < d - 1) p.combos[1].Add(w, ce->D[i + 1]);
    w *= s / (i + 1);
  }
  p.combos[0].out = xs;
  p.combos[1].out = vs;
}

}  // namespace

// Each sweep evaluates the acceleration on the 2R nodes s = jh, j = -R..R, j != 0, along the
// Taylor polynomial of all current derivatives, and replaces D_3..D_{d-1} by the stencil's
// derivatives of those samples. If the polynomial is right to O(s^m), the samples are right to
// O(s^(m-1)) (the velocity loses one power), and a stencil exact on polynomials of degree 2R
// returns derivatives below m - 1 unchanged by that error: every sweep fixes at least one more
// derivative, so d - 3 sweeps leave only the stencil's own O(h^(2R+1-q)) truncation.
// The 2R samples of a sweep are kept (in Dnew[1..d-1] and as: 2R <= d vectors, all free
// before the first step) and combined once at the sweep's end, term for term in the order of a
// running sum, so the derivatives come out as if accumulated node by node.
int StartDerivativesHigh(
    CEodeMemRec* ce, sunrealtype t0, N_Vector xs, N_Vector vs, N_Vector as,
    const std::function<int(sunrealtype, N_Vector, N_Vector, N_Vector)>& accel) {
  const int d = ce->degree;
  const sunrealtype h = ce->h;
  const int R = HalfWidth(d);
  const int npts = 2 * R + 1;
  sunrealtype nodes[2 * kMaxDegree + 1] = {};
  sunrealtype wts[kMaxDegree][2 * kMaxDegree + 1];  // wts[q]: the q-th derivative
  for (int j = 0; j < npts; ++j) nodes[j] = (j - R) * h;
  FornbergTable(d - 3, npts, nodes, wts);
  N_Vector sample[2 * kMaxDegree];
  for (int i = 0; i < 2 * R; ++i) sample[i] = i + 1 < d ? ce->Dnew[i + 1] : as;
  StartPlan taylor[2 * kMaxDegree];
  StartPlan stencil;
  stencil.plan.n = d - 3;
  for (int k = 3; k < d; ++k) {
    Combo& cb = stencil.plan.combos[k - 3];
    cb = Combo{};
    cb.Add(wts[k - 2][R], ce->D[2]);
    for (int j = 0; j < npts; ++j) {
      if (j != R) cb.Add(wts[k - 2][j], sample[j < R ? j : j - 1]);
    }
    cb.out = ce->D[k];
  }
  Prepare(ce, &stencil);
  for (int j = 0; j < 2 * R; ++j) {
    TaylorPlan(ce, nodes[j < R ? j : j + 1], xs, vs, &taylor[j]);
    Prepare(ce, &taylor[j]);
  }
  for (int k = 3; k < d; ++k) N_VConst(0, ce->D[k]);
  int flag = CE_SUCCESS;
  const int sweeps = Sweeps(d, ce->vel_dependent);
  for (int sweep = 0; sweep < sweeps && flag == CE_SUCCESS; ++sweep) {
    for (int j = 0; j < 2 * R && flag == CE_SUCCESS; ++j) {
      Run(taylor[j], ce->n);
      flag = accel(t0 + nodes[j < R ? j : j + 1], xs, vs, sample[j]);
    }
    if (flag == CE_SUCCESS) Run(stencil, ce->n);
  }
  return flag;
}

}  // namespace ceode
