// Error control (docs/theory.md section 12): the tolerances and step bounds, the method's error
// constant and history remap from its parameters, the error weights, the first step and the
// step-size controller. The adaptive step itself is in ceode_adapt_step.cpp.
#include "ceode_adapt.hpp"

#include <ceode/ceode_stability.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <mutex>
#include <new>

namespace ceode {

void AdaptMemFree::operator()(AdaptMem* am) const { delete am; }

namespace {

// ---- The consistent history of a fixed-step run as power series (docs/theory.md 12.2) ----
// D_k = sum_j gamma_kj h^j y^(k+j): R_k(s), s = h d/dt, are the history's series relative to the
// top derivative, from the derivative relations; gamma_k = R_k / R_2.
constexpr int kTerms = 16;
struct Laurent {
  int v = 0;  // valuation: c[i] is the coefficient of s^(v + i)
  long double c[kTerms] = {};
};

Laurent Mul(const Laurent& a, const Laurent& b) {
  Laurent r;
  r.v = a.v + b.v;
  for (int i = 0; i < kTerms; ++i) {
    for (int j = 0; i + j < kTerms; ++j) r.c[i + j] += a.c[i] * b.c[j];
  }
  return r;
}

Laurent Inv(const Laurent& a) {
  Laurent r;
  r.v = -a.v;
  r.c[0] = 1 / a.c[0];
  for (int n = 1; n < kTerms; ++n) {
    long double s = 0;
    for (int i = 1; i <= n; ++i) s += a.c[i] * r.c[n - i];
    r.c[n] = -s / a.c[0];
  }
  return r;
}

// a + s b, on the lower valuation of the two (the other's last terms drop out of the window).
Laurent AddScaled(const Laurent& a, long double s, const Laurent& b) {
  Laurent r;
  r.v = std::min(a.v, b.v);
  for (int i = 0; i < kTerms; ++i) {
    const int ia = i - (a.v - r.v);
    const int ib = i - (b.v - r.v);
    r.c[i] = (ia >= 0 ? a.c[ia] : 0) + (ib >= 0 ? s * b.c[ib] : 0);
  }
  return r;
}

long double FactorialL(int n) {
  long double r = 1;
  for (int i = 2; i <= n; ++i) r *= i;
  return r;
}

// gamma[k][j], k = 1 .. d-1, j = 0 .. kTerms - 1.
void HistoryGammas(int d, const sunrealtype* p, long double (*gamma)[kTerms]) {
  Laurent u;  // e^s - 1
  u.v = 1;
  for (int i = 0; i < kTerms; ++i) u.c[i] = 1 / FactorialL(i + 1);
  const Laurent uinv = Inv(u);
  Laurent R[kMaxDegree];
  R[d - 1].c[0] = 1;
  for (int k = d - 2; k >= 1; --k) {
    Laurent acc;  // (p_k (e^s - 1) + 1) / (d-1-k)!
    acc.c[0] = 1 / FactorialL(d - 1 - k);
    for (int i = 1; i < kTerms; ++i) acc.c[i] = p[k] / FactorialL(i) / FactorialL(d - 1 - k);
    for (int i = 1; i <= d - 2 - k; ++i) acc = AddScaled(acc, 1 / FactorialL(i), R[k + i]);
    R[k] = Mul(acc, uinv);
  }
  const Laurent r2inv = Inv(R[2]);
  for (int k = 1; k < d; ++k) {
    const Laurent q = Mul(R[k], r2inv);
    for (int j = 0; j < kTerms; ++j) {
      const int i = (k - 2 + j) - q.v;  // the coefficient of s^(k-2+j)
      gamma[k][j] = i >= 0 && i < kTerms ? q.c[i] : 0;
    }
  }
}

// C_{p+1}: one step of size 1 from the exact consistent history of y = t^q / q!, q = p + 1, less
// the exact y(1).
sunrealtype ErrorConstant(int d, const sunrealtype* p, int order,
                          const long double (*gamma)[kTerms]) {
  const int q = order + 1;
  const auto y = [q](int k, long double t) -> long double {
    return k > q ? 0 : std::pow(t, q - k) / FactorialL(q - k);
  };
  StepCoeffs co;
  ComputeStepCoeffs(d, p, 1, &co);
  long double D[kMaxDegree] = {};
  for (int k = 1; k < d; ++k) {
    for (int j = 0; k + j <= q && j < kTerms; ++j) D[k] += gamma[k][j] * y(k + j, -1);
  }
  const long double a = y(2, 0);
  long double B[kMaxDegree] = {};
  for (int k = 1; k <= d - 2; ++k) {
    for (int j = 1; j < d; ++j) B[k] += co.T[k][j] * D[j];
  }
  const long double z = d == 3 ? a : (a - B[2]) / co.c[2];
  long double x1 = y(0, 0) + co.wz_old * D[d - 1] + co.wz_new * z;
  for (int i = 1; i <= d - 2; ++i) x1 += co.w[i] * (i == 2 ? a : B[i] + co.c[i] * z);
  return static_cast<sunrealtype>(x1 - y(0, 1));
}

bool AllocAdaptRecord(CEodeMemRec* ce) {
  if (ce->adapt == nullptr) ce->adapt.reset(new (std::nothrow) AdaptMem);
  StepOptionsChanged(ce);
  return ce->adapt != nullptr;
}

// The controller's constants: a PI controller or the filter H211b of Soderlind (b = 4), aiming at
// an error norm of kTarget, with ratios in [kEtaMin, kEtaMax], on the envelope kEnvelope.
constexpr sunrealtype kTarget = 0.5;
constexpr sunrealtype kFilterB = 4;
constexpr sunrealtype kEtaMin = 0.2;
constexpr sunrealtype kEtaMax = 2;
constexpr sunrealtype kStableSafety = 0.9;
constexpr sunrealtype kEnvelope = 0.85;
constexpr sunrealtype kSunSafety = 0.9;
// The band of ratios that keep h is CEodeSetFixedStepBounds' [hold_lb, hold_ub] (AdaptMem); the
// controllers' fast path compares their exponent with the band's logarithms, narrowed by kMargin,
// far beyond the rounding of exp and log, so that an exponent inside it is a ratio inside the band.
constexpr sunrealtype kMargin = 1e-9;

// exp(x) (times 0.9 with the PI controller), or 1 for an x whose ratio the band holds anyway:
// most steps keep their size, and then no exp is taken.
sunrealtype RatioOfExponent(const AdaptMem& am, sunrealtype x, bool pi) {
  if (pi) return x > am.xhold[0] && x < am.xhold[1] ? 1 : 0.9 * std::exp(x);
  return x > am.xhold[2] && x < am.xhold[3] ? 1 : std::exp(x);
}

// The default band, measured (docs/theory.md 12.3): [0.97, 1.5], 1.5 as ARKODE's, up to degree
// 6; [0.95, 1.1] for degrees 7 and 8. Under the PI controller a band leaves the error norm free to
// wander by (ub / lb)^((p + 1) / 0.7) before h changes: 11 for [0.97, 1.2] at p = 7, with which the
// held steps sit differently from one tolerance to the next and G7_O7's global error on the
// pendulum follows the tolerance with slope 1.24; 5.3 for [0.95, 1.1], with which the slopes of
// G7_O7 and G8_O8 on the pendulum and Kepler lie within 0.95 .. 1.13 for every bottom from 0.93 to
// 0.96, with fewer f on Kepler. With a top of 1.5 G7_O7 leaves Kepler's orbit at loose tolerances.
constexpr sunrealtype kHoldLowLow = 0.97;
constexpr sunrealtype kHoldLowHigh = 0.95;
constexpr sunrealtype kHoldHighLow = 1.5;
constexpr sunrealtype kHoldHighHigh = 1.1;

// The fast path's margin inside the band's exponents (BandKeepsStep): above the exponents' error,
// 1.5 kApproxLogError / k (PI, k >= 2) and kApproxLogError / (2 k) (H211b).
constexpr sunrealtype kKeepSlack = 1e-4;

// The run's band: the user's (hold_lb, hold_ub; 0: the default for degree d), its top lowered to
// the remap's growth bound (a step that the bound clips is not held), and its exponents for both
// controllers, also less the fast path's margin.
void HoldBand(AdaptMem* am, int d) {
  const bool high = d > 6;
  const sunrealtype ub = am->hold_ub > 0 ? am->hold_ub : (high ? kHoldHighHigh : kHoldHighLow);
  am->hold_lo = am->hold_lb > 0 ? am->hold_lb : (high ? kHoldLowHigh : kHoldLowLow);
  am->hold_hi = std::min(ub, am->eta_grow);
  const sunrealtype lo = std::log(am->hold_lo), hi = std::log(am->hold_hi), l9 = std::log(0.9);
  am->xhold[0] = lo - l9 + kMargin;
  am->xhold[1] = hi - l9 - kMargin;
  am->xhold[2] = lo + kMargin;
  am->xhold[3] = hi - kMargin;
  for (int i = 0; i < 4; ++i) am->xkeep[i] = am->xhold[i] + (i % 2 == 0 ? kKeepSlack : -kKeepSlack);
}

// SUNDIALS 7: the ratio from the user's SUNAdaptController for an accepted step of hbase with
// error norm err, which it is told of (UpdateH); false without one or when it fails (CEODE's
// own controller decides then).
bool SunControllerRatio(CEodeMemRec* ce, sunrealtype err, sunrealtype hbase, sunrealtype* eta) {
#if SUNDIALS_VERSION_MAJOR >= 7
  auto* C = static_cast<SUNAdaptController>(ce->adapt->sun_controller);
  if (C == nullptr) return false;
  sunrealtype hnew = 0;
  if (SUNAdaptController_EstimateStep(C, hbase, ce->adapt->set.order, err, &hnew) != SUN_SUCCESS ||
      SUNAdaptController_UpdateH(C, hbase, err) != SUN_SUCCESS || !(hnew > 0) ||
      !std::isfinite(hnew)) {
    return false;
  }
  *eta = kSunSafety * hnew / hbase;  // SUNDIALS' controllers aim at an error norm of 1
  return true;
#else
  (void)ce, (void)err, (void)hbase, (void)eta;
  return false;
#endif
}

}  // namespace

void ComputeSetCoefficients(int d, const sunrealtype* params, SetCoefficients* sc) {
  long double gamma[kMaxDegree][kTerms] = {};
  HistoryGammas(d, params, gamma);
  int ox = 0;
  int ov = 0;
  if (const MethodSet* named = NamedSetWithParams(d, params)) {
    ox = named->order_x;  // the table's: the order conditions are not solved again
  } else {
    MethodOrders(d, params, &ox, &ov, nullptr, nullptr);
  }
  *sc = SetCoefficients{};
  sc->order = std::max(1, std::min(ox, d));
  sc->cerr = ErrorConstant(d, params, sc->order, gamma);
  for (int k = 1; k < d; ++k) {
    if (k == 2) continue;  // D_2 is the acceleration itself
    for (int j = 1; k + j <= d; ++j) {
      if (std::fabs(gamma[k][j]) > 1e-10L) {
        sc->remap[sc->nremap++] = {k, j, static_cast<sunrealtype>(gamma[k][j])};
      }
    }
  }
  for (int k = 0; k < d; ++k) {
    for (int l = 0; l < kGammaTerms; ++l) sc->gamma[k][l] = static_cast<sunrealtype>(gamma[k][l]);
  }
}

bool AdaptEnabled(const CEodeMemRec* ce) { return ce->adapt->on; }

namespace {

// GuardStableStep's value, kept with the inputs it came from.
__attribute__((noinline)) sunrealtype StableStepAgain(CEodeMemRec* ce) {
  AdaptMem& am = *ce->adapt;
  am.hs_value = GuardStableStep(ce, kStableSafety);
  am.hs_omega = ce->guard.omega_est;
  am.hs_limit = ce->guard.omega_limit;  // after the call: the limit is looked up on first use
  am.hs_kept = true;
  return am.hs_value;
}

}  // namespace

sunrealtype AdaptStableStep(CEodeMemRec* ce) {
  if (!GuardOn(ce)) return SUN_BIG_REAL;
  const AdaptMem& am = *ce->adapt;
  if (am.hs_kept && GuardStableStepInputsAre(ce, am.hs_omega, am.hs_limit)) return am.hs_value;
  return StableStepAgain(ce);
}

int AdaptWeightsDefined(CEodeMemRec* ce, sunrealtype dmin, const char* func) {
  if (dmin > 0) return CE_SUCCESS;
  return ProcessError(ce, CE_ILL_INPUT, func,
                      "An error weight is not defined at t = %.17g: some x_i = 0 where its "
                      "abstol is 0. Give abstol > 0 for every entry.",
                      static_cast<double>(ce->tcur));
}

int AdaptWeights(CEodeMemRec* ce, N_Vector x, const char* func) {
  AdaptMem& am = *ce->adapt;
  if (am.tol_kind == 2) {
    if (am.efun(x, am.ewt, ce->user_data) != 0) {
      return ProcessError(ce, CE_ILL_INPUT, func,
                          "The error weight function (CEodeWFtolerances) failed at t = %.17g.",
                          static_cast<double>(ce->tcur));
    }
  } else {
    const sunrealtype dmin =
        am.kernels.Weights(x, am.rtol, am.atol, am.tol_kind == 1 ? am.atol_vec : nullptr, am.ewt);
    return AdaptWeightsDefined(ce, dmin, func);
  }
  if (!(N_VMin(am.ewt) > 0) || !IsFinite(am.ewt)) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "The error weight function returned a weight that is not positive and "
                        "finite at t = %.17g.",
                        static_cast<double>(ce->tcur));
  }
  return CE_SUCCESS;
}

