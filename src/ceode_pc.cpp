// The velocity-dependent step without a nonlinear solve (docs/theory.md section 4.3):
// prediction-correction P(EC)^k, the choice between it and the nonlinear solver
// (CE_IMPLICIT_AUTO), and the start's check that f depends on x' at all.

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include "ceode_impl.hpp"
#include "ceode_kernels.hpp"

namespace ceode {

namespace {

// AUTO takes prediction-correction while each correction shrinks the previous one at least this
// much: measured by the corrections themselves every msbj steps, by the coupling estimate
// kappa ||M^{-1} df/dv|| at the start (section 4.3). On the spinning top, the three sets stay
// stable with prediction-correction below it, and G5_TOP is unstable at h = 7e-3 (estimate 0.228).
constexpr sunrealtype kPcContractionLimit = SUN_RCONST(0.2);
// Back from the nonlinear solver only below this estimate: one power step from a kept direction
// varies by a factor 5 along the top's nutation (0.07 .. 0.34 at h = 1e-2, where
// prediction-correction is unstable); 0.05, a quarter of the contraction limit, is safe on every
// scene.
constexpr sunrealtype kPcReturnLimit = kPcContractionLimit / 4;
constexpr int kPowerSteps = 3;  // power steps of the coupling estimate (one f each)
// f changed by more than this many units of round-off of |f|: a real velocity dependence.
constexpr sunrealtype kDependenceUlps = 16;

int PCCorrections(const CEodeMemRec* ce) {
  return ce->pc.corrections > 0 ? ce->pc.corrections : ce->pc.k_default;
}

// A fixed direction with unequal entries, so that no simple structure of df/dv (dampers on
// relative velocities, a sum of columns) hides the dependence; all ones on vectors without
// local data (one process).
void ProbeDirection(N_Vector w) {
  sunrealtype* wd = N_VGetArrayPointer(w);
  if (wd == nullptr || !sun::IsLocal(w)) {
    N_VConst(1, w);
    return;
  }
  const sunindextype n = N_VGetLength(w);
  for (sunindextype i = 0; i < n; ++i) {
    wd[i] = SUN_RCONST(0.75) + SUN_RCONST(0.25) * std::sin(SUN_RCONST(1.3) * i + SUN_RCONST(0.7));
  }
}

// f evaluations of the probes and checks, counted apart from the steps' (like the guard's).
int CountedRhs(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector v, N_Vector f,
               const char* func) {
  const int rv = CallRhs(ce, t, x, v, f);
  ++ce->pc.nfe;
  if (rv != 0) {
    return ProcessError(ce, CE_RHSFUNC_FAIL, func,
                        "The right-hand side function failed (returned %d) at t = %.17g while "
                        "CEODE probed its velocity dependence or checked the contraction of "
                        "prediction-correction.",
                        rv, static_cast<double>(t));
  }
  return CE_SUCCESS;
}

// a = M^{-1} f(t, x, v) for a check inside a step, with f counted as CountedRhs counts it. M is
// the step's: its first correction evaluated it at the step's position x.
int CheckAccel(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector v, N_Vector a,
               const char* func) {
  const int flag = CountedRhs(ce, t, x, v, a, func);
  return flag == CE_SUCCESS ? MassSolve(ce, a, func) : flag;
}

// A correction after the step's first: a = M^{-1} f(t, x, v) with the M of that first one. The
// position of a step is known before its solve, so a position-dependent M is evaluated and
// factored once per step, not once per correction.
int CorrectionAccel(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector v, N_Vector a,
                    const char* func) {
  ++ce->pc.ncorr;
  const int flag = EvalRhs(ce, t, x, v, a, func);
  return flag == CE_SUCCESS ? MassSolve(ce, a, func) : flag;
}

// f(t0, x0, v0) itself (no mass solve) into fbase: the start's a0 when there is no M.
int BaseForce(CEodeMemRec* ce, N_Vector fbase, const char* func) {
  if (ce->ls.M == nullptr) {
    N_VScale(1, ce->D[2], fbase);
    return CE_SUCCESS;
  }
  return CountedRhs(ce, ce->tcur, ce->xcur, ce->D[1], fbase, func);
}

// The increment of the velocity in a directional difference at velocity v.
sunrealtype ProbeIncrement(N_Vector v) {
  return std::sqrt(SUN_UNIT_ROUNDOFF) * std::max(SUN_RCONST(1.0), N_VMaxNorm(v));
}

// u = (f(t, x, v + sig w) - fbase) / sig for w with max |w_i| = 1: df/dv w (vp: scratch).
int DirectionalDifference(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector v, N_Vector vp,
                          N_Vector w, N_Vector fbase, N_Vector u, const char* func) {
  const sunrealtype sig = ProbeIncrement(v);
  N_VLinearSum(1, v, sig, w, vp);
  const int flag = CountedRhs(ce, t, x, vp, u, func);
  if (flag == CE_SUCCESS) N_VLinearSum(1 / sig, u, -1 / sig, fbase, u);
  return flag;
}

// The start's first probe, shared by the dependence check and the coupling estimate:
// fbase = f(t0, x0, v0), w = the probe direction, u = df/dv w (no mass solve).
int FirstProbe(CEodeMemRec* ce, N_Vector w, N_Vector u, N_Vector fbase, const char* func) {
  int flag = BaseForce(ce, fbase, func);
  ProbeDirection(w);
  N_VScale(1 / N_VMaxNorm(w), w, w);
  if (flag == CE_SUCCESS) {
    flag = DirectionalDifference(ce, ce->tcur, ce->xcur, ce->D[1], ce->vtmp, w, fbase, u, func);
  }
  return flag;
}

// One power step on u = df/dv w: u <- M^{-1} u, w <- u / ||u||; *r = ||u|| (0: none).
int PowerStep(CEodeMemRec* ce, N_Vector w, N_Vector u, sunrealtype* r, const char* func) {
  const int flag = MassSolve(ce, u, func);
  *r = flag == CE_SUCCESS ? MaxNormOrNaN(u) : 0;
  if (!(*r > 0) || !std::isfinite(*r)) {
    *r = 0;
    return flag;
  }
  N_VScale(1 / *r, u, w);
  return flag;
}

// A new coupling estimate, made at step nst.
// A coupling or contraction that is not finite is unbounded: the mode decisions (<= a limit)
// are those of NaN, and the statistics stay finite.
sunrealtype Bounded(sunrealtype figure) { return std::isfinite(figure) ? figure : SUN_BIG_REAL; }

void SetCoupling(CEodeMemRec* ce, sunrealtype coupling) {
  ce->pc.coupling = Bounded(coupling);
  ce->pc.theta_last = false;
  ce->pc.nst_check = ce->nst;
}

// kappa ||M^{-1} df/dv||: power steps from the probe direction at the start, into pc.dir (kept
// for the refreshes); atmp, ftmp are scratch.
int EstimateCoupling(CEodeMemRec* ce, const char* func) {
  N_Vector w = ce->pc.dir, u = ce->atmp, fbase = ce->ftmp;
  int flag = FirstProbe(ce, w, u, fbase, func);
  sunrealtype rho = 0;
  for (int i = 0; i < kPowerSteps && flag == CE_SUCCESS; ++i) {
    if (i > 0) {
      flag = DirectionalDifference(ce, ce->tcur, ce->xcur, ce->D[1], ce->vtmp, w, fbase, u, func);
    }
    sunrealtype r = 0;
    if (flag == CE_SUCCESS) flag = PowerStep(ce, w, u, &r, func);
    if (!(r > 0)) break;
    rho = std::max(rho, r);
  }
  SetCoupling(ce, std::fabs(ce->co.kappa) * rho);
  return flag;
}

// Whether this start probes f for a velocity dependence: CE_VELOCITY_DETECT at every start; no
// mode set (the default), once per right-hand side function (restarts and CEodeReInit keep the
// answer); a declared dependence or independence never.
bool ProbeWanted(const CEodeMemRec* ce) {
  if (ce->pc.vel_request == CE_VELOCITY_DETECT) return true;
  return ce->pc.vel_request < 0 && ce->pc.vel_checked_f != RhsIdentity(ce);
}

// AUTO's check after a step of the nonlinear solver at (t, x): the solver's last residual
// evaluation (NlsLastResidual) is the base, so one power step from the kept direction costs one f.
// Prediction-correction comes back only below kPcReturnLimit, so that an estimate near the limit
// does not alternate the modes; its first step measures its contraction at once.
int RefreshCoupling(CEodeMemRec* ce, sunrealtype t, N_Vector x, const char* func) {
  N_Vector v = nullptr, fv = nullptr;
  NlsLastResidual(ce, &v, &fv);
  int flag = DirectionalDifference(ce, t, x, v, ce->ycor, ce->pc.dir, fv, ce->atmp, func);
  sunrealtype r = 0;
  if (flag == CE_SUCCESS) flag = PowerStep(ce, ce->pc.dir, ce->atmp, &r, func);
  if (flag != CE_SUCCESS) return flag;
  SetCoupling(ce, std::fabs(ce->co.kappa) * r);
  if (ce->pc.coupling <= kPcReturnLimit) {
    ce->pc.active = true;
    ce->pc.nst_check = -1;  // the first step of prediction-correction measures its contraction
  }
  return CE_SUCCESS;
}

// out = sum_j c_j X_j: on the serial backend one pass of the library's own kernel (with the
// reference's values), since at n of a few a generic vector operation in an unoptimised SUNDIALS
// build costs more than the step's f (bench_implicit_step).
__attribute__((always_inline)) inline void VelocityCombination(const CEodeMemRec* ce, int m,
                                                               const sunrealtype* c, N_Vector* X,
                                                               N_Vector out) {
  if (!ce->pc.serial) {
    N_VLinearCombination(m, const_cast<sunrealtype*>(c), X, out);
    return;
  }
  const sunrealtype* x[kMaxDegree];
  SerialDataOf(std::min(m, kMaxDegree), X, x);
  if (!CombineEntries(ce->n, m, c, x, SerialData(out)))
    CombineSerial(ce->n, m, c, X, SerialData(out));
}

}  // namespace

// One directional difference of f in x' at (t0, x0, v0), before the solvers are set up, so that a
// detected dependence goes through the same validation and initialisation as a declared one
// (Prepare). Its two f evaluations are counted apart from the steps' (CEodeGetImplicitStats). A
// failing or non-finite probe decides nothing: the start evaluates f again and reports it.
int DetectVelocityDependence(CEodeMemRec* ce) {
  if (!ProbeWanted(ce)) return CE_SUCCESS;
  N_Vector w = ce->tmp3, u = ce->atmp, fbase = ce->tmp2;  // vectors of every run
  ProbeDirection(w);
  N_VScale(1 / N_VMaxNorm(w), w, w);
  N_VLinearSum(1, ce->D[1], ProbeIncrement(ce->D[1]), w, ce->vtmp);
  ce->pc.nfe += 2;
  if (CallRhs(ce, ce->tcur, ce->xcur, ce->D[1], fbase) != 0 ||
      CallRhs(ce, ce->tcur, ce->xcur, ce->vtmp, u) != 0) {
    return CE_SUCCESS;
  }
  N_VLinearSum(1, u, -1, fbase, u);
  const sunrealtype df = MaxNormOrNaN(u);  // the change of f itself
  const sunrealtype floor = kDependenceUlps * SUN_UNIT_ROUNDOFF * MaxNormOrNaN(fbase);
  if (!std::isfinite(df) || !std::isfinite(floor)) return CE_SUCCESS;
  ce->pc.vel_checked_f = RhsIdentity(ce);
  ce->vel_dependent = df > floor;
  ce->pc.vel_detected = ce->vel_dependent;
  return CE_SUCCESS;
}

// One correction leaves an error of global order d - 1 (section 4.3): enough for a set whose
// order in x or x' is below d, one order short for a set of order d in both (G4_A54, measured
// 3.06 with one correction against 4 with Newton, test_pc). From degree 5 on one correction
// keeps the order but its velocity error is up to 12 times Newton's (test_pc): two.
int DefaultPCCorrections(int degree, const sunrealtype* params) {
  if (degree > 4) return 2;
  if (const MethodSet* m = NamedSetWithParams(degree, params)) return m->pc_corrections;
  int ox = degree, ov = degree;  // two corrections, should the conditions not be computed
  try {
    MethodOrders(degree, params, &ox, &ov, nullptr, nullptr);
  } catch (...) {
  }
  return std::min(ox, ov) >= degree ? 2 : 1;
}

namespace {

// The mode in use: AUTO unless the user chose one, or attached a nonlinear solver of their own
// without choosing (that solver is then what the user asked for).
int ImplicitMode(const CEodeMemRec* ce) {
  if (!ce->pc.mode_set && !ce->nls.own) return CE_IMPLICIT_NEWTON;
  return ce->pc.mode;
}

// The predicted velocity's d - 1 weights over D_1 .. D_{d-1}: V0 + kappa times the predictor's
// Taylor polynomial of the acceleration.
void PredictedVelocityWeights(const StepCoeffs& co, int d, sunrealtype* c) {
  for (int j = 1; j < d; ++j) c[j - 1] = co.V0[j] + (j >= 2 ? co.kappa * co.pred[j - 2] : 0);
}

// The corrected velocity's d weights over D_1 .. D_{d-1} and a: V0 + kappa a.
void CorrectedVelocityWeights(const StepCoeffs& co, int d, sunrealtype* c) {
  for (int j = 1; j < d; ++j) c[j - 1] = co.V0[j];
  c[d - 1] = co.kappa;
}

// Whether plan p is the one of the step's configuration at the step's h.
__attribute__((always_inline)) inline bool PlanKeyed(const PcMem::Plan& p, const CEodeMemRec* ce,
                                                     N_Vector a) {
  return p.key[1] == ce->D[2] && p.key[3] == a && p.h == ce->co.h && p.key[0] == ce->D[1] &&
         p.key[2] == ce->D[ce->degree - 1];
}

// A new plan, in the slot the other configuration did not use last: the weights as CorrectPC and
// CorrectedVelocity take them, the vectors' data as VelocityCombination reads it.
__attribute__((noinline)) const PcMem::Plan& NewPcPlan(CEodeMemRec* ce, N_Vector a) {
  PcMem& pc = ce->pc;
  const int d = ce->degree;
  pc.plan_last = 1 - pc.plan_last;
  PcMem::Plan& p = pc.plans[pc.plan_last];
  PredictedVelocityWeights(ce->co, d, p.cp);
  CorrectedVelocityWeights(ce->co, d, p.cc);
  for (int j = 1; j < d; ++j) p.x[j - 1] = NV_DATA_S(ce->D[j]);
  p.x[d - 1] = NV_DATA_S(a);
  p.out = NV_DATA_S(ce->vtmp);
  p.h = ce->co.h;
  p.key[0] = ce->D[1];
  p.key[1] = ce->D[2];
  p.key[2] = ce->D[d - 1];
  p.key[3] = a;
  return p;
}

// The plan of the step's configuration at the step's h (PcMem::Plan), made when the
// configuration first comes at this h.
__attribute__((always_inline)) inline const PcMem::Plan& PcPlanFor(CEodeMemRec* ce, N_Vector a) {
  PcMem& pc = ce->pc;
  const int other = 1 - pc.plan_last;  // the configurations alternate
  if (PlanKeyed(pc.plans[other], ce, a)) {
    pc.plan_last = other;
    return pc.plans[other];
  }
  if (PlanKeyed(pc.plans[pc.plan_last], ce, a)) return pc.plans[pc.plan_last];
  return NewPcPlan(ce, a);
}

// out = sum_j c_j x_j over M terms, as VelocityCombination forms it on the serial backend.
template <int M>
inline void PlannedCombination(sunindextype n, const sunrealtype* c, const sunrealtype* const* x,
                               sunrealtype* out) {
  if constexpr (M >= 3) {
    CombineEntriesOf<M>(n, c, x, out);
  } else {
    CombineSerial(n, M, c, x, out);
  }
}

// CorrectPC without the contraction's measurement on the serial backend without a mass matrix,
// for degree D: the same combinations from the plan (one lookup a step instead of gathering
// weights and data for each), each followed by f alone (M = I: no mass solve).
template <int D>
int CorrectPlannedOf(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector a, int k,
                     const char* func) {
  const PcMem::Plan& p = PcPlanFor(ce, a);
  PlannedCombination<D - 1>(ce->n, p.cp, p.x, p.out);
  int flag = CE_SUCCESS;
  for (int i = 1; i <= k && flag == CE_SUCCESS; ++i) {
    if (i > 1) PlannedCombination<D>(ce->n, p.cc, p.x, p.out);
    ++ce->pc.ncorr;
    flag = EvalRhs(ce, t, x, ce->vtmp, a, func);
  }
  return flag;
}

template <std::size_t... I>
constexpr std::array<PcPlannedFn, sizeof...(I)> PlannedTable(std::index_sequence<I...> /*d*/) {
  return {&CorrectPlannedOf<static_cast<int>(I) + kMinDegree>...};
}
// By the degree d = kMinDegree .. kMaxDegree.
constexpr auto kPlannedFns = PlannedTable(std::make_index_sequence<kMaxDegree - kMinDegree + 1>{});

}  // namespace

namespace {

// The diagonal solve for a run: it needs f to return accelerations (no mass matrix); its factors
// are formed at the first step (the start's h and kappa are new).
int ChooseDiagonalSolve(CEodeMemRec* ce, const char* func) {
  if (HasMassMatrix(ce)) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "CEodeSetVelJacDiagonal's solve needs f to return accelerations, but a "
                        "mass matrix is set: remove one of the two (a lumped mass goes into f and "
                        "into c as c_i / m_i).");
  }
  ce->pc.diag_h = 0;
  SetImplicitSolve(ce, SolveKind::kDiagonal);
  return CE_SUCCESS;
}

}  // namespace

