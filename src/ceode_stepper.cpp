// CEODE as ARKODE's fast integrator: one implementation (Reset, Evolve, FullRhs,
// SetForcing on the Stepper below) behind MRIStep's custom inner stepper
// (SUNDIALS 6.4 and 7.x) and the SUNStepper of SUNDIALS >= 7.2.
//
// The stepper owns its state y = [x; v]. Every inner run hands the MRI forcing to the memory's
// forcing hook (ceode_forcing.hpp: CEODE then integrates in u = x' = v + r_x) and restarts CEODE
// with Reset, which keeps the counters; the user's f and user_data stay in the memory.
#include <ceode/ceode_stepper.h>
#include <nvector/nvector_manyvector.h>
#include <nvector/nvector_serial.h>

#include <algorithm>
#include <cmath>
#include <new>

#include "ceode_forcing.hpp"
#include "ceode_impl.hpp"

namespace ceode {
namespace {

// The two halves of a first-order vector y = [x; v]; as a view slot, empty serial vectors
// re-pointed into y's array (no copy).
struct Halves {
  N_Vector x = nullptr;
  N_Vector v = nullptr;
};

struct Stepper {
  CEodeMemRec* ce = nullptr;
  CEodeRhsFn f = nullptr;  // the memory's f and user_data at creation: a change is refused
  void* user_data = nullptr;
  sunrealtype h_max = 0;  // the user's inner step: the largest one taken
  N_Vector y_own = nullptr;
  sunrealtype t_own = 0;
  bool have_state = false;
  bool omega_known = false;    // the guard's frequency is known: restarts do not re-estimate it
  sunrealtype omega_new = 0;   // the first run's estimate, for the next Reset
  sunrealtype tstop = 0;
  bool tstop_set = false;
  Halves own_view, io_view, io2_view;
  Halves forcing_view[kMaxForcing];
  Forcing forcing;        // Adapters::forcing while the stepper exists
  N_Vector u = nullptr;   // x' = v + r_x during an inner run
  N_Vector rx = nullptr;  // scratch for the restart: the jump of r_x
  N_Vector xp = nullptr;  // and x plus a multiple of it
  long int nrestarts = 0;
  // What the next restart can reuse (docs/porting.md, "What a restart costs"): at t_end, the
  // end of the last inner run, the g parts g_end[k] = D_k - (r_v + r_x')^(k-2) of the history's
  // derivatives D_2 .. D_{d-1} (the old x' in them) and r_x(t_end). Valid while the state has
  // not been changed since.
  bool end_valid = false;
  int end_degree = 0;
  sunrealtype t_end = 0;
  N_Vector g_end[kMaxDegree] = {};
  N_Vector rx_end = nullptr;
  N_Vector ytmp = nullptr;  // for the comparison of a reset state with the owned one
};

void FreeSlot(Halves* s) {
  if (s->x != nullptr) N_VDestroy(s->x);
  if (s->v != nullptr) N_VDestroy(s->v);
  s->x = s->v = nullptr;
}

void DestroyStepper(Stepper* st) {
  if (st == nullptr) return;
  CEodeMemRec* ce = st->ce;
  if (ce != nullptr && ce->adapters.stepper == st) {  // the memory evaluates f unforced again
    ce->adapters.stepper = nullptr;
    ce->adapters.forcing = nullptr;
    SelectRhs(ce);
  }
  FreeSlot(&st->own_view);
  FreeSlot(&st->io_view);
  FreeSlot(&st->io2_view);
  for (Halves& s : st->forcing_view) FreeSlot(&s);
  for (N_Vector w : {st->y_own, st->u, st->rx, st->xp, st->forcing.vg, st->rx_end, st->ytmp}) {
    if (w != nullptr) N_VDestroy(w);
  }
  for (N_Vector w : st->g_end) {
    if (w != nullptr) N_VDestroy(w);
  }
  delete st;
}

// The one validation point of the first-order vectors handed to the stepper:
// y must be [x; v] with both halves of CEODE's length and vector type.
int SplitVector(Stepper* st, N_Vector y, Halves* slot, Halves* out, const char* func) {
  CEodeMemRec* ce = st->ce;
  if (y == nullptr) return ProcessError(ce, CE_ILL_INPUT, func, "The state vector is NULL.");
  const N_Vector_ID id = N_VGetVectorID(y);
  const N_Vector_ID want = N_VGetVectorID(ce->xcur);
  if (id == SUNDIALS_NVEC_MANYVECTOR) {
    const sunindextype np = N_VGetNumSubvectors_ManyVector(y);
    N_Vector x = np == 2 ? N_VGetSubvector_ManyVector(y, 0) : nullptr;
    N_Vector v = np == 2 ? N_VGetSubvector_ManyVector(y, 1) : nullptr;
    if (np != 2 || N_VGetLength(x) != ce->n || N_VGetLength(v) != ce->n ||
        N_VGetVectorID(x) != want || N_VGetVectorID(v) != want) {
      return ProcessError(ce, CE_ILL_INPUT, func,
                          "The ManyVector state has %ld parts: it must have two, y = [x; v], "
                          "each of length %ld and of the vector type of CEODE's x0.",
                          static_cast<long>(np), static_cast<long>(ce->n));
    }
    *out = {x, v};
    return CE_SUCCESS;
  }
  if (id != SUNDIALS_NVEC_SERIAL || want != SUNDIALS_NVEC_SERIAL || N_VGetLength(y) != 2 * ce->n) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "The state vector (id %d, length %ld) is neither a ManyVector [x; v] of "
                        "two parts of length %ld nor a serial vector of length %ld (2n, with a "
                        "serial x0 in CEodeInit).",
                        static_cast<int>(id), static_cast<long>(N_VGetLength(y)),
                        static_cast<long>(ce->n), static_cast<long>(2 * ce->n));
  }
  if (slot->x == nullptr) slot->x = N_VNewEmpty_Serial(ce->n, ce->sunctx);
  if (slot->v == nullptr) slot->v = N_VNewEmpty_Serial(ce->n, ce->sunctx);
  if (slot->x == nullptr || slot->v == nullptr) {
    return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
  }
  sunrealtype* data = N_VGetArrayPointer(y);
  N_VSetArrayPointer(data, slot->x);
  N_VSetArrayPointer(data + ce->n, slot->v);
  *out = {slot->x, slot->v};
  return CE_SUCCESS;
}