namespace {

int AllocAdaptVectors(CEodeMemRec* ce, const char* func) {
  AdaptMem& am = *ce->adapt;
  const bool ahead = am.kernels.serial;  // the next position in the serial pass after f
  bool ok =
      CloneMissing(&am.ewt, ce->xcur) && CloneMissing(&am.ewt_next, ce->xcur) &&
      (!ahead || (CloneMissing(&am.ewt_spec, ce->xcur) && CloneMissing(&am.xspec, ce->xcur))) &&
      CloneMissing(&am.ele, ce->xcur) && CloneMissing(&am.est, ce->xcur) &&
      CloneMissing(&am.yd, ce->xcur) && CloneMissing(&am.yd_next, ce->xcur);
  if (ok) N_VConst(0, am.ele);
  for (int b = 0; b < 2; ++b) {
    for (int j = 1; ok && j <= std::max(1, am.set.order - 1); ++j)
      ok = CloneMissing(&am.dd[b][j], ce->xcur);
  }
  return ok ? CE_SUCCESS : ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
}

// The first step from the initial data when the user gave none: the order-p error model with
// every derivative scaled by the problem's time scale tau (from ||x||, ||v||, ||a|| in the
// error weights), aiming at half the tolerance; at most a tenth of the distance to tout. A first
// step that fails its error test starts the method again with a smaller one (AdaptEvolve), so
// that the start's stencils are spaced for the step the run takes.
sunrealtype InitialStep(CEodeMemRec* ce, sunrealtype span) {
  const AdaptMem& am = *ce->adapt;
  const sunrealtype nx = N_VWrmsNorm(ce->xcur, am.ewt);
  const sunrealtype nv = N_VWrmsNorm(ce->D[1], am.ewt);
  const sunrealtype na = N_VWrmsNorm(ce->D[2], am.ewt);
  // A zero norm says nothing about the time scale (a start at the origin or at rest), so only the
  // ratios of nonzero norms count; with neither x nor v, the time a reaches the tolerance's scale.
  sunrealtype tau = SUN_BIG_REAL;
  if (nx > 0 && nv > 0) tau = std::min(tau, nx / nv);
  if (nx > 0 && na > 0) tau = std::min(tau, std::sqrt(nx / na));
  if (nv > 0 && na > 0) tau = std::min(tau, nv / na);
  if (tau == SUN_BIG_REAL && na > 0) tau = std::sqrt(2 / na);
  const int p = am.set.order;
  sunrealtype h = 0.1 * span;
  if (tau > 0 && tau < SUN_BIG_REAL) {
    const sunrealtype top = std::max(
        {na * std::pow(tau, -(p - 1)), nv * std::pow(tau, -p), nx * std::pow(tau, -(p + 1))});
    const sunrealtype c = std::max(std::fabs(am.set.cerr), SUN_UNIT_ROUNDOFF);
    if (top > 0) h = std::min(h, std::pow(kTarget / (c * top * am.err_scale), 1.0 / (p + 1)));
  }
  return h;
}

// The largest growth of a step under the remap (docs/theory.md 12.5). The remap moves D_k,
// 3 <= k <= d - 2, by gamma_kj (r^j - 1) h^j yd, and yd, the top derivative's rate, carries the
// parasitic modes of the history: a step growing by r = 1 + eps feeds them back with a gain of
// about c eps, c = sum_j j |gamma_kj|, while they lose only 2 % a step (modulus 0.98). The bound 1
// + kCouplingMargin / c keeps that gain below the loss; without such terms (G3_CD, G4_A34) or with
// the refresh (degree >= 6) it is kEtaMax. G5_O4 (gamma_32 = -3.2): 1.01.
constexpr sunrealtype kCouplingMargin = 0.065;
sunrealtype GrowthBound(int d, const RemapTerm* remap, int nremap) {
  sunrealtype c = 0;
  for (int i = 0; i < nremap; ++i) {
    if (remap[i].k >= 3 && remap[i].k <= d - 2) c += remap[i].j * std::fabs(remap[i].gamma);
  }
  return c > 0 ? std::min(kEtaMax, 1 + kCouplingMargin / c) : kEtaMax;
}

// What a run keeps between steps: none of it carries over a start. The fields of the step's
// passes that stay for the run are set here (ceode_adapt_step.cpp fills the others each step).
void ClearRun(CEodeMemRec* ce) {
  AdaptMem* am = ce->adapt.get();
  am->wkind = am->tol_kind == 0
                  ? AdaptAfterF::kWeightsScalar
                  : (am->tol_kind == 1 ? AdaptAfterF::kWeightsVector : AdaptAfterF::kWeightsNone);
  const bool positive = am->tol_kind == 0 ? am->atol > 0 : am->atol_min > 0;
  am->after.d = ce->degree;
  am->after.positive = am->pos.positive = positive;
  am->after.rtol = am->pos.rtol = am->rtol;
  am->after.atol = am->pos.atol = am->atol;
  am->after.atolv = am->pos.atolv = am->atol_vec;
  am->first = true;
  for (int b = 0; b < 2; ++b) {  // the serial pass's differences (only NVECTOR_SERIAL there)
    for (int j = 0; j < kMaxDegree; ++j) {
      const N_Vector v = am->dd[b][j];
      am->dd_data[b][j] = am->kernels.serial && v != nullptr ? NV_DATA_S(v) : nullptr;
    }
  }
  am->plan_h[0] = am->plan_h[1] = 0;  // the vectors may have been cloned again
  am->plan_key[0] = am->plan_key[1] = nullptr;
  am->hist_key[0] = am->hist_key[1] = nullptr;
  // The method or the start's coefficients may be new, and the backend (CEodeSetFusedKernel).
  am->cw_h = am->est_h = am->pos_h = am->spec_h = am->shape_h = 0;
  am->spec_ready = false;
  am->after.fused_key = am->pos.fused_key = -1;
  am->ewt_next_ready = false;
}

// A named set's SetCoefficients, computed once for the process: they depend on the table's
// parameters alone, and every run of a set (each start, each new memory) needs them.
const SetCoefficients& NamedSetCoefficients(const MethodSet& m) {
  struct Entry {
    std::once_flag once;
    SetCoefficients sc;
  };
  static const std::unique_ptr<Entry[]> cache(new Entry[NumMethodSets()]);
  Entry& e = cache[&m - &MethodSetAt(0)];
  std::call_once(e.once, [&m, &e] { ComputeSetCoefficients(m.degree, m.params.data(), &e.sc); });
  return e.sc;
}

// The method's SetCoefficients into am.set, unless they are those of the method already (a new
// start of the same method).
void SetCoefficientsOfMethod(const CEodeMemRec* ce, AdaptMem* am) {
  const int d = ce->degree;
  if (am->set_degree == d && std::equal(ce->params, ce->params + d - 1, am->set_params)) return;
  am->set_degree = 0;  // until the coefficients are complete (an exception leaves none)
  if (const MethodSet* named = NamedSetWithParams(d, ce->params)) {
    am->set = NamedSetCoefficients(*named);
  } else {
    ComputeSetCoefficients(d, ce->params, &am->set);
  }
  std::copy(ce->params, ce->params + d - 1, am->set_params);
  am->set_degree = d;
}

// The method's error, remap and refresh coefficients (at each start: the method may have changed).
int MethodCoefficients(CEodeMemRec* ce, const char* func) {
  AdaptMem& am = *ce->adapt;
  try {
    SetCoefficientsOfMethod(ce, &am);
  } catch (...) {
    return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
  }
  am.pfac = Factorial(am.set.order - 1);
  am.refresh = ce->degree >= 6 && !HasConstraints(ce);
  RefreshTables(&am, ce->degree);
  am.eta_grow = am.refresh ? kEtaMax : GrowthBound(ce->degree, am.set.remap, am.set.nremap);
  HoldBand(&am, ce->degree);
  return CE_SUCCESS;
}

int CollapseError(CEodeMemRec* ce, const char* func, sunrealtype h) {
  const AdaptMem& am = *ce->adapt;
  return ProcessError(ce, CE_ERR_FAILURE, func,
                      "The error test kept failing and the step fell to h = %g at t = %.17g: "
                      "the tolerances (rtol = %g, atol = %g) lie below the round-off the "
                      "solution attains here; loosen them.",
                      static_cast<double>(h), static_cast<double>(ce->tcur),
                      static_cast<double>(am.rtol),
                      static_cast<double>(am.tol_kind == 0 ? am.atol : am.atol_min));
}

}  // namespace