int ChooseImplicitSolve(CEodeMemRec* ce, const char* func) {
  // The velocity combinations' backend, once per start (the step module's rule); the plans of
  // the last run go (its vectors may be gone).
  ce->pc.serial = FusedKernelOn(ce) && N_VGetVectorID(ce->xcur) == SUNDIALS_NVEC_SERIAL;
  for (PcMem::Plan& p : ce->pc.plans) p = PcMem::Plan{};
  ce->pc.planned =
      ce->pc.serial && !HasMassMatrix(ce) ? kPlannedFns[ce->degree - kMinDegree] : nullptr;
  if (HasConstraints(ce) || !ce->vel_dependent) return CE_SUCCESS;
  if (ce->pc.diag != nullptr) return ChooseDiagonalSolve(ce, func);
  const int mode = ImplicitMode(ce);
  SetImplicitSolve(ce, mode == CE_IMPLICIT_PC ? SolveKind::kPC : SolveKind::kNewton);
  if (mode != CE_IMPLICIT_AUTO) return CE_SUCCESS;
  if (ce->pc.dir == nullptr && (ce->pc.dir = CloneVector(ce->ycor)) == nullptr) {
    return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
  }
  const int flag = EstimateCoupling(ce, func);
  ce->pc.active = flag == CE_SUCCESS && ce->pc.coupling <= kPcContractionLimit;
  SetImplicitSolve(ce, SolveKind::kAuto);
  return flag;
}

