// The forcing hook of the right-hand side (ceode_forcing.hpp) and the choice of what CEODE
// evaluates: the user's f, F of the first-order form, or either with the forcing.
#include "ceode_forcing.hpp"

#include <algorithm>
#include <cmath>

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
  CEodeRhsFn adapter = ce->adapters.first_order != nullptr ? FirstOrderRhs : nullptr;
  if (fc != nullptr && fc->n > 0) adapter = ForcedRhs;
  ce->adapters.rhs = adapter != nullptr ? adapter : ce->f;
  ce->adapters.rhs_data = adapter != nullptr ? static_cast<void*>(ce) : ce->user_data;
}

void FreeForcing(Forcing* fc) {
  ForcedEnd& e = fc->end;
  for (N_Vector w : {fc->vg, e.rx, e.jump, e.xp}) {
    if (w != nullptr) N_VDestroy(w);
  }
  for (N_Vector w : e.g) {
    if (w != nullptr) N_VDestroy(w);
  }
  *fc = Forcing();
}

int SetForcing(CEodeMemRec* ce, Forcing* fc, sunrealtype tshift, sunrealtype tscale, int n,
               const N_Vector* Fx, const N_Vector* Fv, const char* func) {
  int flag = CE_SUCCESS;
  bool finite = n <= 0 || (std::isfinite(tshift) && std::isfinite(tscale));
  for (int k = 0; k < n && finite; ++k) finite = IsFinite(Fx[k]) && IsFinite(Fv[k]);
  if (!finite) {  // the forcing enters every acceleration: refused here, not found as NaN later
    flag = ProcessError(ce, CE_ILL_INPUT, func,
                        "The forcing is not finite (tshift = %g, tscale = %g, or an entry of a "
                        "forcing vector is NaN or Inf).",
                        static_cast<double>(tshift), static_cast<double>(tscale));
  } else if (n > 1 && !(tscale != 0)) {
    flag = ProcessError(ce, CE_ILL_INPUT, func, "tscale = 0 with a non-constant forcing.");
  } else if (n > 0 && !CloneMissing(&fc->vg, ce->xcur)) {
    flag = ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
  }
  fc->n = flag == CE_SUCCESS ? n : 0;
  for (int k = 0; k < fc->n; ++k) {
    fc->Fx[k] = Fx[k];
    fc->Fv[k] = Fv[k];
  }
  fc->tshift = tshift;
  fc->tscale = tscale;
  SelectRhs(ce);
  return flag;
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

// The carried history needs the explicit path's (D_2 = G at the end point, exactly; with declared
// velocity dependence D_2 comes from the implicit solve and g_v would enter the jerk) and a
// consistent one (not the zero start).
void KeepEnd(CEodeMemRec* ce, Forcing* fc) {
  ForcedEnd& e = fc->end;
  e.valid = false;
  if (ce->vel_dependent || ce->zero_start || !ce->started) return;
  const sunrealtype t = ce->tcur;
  for (int k = 2; k < ce->degree; ++k) {
    if (!CloneMissing(&e.g[k], ce->xcur)) return;
    ForcingAccel(*fc, t, k - 2, ce->D[k], -1, e.g[k]);
  }
  if (!CloneMissing(&e.rx, ce->xcur) || !CloneMissing(&e.jump, ce->xcur) ||
      !CloneMissing(&e.xp, ce->xcur))
    return;
  ForcingX(*fc, t, 0, nullptr, 1, e.rx);
  e.t = t;
  e.degree = ce->degree;
  e.valid = true;
}

bool CanCarry(const CEodeMemRec* ce, const Forcing& fc, sunrealtype t0) {
  const ForcedEnd& e = fc.end;
  return e.valid && !ce->vel_dependent && !ce->zero_start && e.degree == ce->degree &&
         std::fabs(t0 - e.t) <= GridTolerance(ce, ce->h);
}

// The forcing's derivatives are known exactly. x and v are continuous, so g(t0, x0) is
// unchanged: D_2 costs nothing. x' = v + r_x jumps by delta = r_x,new(t0) - r_x,old(t0), so the
// g part of the jerk, g_t + g_x x', gains g_x delta: one forward difference, none when
// delta = 0. Degrees 3 and 4 are then exact. From D_4 on, the g parts also change with the jump
// (g_x times the jump of D_2, g_xx terms in delta): carried as they are, these errors are
// proportional to the change of the forcing, and a step sees them scaled by h^k (docs/porting.md,
// "What a restart costs").
int CarryHistory(CEodeMemRec* ce, Forcing* fc, sunrealtype t0, N_Vector x0, N_Vector v0,
                 const char* func) {
  ForcedEnd& e = fc->end;
  for (int k = 2; k < ce->degree; ++k) ForcingAccel(*fc, t0, k - 2, e.g[k], 1, ce->D[k]);
  if (ce->degree < 4) return CE_SUCCESS;
  ForcingX(*fc, t0, -1, e.rx, 1, e.jump);
  const sunrealtype dn = N_VMaxNorm(e.jump);
  if (!(dn > 0)) return CE_SUCCESS;
  const sunrealtype eps =
      std::sqrt(SUN_UNIT_ROUNDOFF) * std::max(sunrealtype(1), N_VMaxNorm(x0) / dn);
  N_VLinearSum(1, x0, eps, e.jump, e.xp);
  const int rv = BaseRhs(ce, t0, e.xp, v0, ce->atmp);
  ++ce->nfe;
  ++ce->nfe_start;
  if (rv != 0) {
    return ProcessError(ce, CE_RHSFUNC_FAIL, func,
                        "The right-hand side failed (returned %d) at t = %.17g.", rv,
                        static_cast<double>(t0));
  }
  N_VLinearSum(1 / eps, ce->atmp, -1 / eps, e.g[2], ce->atmp);
  N_VLinearSum(1, ce->D[3], 1, ce->atmp, ce->D[3]);
  return CE_SUCCESS;
}

}  // namespace ceode