int Allocate(Stepper* st, N_Vector y, const char* func) {
  CEodeMemRec* ce = st->ce;
  st->y_own = N_VClone(y);
  st->ytmp = N_VClone(y);
  bool ok = st->y_own != nullptr && st->ytmp != nullptr;
  for (N_Vector* w : {&st->u, &st->rx, &st->xp, &st->forcing.vg, &st->rx_end}) {
    ok = ok && (*w = N_VClone(ce->xcur)) != nullptr;
  }
  return ok ? CE_SUCCESS : ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
}

// Problems the inner stepper cannot take: the forcing adds to x'' directly, so
// a mass matrix would have to multiply it, and constraints would fight it.
int StepperCheckMemory(CEodeMemRec* ce, const char* func) {
  if (ce->mfn != nullptr || ce->M != nullptr || HasConstraints(ce)) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "The inner stepper needs M = I and no constraints (the MRI forcing is "
                        "added to the acceleration): divide f by M in your right-hand side.");
  }
  if (ce->h <= 0) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "No inner step: call CEodeSetFixedStep(ce_mem, h) first (h is the "
                        "largest inner step).");
  }
  return CE_SUCCESS;
}

int StepperCreate(CEodeMemRec* ce, Stepper** out, const char* func) {
  int flag = StepperCheckMemory(ce, func);
  if (flag != CE_SUCCESS) return flag;
  if (ce->adapters.stepper != nullptr) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "This CEODE memory already drives an inner stepper: create one CEODE "
                        "memory per stepper.");
  }
  auto* st = new (std::nothrow) Stepper;
  if (st == nullptr) return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
  st->ce = ce;
  st->f = ce->f;
  st->user_data = ce->user_data;
  st->h_max = ce->h;
  st->omega_known = ce->omega_user > 0;
  ce->adapters.stepper = st;
  ce->adapters.forcing = &st->forcing;  // no terms yet: f is evaluated as it is
  *out = st;
  return CE_SUCCESS;
}