namespace {

// v = V0 + kappa a into vtmp (one pass, the weights of SolvePC's corrections).
__attribute__((always_inline)) inline void CorrectedVelocity(CEodeMemRec* ce, N_Vector a) {
  const StepCoeffs& co = ce->co;
  const int d = ce->degree;
  sunrealtype c[kMaxDegree] = {};
  N_Vector X[kMaxDegree] = {};
  CorrectedVelocityWeights(co, d, c);
  std::copy(ce->D + 1, ce->D + d, X);
  X[d - 1] = a;
  VelocityCombination(ce, d, c, X, ce->vtmp);
}

// One correction more from a into vtmp, ycor and atmp for the contraction: ycor = v_new - v_old
// (kappa times the previous correction), a_next into atmp (into a itself when keep).
int NextCorrection(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector a, bool keep,
                   const char* func) {
  N_VScale(1, ce->vtmp, ce->ycor);
  N_VScale(1, a, ce->atmp);
  CorrectedVelocity(ce, a);
  N_VLinearSum(1, ce->vtmp, -1, ce->ycor, ce->ycor);
  // keep: the step's own last correction; otherwise one more, for the check only.
  const int flag = keep ? CorrectionAccel(ce, t, x, ce->vtmp, a, func)
                        : CheckAccel(ce, t, x, ce->vtmp, ce->atmp, func);
  if (keep) {
    N_VLinearSum(1, a, -1, ce->atmp, ce->atmp);
  } else {
    N_VLinearSum(1, ce->atmp, -1, a, ce->atmp);
  }
  return flag;
}

// P(EC)^k with k corrections. With theta, *theta = ||a_{j+1} - a_j|| / ||a_j - a_{j-1}|| of the
// last two corrections (section 4.3; ycor, atmp: scratch), where a_1 - a_0 = (v_1 - v_0) / kappa:
// the predicted acceleration itself is never formed. With k = 1 that needs one evaluation more,
// counted with the coupling estimates; the step keeps a_1, so that its answer does not depend on
// whether it was a check.
int CorrectPC(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector a, int k, sunrealtype* theta,
              const char* func) {
  const StepCoeffs& co = ce->co;
  const int d = ce->degree;
  sunrealtype c[kMaxDegree] = {};
  N_Vector X[kMaxDegree] = {};
  PredictedVelocityWeights(co, d, c);
  std::copy(ce->D + 1, ce->D + d, X);
  VelocityCombination(ce, d - 1, c, X, ce->vtmp);
  ++ce->pc.ncorr;
  int flag = EvalAccel(ce, t, x, ce->vtmp, a, func);  // M(x, t) of the step, once
  for (int i = 2; i <= k && flag == CE_SUCCESS; ++i) {
    if (theta != nullptr && i == k) {
      flag = NextCorrection(ce, t, x, a, true, func);
    } else {
      CorrectedVelocity(ce, a);
      flag = CorrectionAccel(ce, t, x, ce->vtmp, a, func);
    }
  }
  if (flag != CE_SUCCESS || theta == nullptr) return flag;
  if (k == 1) {
    flag = NextCorrection(ce, t, x, a, false, func);
    if (flag != CE_SUCCESS) return flag;
  }
  const sunrealtype first = MaxNormOrNaN(ce->ycor),
                    second = std::fabs(co.kappa) * MaxNormOrNaN(ce->atmp);
  *theta = first > 0 ? second / first : (std::isfinite(first) ? 0 : first);  // 0: exact predictor
  return flag;
}

}  // namespace