int AdaptStart(CEodeMemRec* ce, const char* func, bool* accel) {
  *accel = false;
  AdaptMem& am = *ce->adapt;
  int flag = MethodCoefficients(ce, func);
  if (flag != CE_SUCCESS) return flag;
  sunrealtype tol = am.tol_kind == 2 ? 1 : am.rtol;
  if (am.tol_kind == 0 && tol == 0) tol = am.atol;
  if (am.tol_kind == 1 && tol == 0) tol = N_VMaxNorm(am.atol_vec);
  am.err_scale = std::pow(std::min<sunrealtype>(tol, 1), -1.0 / am.set.order);
  const bool serial = FusedKernelOn(ce) && N_VGetVectorID(ce->xcur) == SUNDIALS_NVEC_SERIAL &&
                      (am.tol_kind != 1 || N_VGetVectorID(am.atol_vec) == SUNDIALS_NVEC_SERIAL);
  am.kernels = {serial, ce->n};
  flag = AllocAdaptVectors(ce, func);
  if (flag == CE_SUCCESS) flag = AdaptWeights(ce, ce->xcur, func);
  if (flag != CE_SUCCESS) return flag;
  ClearRun(ce);
#if SUNDIALS_VERSION_MAJOR >= 7
  if (am.sun_controller != nullptr) {
    SUNAdaptController_Reset(static_cast<SUNAdaptController>(am.sun_controller));
  }
#endif
  am.capped_last = false;
  am.nst_refresh = ce->nst;
  am.err = am.err_prev = 0;
  am.eta_prev = 1;
  am.hlast = 0;
  am.hprev = 0;
  sunrealtype h = am.h_restart > 0 ? am.h_restart : am.hin;
  am.h_restart = 0;
  const bool after_failures = am.fail_restart;
  am.fail_restart = false;
  if (h == 0) {
    // The constrained acceleration needs the start's own solve (M may be singular): the first
    // step then comes from x and v alone.
    if (HasConstraints(ce)) {
      N_VConst(0, ce->D[2]);
    } else {
      flag = EvalAccel(ce, ce->tcur, ce->xcur, ce->D[1], ce->D[2], func);
      *accel = flag == CE_SUCCESS;
    }
    if (flag != CE_SUCCESS) return flag;
    const sunrealtype span = std::fabs(am.tout_hint - ce->tcur);
    h = InitialStep(ce, span > 0 ? span : 1);
  }
  if (am.hmax > 0) h = std::min(h, am.hmax);
  h = std::max(h, am.hmin);
  if (after_failures && !(ce->tcur + h > ce->tcur)) return CollapseError(ce, func, h);
  if (!(h > 0) || !std::isfinite(h) || !(ce->tcur + h > ce->tcur)) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "No usable first step (h = %g at t = %.17g): give one with "
                        "CEodeSetInitStep.",
                        static_cast<double>(h), static_cast<double>(ce->tcur));
  }
  ce->h = h;
  am.h0 = h;
  am.hmap = h;
  am.h_plan = h;
  return CE_SUCCESS;
}