void StepperDestroy(Stepper* st) { DestroyStepper(st); }

// The stepper copies the state: it owns what it restarts from.
int StepperReset(Stepper* st, sunrealtype tR, N_Vector yR, const char* func) {
  Halves in;
  int flag = SplitVector(st, yR, &st->io_view, &in, func);
  if (flag != CE_SUCCESS) return flag;
  if (!std::isfinite(tR)) return ProcessError(st->ce, CE_ILL_INPUT, func, "tR is not finite.");
  if (st->y_own == nullptr && (flag = Allocate(st, yR, func)) != CE_SUCCESS) return flag;
  if (N_VGetVectorID(yR) != N_VGetVectorID(st->y_own)) {
    return ProcessError(st->ce, CE_ILL_INPUT, func,
                        "The state vector changed type since the first call (serial vs "
                        "ManyVector): pass the same kind of vector every time.");
  }
  // A reset to the state the stepper already stands on (MRIStep does this at every stage; the
  // time may differ by rounding) keeps what the next restart may reuse; any other state drops it.
  if (st->end_valid) {
    N_VLinearSum(1, yR, -1, st->y_own, st->ytmp);
    const sunrealtype tol = 100 * SUN_UNIT_ROUNDOFF * (std::fabs(tR) + std::fabs(st->t_own));
    st->end_valid = std::fabs(tR - st->t_own) <= tol && N_VMaxNorm(st->ytmp) == 0;
  }
  N_VScale(1, yR, st->y_own);
  st->t_own = tR;
  st->have_state = true;
  return CE_SUCCESS;
}

int StepperSetForcing(Stepper* st, sunrealtype tshift, sunrealtype tscale, N_Vector* F, int nf,
                      const char* func) {
  if (nf < 0 || nf > kMaxForcing || (nf > 0 && F == nullptr)) {
    return ProcessError(st->ce, CE_ILL_INPUT, func,
                        "%d forcing vectors: 0..%d are supported (F must not be NULL).", nf,
                        kMaxForcing);
  }
  N_Vector Fx[kMaxForcing], Fv[kMaxForcing];
  for (int k = 0; k < nf; ++k) {
    Halves hv;
    const int flag = SplitVector(st, F[k], &st->forcing_view[k], &hv, func);
    if (flag != CE_SUCCESS) {
      SetForcing(st->ce, &st->forcing, 0, 1, 0, Fx, Fv, func);  // no forcing rather than half of one
      return flag;
    }
    Fx[k] = hv.x;
    Fv[k] = hv.v;
  }
  return SetForcing(st->ce, &st->forcing, tshift, tscale, nf, Fx, Fv, func);
}

#ifdef CEODE_HAVE_SUNSTEPPER
int StepperSetStepDirection(Stepper* st, sunrealtype stepdir, const char* func) {
  if (stepdir < 0) {
    return ProcessError(st->ce, CE_BAD_T, func,
                        "Step direction %g: CEODE integrates forward only (a splitting method "
                        "of order > 2 takes negative substeps); use a second-order splitting "
                        "such as Strang, or another inner stepper.",
                        static_cast<double>(stepdir));
  }
  return CE_SUCCESS;
}

void StepperSetStopTime(Stepper* st, sunrealtype tstop) {
  st->tstop = tstop;
  st->tstop_set = true;
}
#endif