// P(EC)^k: the predicted acceleration gives the velocity, each evaluation-correction
// a = M^{-1} f(t, x, V0 + kappa a) replaces it; no convergence test. The velocity of the
// update follows from the last a by the method's own relation. Each velocity is one linear
// combination of the history (and a): V0 + kappa * (PredictAccel's Taylor polynomial) for the
// first, so that a step of k corrections makes k vector passes besides f and the update.
int SolvePC(CEodeMemRec* ce, sunrealtype t, sunrealtype /*tnext*/, N_Vector x, N_Vector a,
            const char* func) {
  ++ce->pc.nsteps;
  if (ce->pc.planned != nullptr) return ce->pc.planned(ce, t, x, a, PCCorrections(ce), func);
  return CorrectPC(ce, t, x, a, PCCorrections(ce), nullptr, func);
}

namespace {

// SolveAuto on a step that checks its choice, or solved by the nonlinear solver (few steps):
// apart, so that a step of prediction-correction keeps a small frame.
__attribute__((noinline)) int SolveAutoChecked(CEodeMemRec* ce, sunrealtype t, sunrealtype tnext,
                                               N_Vector x, N_Vector a, bool check,
                                               const char* func) {
  if (!ce->pc.active) {
    const int flag = SolveImplicit(ce, t, tnext, x, a, func);
    return flag != CE_SUCCESS || !check ? flag : RefreshCoupling(ce, t, x, func);
  }
  sunrealtype theta = 0;
  const int flag = CorrectPC(ce, t, x, a, PCCorrections(ce), &theta, func);
  ce->pc.theta = Bounded(theta);
  ce->pc.theta_last = true;
  ce->pc.nst_check = ce->nst;
  if (flag == CE_SUCCESS && theta <= kPcContractionLimit) {
    ++ce->pc.nsteps;
    return flag;
  }
  ce->pc.active = false;  // an f failure at a diverging velocity, too
  return SolveImplicit(ce, t, tnext, x, a, func);
}

}  // namespace