// With constraints the velocity is a difference quotient of positions solved to round-off: it
// carries about eps |x| / h. Once that is far above the velocity's own tolerance scale (rtol |v|
// + atol), a smaller step only adds round-off; the error estimate, which meets the same round-off
// in the position solve, keeps asking for one, and the step would fall to the round-off of t.
constexpr sunrealtype kVelocityRoundOff = 100;
int AdaptCheckVelocityRoundOff(CEodeMemRec* ce, sunrealtype h, const char* func) {
  const AdaptMem& am = *ce->adapt;
  if (am.tol_kind == 2) return CE_SUCCESS;  // the user's weights: no velocity scale to compare
  const sunrealtype atol = am.tol_kind == 0 ? am.atol : am.atol_min;
  const sunrealtype xmax = N_VMaxNorm(ce->xcur);
  const sunrealtype vscale = am.rtol * N_VMaxNorm(ce->D[1]) + atol;
  if (SUN_UNIT_ROUNDOFF * xmax <= kVelocityRoundOff * vscale * h) return CE_SUCCESS;
  return ProcessError(ce, CE_ERR_FAILURE, func,
                      "The step fell to h = %g at t = %.17g, where the velocity's round-off "
                      "(eps |x| / h = %g) exceeds its tolerance scale (rtol |v| + atol = %g) "
                      "%g times: the tolerances (rtol = %g, atol = %g) lie below what the "
                      "constrained solve attains here; loosen them.",
                      static_cast<double>(h), static_cast<double>(ce->tcur),
                      static_cast<double>(SUN_UNIT_ROUNDOFF * xmax / h),
                      static_cast<double>(vscale), static_cast<double>(kVelocityRoundOff),
                      static_cast<double>(am.rtol), static_cast<double>(atol));
}