// The cheap restart needs the history to be the explicit path's (D_2 = G at the end point,
// exactly; with declared velocity dependence D_2 comes from the implicit solve and g_v would
// enter the jerk) and a consistent one (not the zero start).
bool CanReuse(const Stepper* st) {
  const CEodeMemRec* ce = st->ce;
  return !ce->vel_dependent && !ce->zero_start;
}

// After an inner run that ended on a step: strip the old forcing from the history at t_end,
// g_end[k] = D_k - r_v^(k-2) - r_x^(k-1), k = 2 .. d-1 (for k = 2: g(t, x) itself).
void CaptureEnd(Stepper* st) {
  CEodeMemRec* ce = st->ce;
  st->end_valid = false;
  if (!CanReuse(st) || !ce->started) return;
  const sunrealtype t = ce->tcur;
  for (int k = 2; k < ce->degree; ++k) {
    if (st->g_end[k] == nullptr && (st->g_end[k] = N_VClone(ce->xcur)) == nullptr) return;
    ForcingAccel(st->forcing, t, k - 2, ce->D[k], -1, st->g_end[k]);
  }
  ForcingX(st->forcing, t, 0, nullptr, 1, st->rx_end);
  st->t_end = t;
  st->end_degree = ce->degree;
  st->end_valid = true;
}

// The start's derivatives at t0 from the last run's end and the new forcing (its derivatives
// are known exactly), written into the history by Reset. x and v are continuous, so g(t0, x0)
// is unchanged: D_2 costs nothing. x' = v + r_x jumps by delta = r_x,new(t0) - r_x,old(t0), so
// the g part of the jerk, g_t + g_x x', gains g_x delta: one forward difference, none when
// delta = 0. Degrees 3 and 4 are then exact. From D_4 on, the g parts also change with the jump
// (g_x times the jump of D_2, g_xx terms in delta): carried as they are, these errors are
// proportional to the change of the forcing, and a step sees them scaled by h^k (docs/porting.md,
// "What a restart costs").
int PresetHistory(Stepper* st, sunrealtype t0, const Halves& own, const char* func) {
  CEodeMemRec* ce = st->ce;
  for (int k = 2; k < ce->degree; ++k) {
    ForcingAccel(st->forcing, t0, k - 2, st->g_end[k], 1, ce->D[k]);
  }
  if (ce->degree < 4) return CE_SUCCESS;
  ForcingX(st->forcing, t0, -1, st->rx_end, 1, st->rx);
  const sunrealtype dn = N_VMaxNorm(st->rx);
  if (!(dn > 0)) return CE_SUCCESS;
  const sunrealtype eps =
      std::sqrt(SUN_UNIT_ROUNDOFF) * std::max(sunrealtype(1), N_VMaxNorm(own.x) / dn);
  N_VLinearSum(1, own.x, eps, st->rx, st->xp);
  const int rv = BaseRhs(ce, t0, st->xp, own.v, ce->atmp);
  ++ce->nfe;
  ++ce->nfe_start;
  if (rv != 0) {
    return ProcessError(ce, CE_RHSFUNC_FAIL, func,
                        "The right-hand side failed (returned %d) at t = %.17g.", rv,
                        static_cast<double>(t0));
  }
  N_VLinearSum(1 / eps, ce->atmp, -1 / eps, st->g_end[2], ce->atmp);
  N_VLinearSum(1, ce->D[3], 1, ce->atmp, ce->D[3]);
  return CE_SUCCESS;
}