// CE_IMPLICIT_AUTO's step: the solve in use, and every msbj steps (at least
// kDefaultJacEvalFrequency apart: a user's msbj = 1, a fresh Newton matrix every step, would
// otherwise add an f to every step) the check whether it is still the right one (section 4.3).
// Prediction-correction measures its own contraction on that step; when the contraction is
// lost, the step is solved again by the nonlinear solver, which then stays until the coupling
// estimate (one power step per check) falls below kPcReturnLimit.
int SolveAuto(CEodeMemRec* ce, sunrealtype t, sunrealtype tnext, N_Vector x, N_Vector a,
              const char* func) {
  const long int every = std::max(ce->ls.msbj, kDefaultJacEvalFrequency);
  const bool check = ce->nst - ce->pc.nst_check >= every || ce->pc.nst_check < 0;
  if (ce->pc.active && !check) return SolvePC(ce, t, tnext, x, a, func);
  return SolveAutoChecked(ce, t, tnext, x, a, check, func);
}

namespace {

// 1 / (1 - kappa c) for the step's h into diag_inv; CE_ILL_INPUT where an entry of 1 - kappa c is
// not positive (a velocity dependence that pumps energy in, too strong for the step).
int DiagonalFactors(CEodeMemRec* ce, const char* func) {
  PcMem& pc = ce->pc;
  N_VScale(-ce->co.kappa, pc.diag, pc.diag_inv);
  N_VAddConst(pc.diag_inv, 1, pc.diag_inv);
  const sunrealtype smallest = N_VMin(pc.diag_inv);
  if (!(smallest > 0)) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "1 - kappa c has the entry %g <= 0 at h = %g (kappa = %g): a positive "
                        "entry of the diagonal given to CEodeSetVelJacDiagonal (energy pumped in) "
                        "is too large for this step; reduce h.",
                        static_cast<double>(smallest), static_cast<double>(ce->co.h),
                        static_cast<double>(ce->co.kappa));
  }
  N_VInv(pc.diag_inv, pc.diag_inv);
  pc.diag_h = ce->co.h;
  return CE_SUCCESS;
}