void AdaptStartHistory(CEodeMemRec* ce) {
  AdaptMem& am = *ce->adapt;
  const int d = ce->degree;
  // The start's derivatives at t0 are a's Taylor coefficients there: t0 counts d - 2 times in the
  // divided differences (a, a', ..., a^(d-3)); the zero start has only a.
  const int mult = ce->zero_start ? 1 : d - 2;
  am.cur = 0;
  for (int j = 1; j <= am.set.order - 2; ++j) {
    if (j < mult) N_VScale(1 / Factorial(j), ce->D[j + 2], am.dd[0][j]);
  }
  am.ndata = mult;
  for (sunrealtype& t : am.tnode) t = ce->tcur;
  N_VConst(0, am.yd);
}

sunrealtype AdaptRetryStep(const CEodeMemRec* ce, sunrealtype err) {
  const AdaptMem& am = *ce->adapt;
  const sunrealtype k = am.set.order + 1;
  sunrealtype eta = std::isfinite(err) ? 0.9 * std::pow(err, -1 / k) : 0.25;
  eta = std::min(0.9, std::max(kEtaMin, eta));
  return std::max(ce->h * eta, am.hmin);
}

namespace {

// The tests' hook (CEodeSetStepSchedule): its step instead of h, unless the step cannot take it
// (not finite, not positive, too small to advance t or to divide by).
sunrealtype ScheduledStep(const CEodeMemRec* ce, sunrealtype h) {
  const AdaptMem& am = *ce->adapt;
  if (am.schedule == nullptr) return h;
  const sunrealtype given = am.schedule(ce->tcur, ce->nst, am.schedule_data);
  return given > 0 && std::isfinite(1 / given) && ce->tcur + given > ce->tcur ? given : h;
}

}  // namespace

