// The forcing hook of the right-hand side (ceode_forcing.hpp) and the choice of what CEODE
// evaluates: the user's f, F of the first-order form, or either with the forcing.
#include "ceode_forcing.hpp"

namespace ceode {
namespace {

// Weights of r(t) (value) and r'(t) at t.
void ForcingWeights(const Forcing& fc, sunrealtype t, sunrealtype* val, sunrealtype* der) {
  const sunrealtype tau = fc.n > 1 ? (t - fc.tshift) / fc.tscale : 0;
  sunrealtype p = 1;  // tau^k
  for (int k = 0; k < fc.n; ++k) {
    val[k] = p;
    der[k] = 0;
    if (k > 0) der[k] = k * val[k - 1] / fc.tscale;
    p *= tau;
  }
}

// Weights of the m-th time derivative of r(t) at t.
void ForcingDerivWeights(const Forcing& fc, sunrealtype t, int m, sunrealtype* w) {
  const sunrealtype tau = fc.n > 1 ? (t - fc.tshift) / fc.tscale : 0;
  for (int k = 0; k < fc.n; ++k) {
    sunrealtype c = k >= m ? 1 : 0;
    for (int i = 0; i < m && k >= m; ++i) c *= static_cast<sunrealtype>(k - i) / fc.tscale;
    for (int i = m; i < k; ++i) c *= tau;
    w[k] = c;
  }
}

// out = a * base + s * sum_k w[k] F[k] in one pass (base may be out or null; zero weights are
// skipped, since a forced vector at large n costs one pass per term).
void CombineForcing(sunrealtype a, N_Vector base, sunrealtype s, int nw, const sunrealtype* w,
                    N_Vector const* F, N_Vector out) {
  sunrealtype c[2 * kMaxForcing + 1];
  N_Vector X[2 * kMaxForcing + 1];
  int m = 0;
  if (base != nullptr) {
    c[m] = a;
    X[m++] = base;
  }
  for (int k = 0; k < nw; ++k) {
    if (w[k] == 0) continue;
    c[m] = s * w[k];
    X[m++] = F[k];
  }
  if (m == 0) {  // N_VLinearCombination needs at least one vector
    N_VConst(0, out);
    return;
  }
  N_VLinearCombination(m, c, X, out);
}

// The forced right-hand side g(t, x, u - r_x) + r_v + r_x' (data: the memory).
int ForcedRhs(sunrealtype t, N_Vector x, N_Vector u, N_Vector f, void* mem) {
  auto* ce = static_cast<CEodeMemRec*>(mem);
  const Forcing& fc = *ce->adapters.forcing;
  sunrealtype val[kMaxForcing], der[kMaxForcing];
  ForcingWeights(fc, t, val, der);
  CombineForcing(1, u, -1, fc.n, val, fc.Fx, fc.vg);
  const int rv = BaseRhs(ce, t, x, fc.vg, f);
  if (rv != 0) return rv;
  sunrealtype c[2 * kMaxForcing];
  N_Vector X[2 * kMaxForcing];
  for (int k = 0; k < fc.n; ++k) {
    c[k] = val[k];
    X[k] = fc.Fv[k];
    c[fc.n + k] = der[k];
    X[fc.n + k] = fc.Fx[k];
  }
  CombineForcing(1, f, 1, 2 * fc.n, c, X, f);
  return 0;
}

}  // namespace

int BaseRhs(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector v, N_Vector f) {
  return ce->adapters.first_order != nullptr ? FirstOrderRhs(t, x, v, f, ce)
                                             : ce->f(t, x, v, f, ce->user_data);
}

void SelectRhs(CEodeMemRec* ce) {
  const Forcing* fc = ce->adapters.forcing;
  if (fc != nullptr && fc->n > 0) {
    ce->adapters.rhs = ForcedRhs;
  } else {
    ce->adapters.rhs = ce->adapters.first_order != nullptr ? FirstOrderRhs : nullptr;
  }
}

int SetForcing(CEodeMemRec* ce, Forcing* fc, sunrealtype tshift, sunrealtype tscale, int n,
               const N_Vector* Fx, const N_Vector* Fv, const char* func) {
  if (n > 1 && !(tscale != 0)) {
    fc->n = 0;
    SelectRhs(ce);
    return ProcessError(ce, CE_ILL_INPUT, func, "tscale = 0 with a non-constant forcing.");
  }
  for (int k = 0; k < n; ++k) {
    fc->Fx[k] = Fx[k];
    fc->Fv[k] = Fv[k];
  }
  fc->n = n;
  fc->tshift = tshift;
  fc->tscale = tscale;
  SelectRhs(ce);
  return CE_SUCCESS;
}

void ForcingX(const Forcing& fc, sunrealtype t, sunrealtype a, N_Vector base, sunrealtype s,
              N_Vector out) {
  sunrealtype val[kMaxForcing], der[kMaxForcing];
  ForcingWeights(fc, t, val, der);
  CombineForcing(a, base, s, fc.n, val, fc.Fx, out);
}

void ForcingAccel(const Forcing& fc, sunrealtype t, int m, N_Vector base, sunrealtype s,
                  N_Vector out) {
  sunrealtype c[2 * kMaxForcing];
  N_Vector X[2 * kMaxForcing];
  ForcingDerivWeights(fc, t, m, c);
  ForcingDerivWeights(fc, t, m + 1, c + fc.n);
  for (int k = 0; k < fc.n; ++k) {
    X[k] = fc.Fv[k];
    X[fc.n + k] = fc.Fx[k];
  }
  CombineForcing(1, base, s, 2 * fc.n, c, X, out);
}

}  // namespace ceode