// a *= 1 / (1 - kappa c) after a = f(t, x, V0): N_VProd's products, on serial data without its
// call.
inline void ApplyDiagonal(CEodeMemRec* ce, N_Vector a) {
  const PcMem& pc = ce->pc;
  if (!pc.serial) {
    N_VProd(a, pc.diag_inv, a);
    return;
  }
  sunrealtype* ad = SerialData(a);
  const sunrealtype* s = SerialData(pc.diag_inv);
  for (sunindextype i = 0; i < ce->n; ++i) ad[i] *= s[i];
}

// SolveDiagonal on the serial backend for degree D: V0 from the plan of the step's configuration
// (PcPlanFor; the corrected velocity's weights less a's), then f and the factors.
template <int D>
int DiagonalPlannedOf(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector a, const char* func) {
  const PcMem::Plan& p = PcPlanFor(ce, a);
  PlannedCombination<D - 1>(ce->n, p.cc, p.x, p.out);
  const int flag = EvalRhs(ce, t, x, ce->vtmp, a, func);
  if (flag == CE_SUCCESS) ApplyDiagonal(ce, a);
  return flag;
}

using DiagonalFn = int (*)(CEodeMemRec*, sunrealtype, N_Vector, N_Vector, const char*);
template <std::size_t... I>
constexpr std::array<DiagonalFn, sizeof...(I)> DiagonalTable(std::index_sequence<I...> /*d*/) {
  return {&DiagonalPlannedOf<static_cast<int>(I) + kMinDegree>...};
}
// By the degree d = kMinDegree .. kMaxDegree.
constexpr auto kDiagonalFns =
    DiagonalTable(std::make_index_sequence<kMaxDegree - kMinDegree + 1>{});

}  // namespace