namespace {

// log(v) within kApproxLogError, for the controller's decision only (v >= 1e-10 finite): the
// binary exponent from the bits and the log of the mantissa m in [sqrt(1/2), sqrt(2)) by the
// series 2 atanh(s), s = (m - 1) / (m + 1), |s| < 0.1716, to s^3 (the rest below 6.2e-5). Other
// types than IEEE double, and v beyond 1e300, take std::log.
constexpr sunrealtype kApproxLogError = 1e-4;
sunrealtype ApproxLog(sunrealtype v) {
  if constexpr (sizeof(sunrealtype) == sizeof(std::uint64_t) &&
                std::numeric_limits<sunrealtype>::is_iec559) {
    if (!(v < 1e300)) return std::log(v);
    std::uint64_t u = 0;
    std::memcpy(&u, &v, sizeof u);
    int e = static_cast<int>(u >> 52) - 1023;  // v > 0: no sign bit
    u = (u & 0x000fffffffffffffULL) | 0x3ff0000000000000ULL;
    sunrealtype m = 0;
    std::memcpy(&m, &u, sizeof m);
    if (m > 1.4142135623730951) {
      m *= 0.5;
      ++e;
    }
    const sunrealtype s = (m - 1) / (m + 1);
    return e * 0.6931471805599453 + 2 * s * (1 + s * s * (1.0 / 3));
  } else {
    return std::log(v);
  }
}

// Whether the controller keeps h, decided from logarithms within kApproxLogError of
// log(err / target) (le) and of the last step's (lep): only when the exponent lies inside the band
// by more than what their error can move it, so that the exact logarithms decide the same; false
// leaves the decision to them (and to the user's SUNAdaptController when there is one).
bool BandKeepsStep(const AdaptMem& am, sunrealtype le, sunrealtype lep, sunrealtype k) {
  if (am.sun_controller != nullptr) return false;
  if (am.controller == CE_ADAPT_PI) {
    const sunrealtype x = (-0.7 * le + 0.4 * (lep - le)) / k;
    return x > am.xkeep[0] && x < am.xkeep[1];
  }
  if (am.eta_prev != 1) return false;  // H211b with log(eta_prev) != 0
  const sunrealtype x = -(le + lep) / (kFilterB * k);
  return x > am.xkeep[2] && x < am.xkeep[3];
}

// The exact log(err_prev / target), which the last step did not take.
sunrealtype PrevLog(const AdaptMem& am) { return std::log(std::max(am.err_prev, 1e-10) / kTarget); }

// The controller's ratio from exact logarithms (the band's fast path did not decide): le of
// v = err / target, lep the last step's (had_prev: there was one). Out of line: the step that
// keeps h runs without its calls (log, exp, the user's controller) and the registers they need.
__attribute__((noinline)) sunrealtype ExactRatio(CEodeMemRec* ce, sunrealtype err,
                                                 sunrealtype hbase, sunrealtype v, bool had_prev) {
  AdaptMem& am = *ce->adapt;
  const sunrealtype k = am.set.order + 1;
  const sunrealtype le = std::log(v);
  const sunrealtype lep = !had_prev ? le : (am.lerr_prev_exact ? am.lerr_prev : PrevLog(am));
  am.lerr_prev_approx = le;
  am.lerr_prev_exact = true;
  sunrealtype eta = 1;
  if (SunControllerRatio(ce, err, hbase, &eta)) {
    // the user's SUNAdaptController chose
  } else if (am.controller == CE_ADAPT_PI) {
    eta =
        RatioOfExponent(am, (-0.7 * le + 0.4 * (lep - le)) / k, true);  // e^(-0.7/k) (ep/e)^(0.4/k)
  } else {
    const sunrealtype lr = am.eta_prev == 1 ? 0 : std::log(am.eta_prev);
    eta = RatioOfExponent(am, -(le + lep) / (kFilterB * k) - lr / kFilterB, false);
  }
  am.err_prev = err;
  am.lerr_prev = le;
  return eta;
}

// The error norm the controller reads: err, or the envelope of the last ones (kEnvelope a step).
sunrealtype Enveloped(const AdaptMem& am, sunrealtype err) {
  // y^(p+1) has zeros where the estimate dips although the error of a longer step would not; the
  // controller reads a value that falls by at most kEnvelope a step (the test itself uses the
  // estimate).
  if (am.err_prev > 0) {
    sunrealtype grow = 1;  // eta_prev^(p+1)
    if (am.eta_prev != 1) {
      for (int i = 0; i <= am.set.order; ++i) grow *= am.eta_prev;
    }
    err = std::max(err, kEnvelope * am.err_prev * grow);
  }
  return err;
}

// The controller's ratio from the error norm err of the last accepted step of hbase.
sunrealtype ControllerRatio(CEodeMemRec* ce, sunrealtype err, sunrealtype hbase) {
  AdaptMem& am = *ce->adapt;
  const sunrealtype k = am.set.order + 1;
  err = Enveloped(am, err);
  if (err == 0) {
    // An estimate of exactly 0 (x'' = 0, a solution polynomial of degree below p + 1): no error
    // to aim at, so the step grows by the largest ratio, as CVODE's eta = etamax.
    return kEtaMax;
  }
  // In logarithms: one log and one exp a step instead of two pow calls, and neither while the
  // bounded approximation decides that the band keeps h (BandKeepsStep).
  const sunrealtype v = std::max(err, 1e-10) / kTarget;
  const sunrealtype le_approx = ApproxLog(v);
  const bool had_prev = am.err_prev > 0;
  const sunrealtype lep_approx = had_prev ? am.lerr_prev_approx : le_approx;
  am.lerr_prev_approx = le_approx;
  if (BandKeepsStep(am, le_approx, lep_approx, k)) {
    am.err_prev = err;
    am.lerr_prev_exact = false;
    return 1;
  }
  return ExactRatio(ce, err, hbase, v, had_prev);
}

// ControllerRatio's verdict and effects when the band keeps h (true); false leaves the record as
// it was, for ControllerRatio to decide. Without calls, so that the step that keeps h runs
// without saving registers for them.
bool KeepsStep(AdaptMem& am, sunrealtype err) {
  err = Enveloped(am, err);
  if (err == 0) return false;
  const sunrealtype le_approx = ApproxLog(std::max(err, 1e-10) / kTarget);
  const sunrealtype lep_approx = am.err_prev > 0 ? am.lerr_prev_approx : le_approx;
  if (!BandKeepsStep(am, le_approx, lep_approx, am.set.order + 1)) return false;
  am.lerr_prev_approx = le_approx;
  am.err_prev = err;
  am.lerr_prev_exact = false;
  return true;
}

// The step hbase * eta within hmax, the stable step, hmin and the stop time limit_t (from tfrom).
__attribute__((always_inline)) inline sunrealtype BoundedStep(CEodeMemRec* ce, sunrealtype h,
                                                              sunrealtype tfrom,
                                                              sunrealtype limit_t, bool* capped) {
  const AdaptMem& am = *ce->adapt;
  if (am.hmax > 0) h = std::min(h, am.hmax);
  const sunrealtype hs = AdaptStableStep(ce);
  *capped = h > hs;
  if (*capped) h = hs;
  h = std::max(h, am.hmin);
  // On the limit itself (a stop time just reached) the step stays the controller's: the next
  // CEodeEvolve cuts it to its own stop time.
  const sunrealtype rem = limit_t - tfrom;
  if (rem > 0 && rem < 2 * h) {  // one test while the limit is far (h > 0)
    // lands on the limit (a stretch of at most 1e-4), or two even steps instead of a sliver
    h = rem <= h * (1 + 1e-4) ? rem : rem / 2;
  }
  return h;
}

// AdaptNextStep where the band's fast path does not keep h (or a schedule decides).
__attribute__((noinline)) sunrealtype NextStepAnyRatio(CEodeMemRec* ce, sunrealtype err,
                                                       sunrealtype hbase, sunrealtype tfrom,
                                                       sunrealtype limit_t, bool* capped) {
  AdaptMem& am = *ce->adapt;
  // Without an estimate (the history is still too short) the step stays.
  sunrealtype eta = AdaptEstimated(am) ? ControllerRatio(ce, err, hbase) : 1;
  // Small changes are not made: a step kept costs no new coefficients, plans or remap, and
  // fewer changes excite the high-degree sets' parasitic roots less (docs/theory.md 12.5). A step
  // grows by at most the remap's bound (GrowthBound), unless the estimate is exactly 0 (nothing
  // for the remap to carry).
  // (A ratio of 1, the band's usual verdict, passes both unchanged: hold_lo <= 1 <= the growth.)
  if (eta != 1) {
    const sunrealtype grow = AdaptEstimated(am) && err == 0 ? kEtaMax : am.eta_grow;
    if (eta >= am.hold_lo && eta <= std::min(am.hold_hi, grow)) eta = 1;
    eta = std::min(grow, std::max(kEtaMin, eta));
  }
  const sunrealtype hold = hbase;
  const sunrealtype h = BoundedStep(ce, ScheduledStep(ce, hold * eta), tfrom, limit_t, capped);
  am.eta_prev = h / hold;
  return h;
}

}  // namespace

sunrealtype AdaptNextStep(CEodeMemRec* ce, sunrealtype err, sunrealtype hbase, sunrealtype tfrom,
                          sunrealtype limit_t, bool* capped) {
  AdaptMem& am = *ce->adapt;
  // Most steps: the band keeps h (hbase * 1 is hbase), and no schedule replaces it.
  if (AdaptEstimated(am) && am.schedule == nullptr && KeepsStep(am, err)) {
    const sunrealtype h = BoundedStep(ce, hbase, tfrom, limit_t, capped);
    am.eta_prev = h / hbase;
    return h;
  }
  return NextStepAnyRatio(ce, err, hbase, tfrom, limit_t, capped);
}

bool AdaptKeepsStep(CEodeMemRec* ce, sunrealtype err) { return KeepsStep(*ce->adapt, err); }

void AdaptFree(CEodeMemRec* ce) {
  if (ce->adapt == nullptr) return;
  AdaptMem& am = *ce->adapt;
  N_Vector* vs[] = {&am.ewt, &am.ewt_next, &am.ewt_spec, &am.xspec,   &am.ele,
                    &am.est, &am.yd,       &am.yd_next,  &am.atol_vec};
  for (N_Vector* v : vs) {
    if (*v != nullptr) N_VDestroy(*v);
    *v = nullptr;
  }
  for (auto& buf : am.dd) {
    for (N_Vector& v : buf) {
      if (v != nullptr) N_VDestroy(v);
      v = nullptr;
    }
  }
  if (am.tol_kind == 1) am.on = false;  // the abstol vector went with the problem's size
}