// Restart CEODE at (t0, x, u = v + r_x(t0)) with the largest step <= h_max that
// lands on tout, keeping the counters and the guard's frequency.
int RestartInner(Stepper* st, sunrealtype t0, sunrealtype tout, const Halves& own,
                 const char* func) {
  CEodeMemRec* ce = st->ce;
  const sunrealtype span = tout - t0;
  const long int nsub = std::max(1L, static_cast<long int>(std::ceil(span / st->h_max - 1e-8)));
  int flag = CEodeSetFixedStep(ce, span / static_cast<sunrealtype>(nsub));
  if (flag != CE_SUCCESS) return flag;
  ForcingX(st->forcing, t0, 1, own.v, 1, st->u);
  ++st->nrestarts;
  ResetOptions opt;
  opt.omega_max = st->omega_new;
  st->omega_new = 0;
  if (st->end_valid && CanReuse(st) && st->end_degree == ce->degree &&
      std::fabs(t0 - st->t_end) <= 1e-8 * ce->h) {
    opt.history = [&] { return PresetHistory(st, t0, own, func); };
  }
  st->end_valid = false;
  return Reset(ce, func, t0, own.x, st->u, opt);
}

// Without a reset, the stepper starts where the CEODE memory stands (CEodeInit's
// x0, v0 at t0), as ARKODE's own SUNSteppers do; y only gives the vector shape.
int StateFromMemory(Stepper* st, N_Vector y, const char* func) {
  Halves in, own;
  int flag = SplitVector(st, y, &st->io_view, &in, func);
  if (flag == CE_SUCCESS && st->y_own == nullptr) flag = Allocate(st, y, func);
  if (flag == CE_SUCCESS) flag = SplitVector(st, st->y_own, &st->own_view, &own, func);
  if (flag != CE_SUCCESS) return flag;
  N_VScale(1, st->ce->xcur, own.x);
  N_VScale(1, st->ce->D[1], own.v);
  st->t_own = st->ce->tcur;
  st->have_state = true;
  st->end_valid = false;
  return CE_SUCCESS;
}

// Integrates the owned state from t_own to tout (> t_own) and copies it to y.
int StepperEvolve(Stepper* st, sunrealtype tout, N_Vector y, const char* func) {
  CEodeMemRec* ce = st->ce;
  int flag = StepperCheckMemory(ce, func);
  if (flag != CE_SUCCESS) return flag;
  if (ce->f != st->f || ce->user_data != st->user_data) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "The CEODE memory of this stepper was changed by CEodeInit or "
                        "CEodeSetUserData after the stepper was created: free the stepper and "
                        "create a new one (put your data in user_data before creating it).");
  }
  if (!st->have_state && (flag = StateFromMemory(st, y, func)) != CE_SUCCESS) return flag;
  if (st->tstop_set && tout > st->tstop) tout = st->tstop;
  const sunrealtype t0 = st->t_own;
  const sunrealtype tol = 100 * SUN_UNIT_ROUNDOFF * (std::fabs(t0) + std::fabs(tout));
  if (!(tout >= t0 - tol)) {
    return ProcessError(ce, CE_BAD_T, func,
                        "Inner step from t0 = %.17g to tout = %.17g is negative: CEODE integrates "
                        "forward only (a splitting method of order > 2 takes negative substeps); "
                        "use a second-order splitting such as Strang, or another inner stepper.",
                        static_cast<double>(t0), static_cast<double>(tout));
  }
  Halves own, io;
  if ((flag = SplitVector(st, st->y_own, &st->own_view, &own, func)) != CE_SUCCESS) return flag;
  if ((flag = SplitVector(st, y, &st->io_view, &io, func)) != CE_SUCCESS) return flag;
  if (tout - t0 > tol) {
    if ((flag = RestartInner(st, t0, tout, own, func)) != CE_SUCCESS) return flag;
    sunrealtype tret = t0;
    if ((flag = CEodeEvolve(ce, tout, own.x, st->u, &tret, CE_NORMAL)) < 0) return flag;
    // The output is the method's own state at tcur (no interpolation) only if the run ended on
    // a step; only then is the history's D_2 the acceleration at the returned state.
    if (std::fabs(tout - ce->tcur) <= 1e-8 * ce->h) CaptureEnd(st);
    // The first run estimated omega_max; later restarts check h against it without
    // a new power iteration.
    if (!st->omega_known && ce->omega_est > 0 && std::isfinite(ce->omega_est)) {
      st->omega_new = ce->omega_est;
      st->omega_known = true;
    }
    ForcingX(st->forcing, tout, 1, st->u, -1, own.v);
    st->t_own = tout;
  }
  N_VScale(1, st->y_own, y);
  return CE_SUCCESS;
}