// f(t, x, V0 + kappa a) = f(t, x, V0) + kappa c a for f affine in x' with df/dx' = diag(c): the
// step's equation a = f(t, x, V0 + kappa a) has the solution a = f(t, x, V0) / (1 - kappa c), one
// evaluation and no iteration (docs/theory.md section 4.3). The factors follow h.
int SolveDiagonal(CEodeMemRec* ce, sunrealtype t, sunrealtype /*tnext*/, N_Vector x, N_Vector a,
                  const char* func) {
  if (ce->pc.diag_h != ce->co.h) {
    const int flag = DiagonalFactors(ce, func);
    if (flag != CE_SUCCESS) return flag;
  }
  // The plans exist on the serial backend without a mass matrix, the diagonal solve's case.
  if (ce->pc.planned != nullptr) return kDiagonalFns[ce->degree - kMinDegree](ce, t, x, a, func);
  const int d = ce->degree;
  sunrealtype c[kMaxDegree] = {};
  N_Vector X[kMaxDegree] = {};
  CorrectedVelocityWeights(ce->co, d, c);  // V0's d - 1 weights, a's left out
  std::copy(ce->D + 1, ce->D + d, X);
  VelocityCombination(ce, d - 1, c, X, ce->vtmp);
  const int flag = EvalRhs(ce, t, x, ce->vtmp, a, func);
  if (flag == CE_SUCCESS) ApplyDiagonal(ce, a);
  return flag;
}

void PcReset(CEodeMemRec* ce, bool counters) {
  PcMem& pc = ce->pc;
  if (counters) pc.nsteps = pc.ncorr = pc.nfe = 0;
  pc.coupling = pc.theta = 0;
  pc.theta_last = false;
}

void PcFree(CEodeMemRec* ce) {
  for (N_Vector* v : {&ce->pc.dir, &ce->pc.diag, &ce->pc.diag_inv}) {
    if (*v != nullptr) N_VDestroy(*v);
    *v = nullptr;
  }
}

void PcMethodChanged(CEodeMemRec* ce) {
  ce->pc.k_default = DefaultPCCorrections(ce->degree, ce->params);
}

void PcSetVelocityRequest(CEodeMemRec* ce, int request) {
  ce->pc.vel_request = request;
  ce->pc.vel_checked_f = nullptr;
  ce->pc.vel_detected = false;
}