void AdaptReset(CEodeMemRec* ce, bool counters) {
  if (ce->adapt == nullptr || !counters) return;
  ce->adapt->netf = ce->adapt->ncapped = 0;
}

void AdaptKeepStep(CEodeMemRec* ce) {
  AdaptMem* am = ce->adapt.get();
  if (am != nullptr && am->on && am->hlast > 0 && ce->h > 0) am->h_restart = ce->h;
}

void AdaptSetTarget(CEodeMemRec* ce, sunrealtype tout) {
  if (ce->adapt != nullptr) ce->adapt->tout_hint = tout;
}

void AdaptDisable(CEodeMemRec* ce) {
  if (ce->adapt != nullptr) ce->adapt->on = false;
}

}  // namespace ceode

using ceode::Access;
using ceode::AdaptMem;
using ceode::ProcessError;

namespace {

// The record for a setter, created on first use.
int AdaptAccess(void* mem, const char* func, CEodeMemRec** ce) {
  int flag = Access(mem, func, ce);
  if (flag != CE_SUCCESS) return flag;
  if (!ceode::AllocAdaptRecord(*ce)) return ProcessError(*ce, CE_MEM_FAIL, func, "Out of memory.");
  return CE_SUCCESS;
}

// Turns the adaptive step on with the weights of kind `kind`.
int EnableTolerances(CEodeMemRec* ce, int kind) {
  AdaptMem& am = *ce->adapt;
  am.tol_kind = kind;
  am.on = true;
  ceode::Restart(ce);
  return CE_SUCCESS;
}

int CheckRtol(CEodeMemRec* ce, const char* func, sunrealtype reltol) {
  if (!(reltol >= 0) || !std::isfinite(reltol)) {
    return ProcessError(ce, CE_ILL_INPUT, func, "reltol = %g: need a finite reltol >= 0.",
                        static_cast<double>(reltol));
  }
  return CE_SUCCESS;
}

}  // namespace