// The unforced fast right-hand side f = [v; g(t, x, v)].
int StepperFullRhs(Stepper* st, sunrealtype t, N_Vector y, N_Vector f, const char* func) {
  Halves in, out;
  int flag = SplitVector(st, y, &st->io_view, &in, func);
  if (flag != CE_SUCCESS) return flag;
  if ((flag = SplitVector(st, f, &st->io2_view, &out, func)) != CE_SUCCESS) return flag;
  N_VScale(1, in.v, out.x);
  const int rv = BaseRhs(st->ce, t, in.x, in.v, out.v);
  ++st->ce->nfe;
  if (rv != 0) {
    return ProcessError(st->ce, CE_RHSFUNC_FAIL, func,
                        "The right-hand side failed (returned %d) at t = %.17g.", rv,
                        static_cast<double>(t));
  }
  return CE_SUCCESS;
}

long int StepperNumRestarts(const Stepper* st) { return st->nrestarts; }

// The stepper attached to a CEODE memory, or nullptr.
Stepper* AttachedStepper(CEodeMemRec* ce) { return static_cast<Stepper*>(ce->adapters.stepper); }

}  // namespace
}  // namespace ceode

// ---------------------------------------------------------------------------
// Version-specific glue: each callback unpacks its stepper and calls the
// implementation above.
// ---------------------------------------------------------------------------
namespace {

using ceode::Stepper;

Stepper* MriContent(MRIStepInnerStepper s) {
  void* content = nullptr;
  return MRIStepInnerStepper_GetContent(s, &content) == 0 ? static_cast<Stepper*>(content)
                                                          : nullptr;
}

int MriEvolve(MRIStepInnerStepper s, sunrealtype t0, sunrealtype tout, N_Vector y) {
  static const char* func = "CEodeMRIStepInnerEvolve";
  Stepper* st = MriContent(s);
  if (st == nullptr) return CE_MEM_NULL;
  sunrealtype tshift = 0, tscale = 1;
  N_Vector* F = nullptr;
  int nf = 0;
  if (MRIStepInnerStepper_GetForcingData(s, &tshift, &tscale, &F, &nf) != 0) nf = 0;
  int flag = ceode::StepperSetForcing(st, tshift, tscale, F, nf, func);
  if (flag == CE_SUCCESS) flag = ceode::StepperReset(st, t0, y, func);
  if (flag == CE_SUCCESS) flag = ceode::StepperEvolve(st, tout, y, func);
  return flag;
}

int MriFullRhs(MRIStepInnerStepper s, sunrealtype t, N_Vector y, N_Vector f, int /*mode*/) {
  Stepper* st = MriContent(s);
  return st == nullptr ? CE_MEM_NULL : ceode::StepperFullRhs(st, t, y, f, "CEodeMRIStepFullRhs");
}

int MriReset(MRIStepInnerStepper s, sunrealtype tR, N_Vector yR) {
  Stepper* st = MriContent(s);
  return st == nullptr ? CE_MEM_NULL : ceode::StepperReset(st, tR, yR, "CEodeMRIStepReset");
}

#ifdef CEODE_HAVE_SUNSTEPPER
Stepper* SunContent(SUNStepper s) {
  void* content = nullptr;
  return SUNStepper_GetContent(s, &content) == SUN_SUCCESS ? static_cast<Stepper*>(content)
                                                           : nullptr;
}

// SUNStepper calls return a SUNErrCode; CEODE's own flag is the stepper's last flag.
SUNErrCode SunResult(SUNStepper s, int flag) {
  SUNStepper_SetLastFlag(s, flag);
  return flag < 0 ? SUN_ERR_OP_FAIL : SUN_SUCCESS;
}

SUNErrCode SunEvolve(SUNStepper s, sunrealtype tout, N_Vector vret, sunrealtype* tret) {
  Stepper* st = SunContent(s);
  if (st == nullptr || tret == nullptr) return SUN_ERR_ARG_CORRUPT;
  const int flag = ceode::StepperEvolve(st, tout, vret, "CEodeSUNStepperEvolve");
  *tret = st->t_own;
  return SunResult(s, flag);
}

SUNErrCode SunFullRhs(SUNStepper s, sunrealtype t, N_Vector v, N_Vector f, SUNFullRhsMode) {
  Stepper* st = SunContent(s);
  if (st == nullptr) return SUN_ERR_ARG_CORRUPT;
  return SunResult(s, ceode::StepperFullRhs(st, t, v, f, "CEodeSUNStepperFullRhs"));
}

SUNErrCode SunReset(SUNStepper s, sunrealtype tR, N_Vector vR) {
  Stepper* st = SunContent(s);
  if (st == nullptr) return SUN_ERR_ARG_CORRUPT;
  return SunResult(s, ceode::StepperReset(st, tR, vR, "CEodeSUNStepperReset"));
}

SUNErrCode SunSetStopTime(SUNStepper s, sunrealtype tstop) {
  Stepper* st = SunContent(s);
  if (st == nullptr) return SUN_ERR_ARG_CORRUPT;
  ceode::StepperSetStopTime(st, tstop);
  return SUN_SUCCESS;
}

SUNErrCode SunSetStepDirection(SUNStepper s, sunrealtype stepdir) {
  Stepper* st = SunContent(s);
  if (st == nullptr) return SUN_ERR_ARG_CORRUPT;
  const int flag = ceode::StepperSetStepDirection(st, stepdir, "CEodeSUNStepperSetStepDirection");
  SUNStepper_SetLastFlag(s, flag);
  return flag < 0 ? SUN_ERR_ARG_OUTOFRANGE : SUN_SUCCESS;
}

SUNErrCode SunSetForcing(SUNStepper s, sunrealtype tshift, sunrealtype tscale, N_Vector* F,
                         int nf) {
  Stepper* st = SunContent(s);
  if (st == nullptr) return SUN_ERR_ARG_CORRUPT;
  return SunResult(s,
                   ceode::StepperSetForcing(st, tshift, tscale, F, nf, "CEodeSUNStepperForcing"));
}

SUNErrCode SunGetNumSteps(SUNStepper s, suncountertype* nst) {
  Stepper* st = SunContent(s);
  if (st == nullptr || nst == nullptr) return SUN_ERR_ARG_CORRUPT;
  *nst = static_cast<suncountertype>(st->ce->nst);
  return SUN_SUCCESS;
}

SUNErrCode SunDestroy(SUNStepper s) {
  ceode::StepperDestroy(SunContent(s));
  return SUNStepper_SetContent(s, nullptr);
}

int SunAttach(SUNStepper s, Stepper* st) {
  int rv = SUNStepper_SetContent(s, st);
  if (rv == 0) rv = SUNStepper_SetEvolveFn(s, SunEvolve);
  if (rv == 0) rv = SUNStepper_SetFullRhsFn(s, SunFullRhs);
  if (rv == 0) rv = SUNStepper_SetResetFn(s, SunReset);
  if (rv == 0) rv = SUNStepper_SetStopTimeFn(s, SunSetStopTime);
  if (rv == 0) rv = SUNStepper_SetStepDirectionFn(s, SunSetStepDirection);
  if (rv == 0) rv = SUNStepper_SetForcingFn(s, SunSetForcing);
  if (rv == 0) rv = SUNStepper_SetGetNumStepsFn(s, SunGetNumSteps);
  if (rv == 0) rv = SUNStepper_SetDestroyFn(s, SunDestroy);
  return rv;
}
#endif

// The preamble of the two stepper constructors: the access guard, the output pointer, the
// stepper's own state.
template <class Handle>
int BeginCreate(void* ce_mem, Handle* out, const char* func, CEodeMemRec** ce, Stepper** st) {
  const int flag = ceode::Access(ce_mem, func, ce, true);
  if (flag != CE_SUCCESS) return flag;
  if (out == nullptr) return ceode::ProcessError(*ce, CE_ILL_INPUT, func, "stepper = NULL.");
  *out = nullptr;
  return ceode::StepperCreate(*ce, st, func);
}

}  // namespace