bool VelocityUnread(const CEodeMemRec* ce) {
  const int r = ce->pc.vel_request;
  return r != CE_VELOCITY_DEPENDENT && r != CE_VELOCITY_INDEPENDENT && !ce->vel_dependent &&
         !ce->pc.vel_detected && ce->pc.vel_checked_f == RhsIdentity(ce);
}

const char* VelocityDependenceName(const CEodeMemRec* ce) {
  if (ce->pc.vel_request == CE_VELOCITY_DEPENDENT) return "declared";
  if (ce->pc.vel_request == CE_VELOCITY_INDEPENDENT) return "none (declared)";
  return ce->pc.vel_detected ? "detected" : "none";
}

// The step's solve for the acceleration that the last start chose (with AUTO, the one it runs
// now).
const char* AccelSolveName(const CEodeMemRec* ce) {
  if (!ce->started) return "not started";
  switch (ChosenSolve(ce)) {
    case SolveKind::kExplicit:
      return "explicit";
    case SolveKind::kNewton:
      return "Newton";
    case SolveKind::kPC:
      return "prediction-correction";
    case SolveKind::kAuto:
      return ce->pc.active ? "AUTO: prediction-correction" : "AUTO: Newton";
    case SolveKind::kConstrained:
      return "constrained";
    case SolveKind::kDiagonal:
      return "diagonal";
  }
  return "unknown";
}

}  // namespace ceode

extern "C" {

int CEodeSetImplicitMode(void* mem, int mode) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (mode != CE_IMPLICIT_NEWTON && mode != CE_IMPLICIT_PC && mode != CE_IMPLICIT_AUTO) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "mode = %d: use CE_IMPLICIT_NEWTON, CE_IMPLICIT_PC or "
                               "CE_IMPLICIT_AUTO.",
                               mode);
  }
  ce->pc.mode = mode;
  ce->pc.mode_set = true;
  ceode::Restart(ce);  // the choice is made at the start
  return CE_SUCCESS;
}

int CEodeSetPCCorrections(void* mem, int k) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (k < 0 || k > 2) {
    return ceode::ProcessError(
        ce, CE_ILL_INPUT, __func__,
        "k = %d: use 1 or 2 corrections (0: the set's default, docs/theory.md 4.3).", k);
  }
  ce->pc.corrections = k;
  return CE_SUCCESS;
}

int CEodeSetVelJacDiagonal(void* mem, N_Vector c) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  ceode::PcMem& pc = ce->pc;
  if (c == nullptr) {  // removed: the next start chooses as CEodeSetImplicitMode says
    for (N_Vector* v : {&pc.diag, &pc.diag_inv}) {
      if (*v != nullptr) N_VDestroy(*v);
      *v = nullptr;
    }
    ceode::Restart(ce);
    return CE_SUCCESS;
  }
  if (!ce->initialized) {
    return ceode::ProcessError(ce, CE_NO_MALLOC, __func__,
                               "The diagonal needs the problem's size: call CEodeInit first.");
  }
  if (N_VGetLength(c) != ce->n || !ceode::IsFinite(c)) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "c has %ld entries (the problem has %ld) or a NaN or Inf: give "
                               "df/dx' as a vector cloned from x0.",
                               static_cast<long>(N_VGetLength(c)), static_cast<long>(ce->n));
  }
  for (N_Vector* v : {&pc.diag, &pc.diag_inv}) {
    if (*v == nullptr) *v = ceode::CloneVector(ce->xcur);
    if (*v == nullptr) return ceode::ProcessError(ce, CE_MEM_FAIL, __func__, "Out of memory.");
  }
  N_VScale(1, c, pc.diag);
  ceode::Restart(ce);  // the solve is chosen at the start
  return CE_SUCCESS;
}

int CEodeGetImplicitStats(void* mem, long int* npcsteps, long int* nnlssteps, long int* nfecoupling,
                          sunrealtype* coupling) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (npcsteps == nullptr || nnlssteps == nullptr || nfecoupling == nullptr ||
      coupling == nullptr) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__, "An output pointer is NULL.");
  }
  *npcsteps = ce->pc.nsteps;
  *nnlssteps = ce->nls.nsteps;
  *nfecoupling = ce->pc.nfe;
  *coupling = ce->pc.theta_last ? ce->pc.theta : ce->pc.coupling;  // the last figure measured
  return CE_SUCCESS;
}

}  // extern "C"