extern "C" {

int CEodeSStolerances(void* mem, sunrealtype reltol, sunrealtype abstol) {
  CEodeMemRec* ce = nullptr;
  int flag = AdaptAccess(mem, __func__, &ce);
  if (flag == CE_SUCCESS) flag = CheckRtol(ce, __func__, reltol);
  if (flag != CE_SUCCESS) return flag;
  if (!(abstol >= 0) || !std::isfinite(abstol) || (reltol == 0 && abstol == 0)) {
    return ProcessError(ce, CE_ILL_INPUT, __func__,
                        "abstol = %g (reltol = %g): need a finite abstol >= 0, not both zero.",
                        static_cast<double>(abstol), static_cast<double>(reltol));
  }
  ce->adapt->rtol = reltol;
  ce->adapt->atol = abstol;
  return EnableTolerances(ce, 0);
}

int CEodeSVtolerances(void* mem, sunrealtype reltol, N_Vector abstol) {
  CEodeMemRec* ce = nullptr;
  int flag = AdaptAccess(mem, __func__, &ce);
  if (flag == CE_SUCCESS) flag = CheckRtol(ce, __func__, reltol);
  if (flag != CE_SUCCESS) return flag;
  if (!ce->initialized) {
    return ProcessError(ce, CE_NO_MALLOC, __func__,
                        "A vector abstol needs the problem's size: call CEodeInit first.");
  }
  if (abstol == nullptr || N_VGetLength(abstol) != ce->n) {
    return ProcessError(ce, CE_ILL_INPUT, __func__,
                        "abstol is NULL or not of the problem's length %ld: clone it from x0.",
                        static_cast<long>(ce->n));
  }
  if (!ceode::IsFinite(abstol) || N_VMin(abstol) < 0) {
    return ProcessError(ce, CE_ILL_INPUT, __func__, "abstol has a negative or non-finite entry.");
  }
  AdaptMem& am = *ce->adapt;
  if (am.atol_vec == nullptr) am.atol_vec = ceode::CloneVector(ce->xcur);
  if (am.atol_vec == nullptr) return ProcessError(ce, CE_MEM_FAIL, __func__, "Out of memory.");
  N_VScale(1, abstol, am.atol_vec);
  am.atol_min = N_VMin(abstol);
  am.rtol = reltol;
  return EnableTolerances(ce, 1);
}

int CEodeWFtolerances(void* mem, CEodeEwtFn efun) {
  CEodeMemRec* ce = nullptr;
  int flag = AdaptAccess(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (efun == nullptr) return ProcessError(ce, CE_ILL_INPUT, __func__, "efun = NULL.");
  ce->adapt->efun = efun;
  return EnableTolerances(ce, 2);
}

int CEodeSetInitStep(void* mem, sunrealtype hin) {
  CEodeMemRec* ce = nullptr;
  int flag = AdaptAccess(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (!(hin >= 0) || !std::isfinite(hin)) {
    return ProcessError(ce, CE_ILL_INPUT, __func__,
                        "hin = %g: give a finite hin > 0, or 0 to let CEODE choose.",
                        static_cast<double>(hin));
  }
  ce->adapt->hin = hin;
  return CE_SUCCESS;
}

int CEodeSetMinStep(void* mem, sunrealtype hmin) {
  CEodeMemRec* ce = nullptr;
  int flag = AdaptAccess(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  const sunrealtype hmax = ce->adapt->hmax;
  if (!(hmin >= 0) || !std::isfinite(hmin) || (hmax > 0 && hmin > hmax)) {
    return ProcessError(ce, CE_ILL_INPUT, __func__,
                        "hmin = %g: need a finite hmin >= 0, not above hmax = %g.",
                        static_cast<double>(hmin), static_cast<double>(hmax));
  }
  ce->adapt->hmin = hmin;
  return CE_SUCCESS;
}

int CEodeSetMaxStep(void* mem, sunrealtype hmax) {
  CEodeMemRec* ce = nullptr;
  int flag = AdaptAccess(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (!(hmax >= 0) || !std::isfinite(hmax) || (hmax > 0 && hmax < ce->adapt->hmin)) {
    return ProcessError(ce, CE_ILL_INPUT, __func__,
                        "hmax = %g: need a finite hmax >= hmin (%g), or 0 for no limit.",
                        static_cast<double>(hmax), static_cast<double>(ce->adapt->hmin));
  }
  ce->adapt->hmax = hmax;
  return CE_SUCCESS;
}

int CEodeSetFixedStepBounds(void* mem, sunrealtype lb, sunrealtype ub) {
  CEodeMemRec* ce = nullptr;
  int flag = AdaptAccess(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (!(lb > 0 && lb <= 1 && ub >= 1) || !std::isfinite(ub)) {
    return ProcessError(ce, CE_ILL_INPUT, __func__,
                        "lb = %g, ub = %g: need 0 < lb <= 1 <= ub, both finite.",
                        static_cast<double>(lb), static_cast<double>(ub));
  }
  ce->adapt->hold_lb = lb;
  ce->adapt->hold_ub = ub;
  ceode::HoldBand(ce->adapt.get(),
                  ce->degree);  // for the running method (each start sets it again)
  return CE_SUCCESS;
}

int CEodeSetMaxErrTestFails(void* mem, int maxnef) {
  CEodeMemRec* ce = nullptr;
  int flag = AdaptAccess(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  ce->adapt->maxnef = maxnef > 0 ? maxnef : 7;  // as CVODE: <= 0 restores the default
  return CE_SUCCESS;
}

int CEodeSetAdaptivityMethod(void* mem, int controller) {
  CEodeMemRec* ce = nullptr;
  int flag = AdaptAccess(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (controller != CE_ADAPT_H211B && controller != CE_ADAPT_PI) {
    return ProcessError(ce, CE_ILL_INPUT, __func__,
                        "controller = %d: use CE_ADAPT_H211B or CE_ADAPT_PI.", controller);
  }
  ce->adapt->controller = controller;
  return CE_SUCCESS;
}

int CEodeMethodErrorConstant(int degree, const sunrealtype* params, int* order, sunrealtype* cerr) {
  if (degree < ceode::kMinDegree || degree > ceode::kMaxDegree || params == nullptr ||
      order == nullptr || cerr == nullptr) {
    return CE_ILL_INPUT;
  }
  for (int i = 0; i < degree - 1; ++i) {
    if (!std::isfinite(params[i])) return CE_ILL_INPUT;
  }
  try {
    ceode::SetCoefficients sc;
    ceode::ComputeSetCoefficients(degree, params, &sc);
    *order = sc.order;
    *cerr = sc.cerr;
    return std::isfinite(*cerr) ? CE_SUCCESS : CE_ILL_INPUT;
  } catch (...) {
    return CE_MEM_FAIL;
  }
}

int CEodeSetStepSchedule(void* mem, CEodeStepScheduleFn schedule, void* data) {
  CEodeMemRec* ce = nullptr;
  int flag = AdaptAccess(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  ce->adapt->schedule = schedule;
  ce->adapt->schedule_data = data;
  return CE_SUCCESS;
}

#if SUNDIALS_VERSION_MAJOR >= 7
int CEodeSetAdaptController(void* mem, SUNAdaptController C) {
  CEodeMemRec* ce = nullptr;
  int flag = AdaptAccess(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (C != nullptr && SUNAdaptController_GetType(C) != SUN_ADAPTCONTROLLER_H) {
    return ProcessError(ce, CE_ILL_INPUT, __func__,
                        "The controller is not of type SUN_ADAPTCONTROLLER_H (a single-rate "
                        "step controller).");
  }
  ce->adapt->sun_controller = C;
  return CE_SUCCESS;
}
#endif

int CEodeGetLastStep(void* mem, sunrealtype* hlast) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (hlast == nullptr) return ProcessError(ce, CE_ILL_INPUT, __func__, "hlast = NULL.");
  if (ceode::AdaptOn(ce)) {
    *hlast = ce->adapt->hlast;
  } else {
    *hlast = ce->nst > 0 ? ce->h : 0;
  }
  return CE_SUCCESS;
}

int CEodeGetActualInitStep(void* mem, sunrealtype* hinused) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (hinused == nullptr) return ProcessError(ce, CE_ILL_INPUT, __func__, "hinused = NULL.");
  *hinused = ceode::AdaptOn(ce) ? ce->adapt->h0 : ce->h;
  return CE_SUCCESS;
}

namespace {

int CopyAdaptVector(void* mem, const char* func, N_Vector out, N_Vector AdaptMem::*field,
                    const char* what) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, func, &ce, true);
  if (flag != CE_SUCCESS) return flag;
  if (out == nullptr || N_VGetLength(out) != ce->n) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "The output vector is NULL or not of the problem's length %ld.",
                        static_cast<long>(ce->n));
  }
  if (!ceode::AdaptOn(ce) || !ce->started || ce->adapt.get()->*field == nullptr) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "No error control in this run: set tolerances (CEodeSStolerances) and "
                        "call CEodeEvolve first.");
  }
  N_Vector v = ce->adapt.get()->*field;
  if (!ceode::IsFinite(v)) {
    // Zero tolerances where x_i = 0 make infinite weights; a failed step leaves its estimate.
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "The %s at t = %.17g are not finite: a weight is infinite where x_i = 0 "
                        "and abstol = 0, or the last step failed. Give abstol > 0, or start again "
                        "with CEodeReInit.",
                        what, static_cast<double>(ce->tcur));
  }
  N_VScale(1, v, out);
  return CE_SUCCESS;
}

long int AdaptCounter(const CEodeMemRec& ce, long int AdaptMem::*field) {
  return ce.adapt != nullptr ? ce.adapt.get()->*field : 0;
}

int GetAdaptCounter(void* mem, const char* func, long int* out, long int AdaptMem::*field) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, func, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (out == nullptr) return ProcessError(ce, CE_ILL_INPUT, func, "The output pointer is NULL.");
  *out = AdaptCounter(*ce, field);
  return CE_SUCCESS;
}

}  // namespace

int CEodeGetErrWeights(void* mem, N_Vector eweight) {
  return CopyAdaptVector(mem, __func__, eweight, &AdaptMem::ewt, "error weights");
}

int CEodeGetEstLocalErrors(void* mem, N_Vector ele) {
  return CopyAdaptVector(mem, __func__, ele, &AdaptMem::ele, "local error estimates");
}

int CEodeGetNumErrTestFails(void* mem, long int* netfails) {
  return GetAdaptCounter(mem, __func__, netfails, &AdaptMem::netf);
}

int CEodeGetNumStableStepLimited(void* mem, long int* ncapped) {
  return GetAdaptCounter(mem, __func__, ncapped, &AdaptMem::ncapped);
}

}  // extern "C"