extern "C" {

int CEodeCreateMRIStepInnerStepper(void* ce_mem, MRIStepInnerStepper* stepper) {
  CEodeMemRec* ce = nullptr;
  Stepper* st = nullptr;
  const int flag = BeginCreate(ce_mem, stepper, __func__, &ce, &st);
  if (flag != CE_SUCCESS) return flag;
  int rv = MRIStepInnerStepper_Create(ce->sunctx, stepper);
  if (rv == 0) rv = MRIStepInnerStepper_SetContent(*stepper, st);
  if (rv == 0) rv = MRIStepInnerStepper_SetEvolveFn(*stepper, MriEvolve);
  if (rv == 0) rv = MRIStepInnerStepper_SetFullRhsFn(*stepper, MriFullRhs);
  if (rv == 0) rv = MRIStepInnerStepper_SetResetFn(*stepper, MriReset);
  if (rv != 0) {
    ceode::StepperDestroy(st);
    if (*stepper != nullptr) MRIStepInnerStepper_Free(stepper);
    return ceode::ProcessError(ce, CE_MEM_FAIL, __func__,
                               "MRIStepInnerStepper_Create or a setter failed (%d).", rv);
  }
  return CE_SUCCESS;
}

int CEodeFreeMRIStepInnerStepper(MRIStepInnerStepper* stepper) {
  if (stepper == nullptr || *stepper == nullptr) return CE_SUCCESS;
  ceode::StepperDestroy(MriContent(*stepper));
  MRIStepInnerStepper_SetContent(*stepper, nullptr);
  MRIStepInnerStepper_Free(stepper);
  return CE_SUCCESS;
}

int CEodeGetNumInnerRestarts(void* ce_mem, long int* nrestarts) {
  CEodeMemRec* ce = nullptr;
  const int flag = ceode::Access(ce_mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (nrestarts == nullptr) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__, "nrestarts = NULL.");
  }
  const Stepper* st = ceode::AttachedStepper(ce);
  if (st == nullptr) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "This CEODE memory drives no inner stepper.");
  }
  *nrestarts = ceode::StepperNumRestarts(st);
  return CE_SUCCESS;
}

#ifdef CEODE_HAVE_SUNSTEPPER
int CEodeCreateSUNStepper(void* ce_mem, SUNStepper* stepper) {
  CEodeMemRec* ce = nullptr;
  Stepper* st = nullptr;
  const int flag = BeginCreate(ce_mem, stepper, __func__, &ce, &st);
  if (flag != CE_SUCCESS) return flag;
  int rv = SUNStepper_Create(ce->sunctx, stepper);
  if (rv == 0) rv = SunAttach(*stepper, st);
  if (rv != 0) {
    ceode::StepperDestroy(st);
    if (*stepper != nullptr) {
      SUNStepper_SetContent(*stepper, nullptr);
      SUNStepper_Destroy(stepper);
    }
    return ceode::ProcessError(ce, CE_MEM_FAIL, __func__,
                               "SUNStepper_Create or a setter failed (%d).", rv);
  }
  return CE_SUCCESS;
}
#endif

}  // extern "C"
