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

// The two halves of a first-order vector y = [x; v].
struct Halves {
  N_Vector x = nullptr;
  N_Vector v = nullptr;
};
using Views = N_Vector[2];  // SplitHalves' windows on a serial y

struct Stepper {
  CEodeMemRec* ce = nullptr;
  CEodeRhsFn f = nullptr;  // the memory's f and user_data at creation: a change is refused
  void* user_data = nullptr;
  sunrealtype h_max = 0;  // the user's inner step: the largest one taken
  // Tolerances were set on the memory: the inner steps follow its error control, each slow
  // stage starting from the last inner step (h_last) and ending on the stage's time exactly.
  bool adaptive = false;
  sunrealtype h_last = 0;
  N_Vector y_own = nullptr;
  sunrealtype t_own = 0;
  bool have_state = false;
  sunrealtype tstop = 0;
  bool tstop_set = false;
  Views own_view = {}, io_view = {}, io2_view = {};
  Views forcing_view[kMaxForcing] = {};
  Forcing forcing;          // Adapters::forcing while the stepper exists; its end is what the
                            // next restart reuses, valid while the owned state stays unchanged
  N_Vector u = nullptr;     // x' = v + r_x during an inner run
  N_Vector ytmp = nullptr;  // for the comparison of a reset state with the owned one
  long int nrestarts = 0;
};

void StepperDestroy(Stepper* st) {
  if (st == nullptr) return;
  CEodeMemRec* ce = st->ce;
  if (ce != nullptr && ce->adapters.stepper == st) {  // the memory evaluates f unforced again
    ce->adapters.stepper = nullptr;
    ce->adapters.forcing = nullptr;
    SelectRhs(ce);
  }
  const auto destroy = [](N_Vector w) {
    if (w != nullptr) N_VDestroy(w);
  };
  for (N_Vector w : {st->y_own, st->u, st->ytmp}) destroy(w);
  for (const Views* vw : {&st->own_view, &st->io_view, &st->io2_view})
    std::for_each(*vw, *vw + 2, destroy);
  for (const Views& vw : st->forcing_view) std::for_each(vw, vw + 2, destroy);
  FreeForcing(&st->forcing);
  delete st;
}

// y = [x; v] as views of the stepper's (SplitFirstOrder: the one check of its vectors).
int SplitVector(Stepper* st, N_Vector y, Views& view, Halves* out, const char* func) {
  return SplitFirstOrder(st->ce, y, view, &out->x, &out->v, func);
}

int Allocate(Stepper* st, N_Vector y, const char* func) {
  st->y_own = CloneVector(y);
  st->ytmp = CloneVector(y);
  st->u = CloneVector(st->ce->xcur);
  if (st->y_own == nullptr || st->ytmp == nullptr || st->u == nullptr) {
    return ProcessError(st->ce, CE_MEM_FAIL, func, "Out of memory.");
  }
  return CE_SUCCESS;
}

// Problems the inner stepper cannot take (the forcing adds to x'' directly: a mass matrix would
// have to multiply it, constraints would fight it), and, with st, a memory changed behind it.
int StepperCheckMemory(CEodeMemRec* ce, const Stepper* st, const char* func) {
  if (HasMassMatrix(ce) || HasConstraints(ce)) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "The inner stepper needs M = I and no constraints (the MRI forcing is "
                        "added to the acceleration): divide f by M in your right-hand side.");
  }
  if (ce->h <= 0 && !AdaptOn(ce)) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "No inner step: call CEodeSetFixedStep(ce_mem, h) first (h is the "
                        "largest inner step), or set tolerances (CEodeSStolerances).");
  }
  if (st != nullptr && (ce->f != st->f || ce->user_data != st->user_data)) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "The CEODE memory of this stepper was changed by CEodeInit or "
                        "CEodeSetUserData after the stepper was created: free the stepper and "
                        "create a new one (put your data in user_data before creating it).");
  }
  return CE_SUCCESS;
}

int StepperCreate(CEodeMemRec* ce, Stepper** out, const char* func) {
  int flag = StepperCheckMemory(ce, nullptr, func);
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
  st->adaptive = AdaptOn(ce);
  ce->adapters.stepper = st;
  ce->adapters.forcing = &st->forcing;  // no terms yet: f is evaluated as it is
  *out = st;
  return CE_SUCCESS;
}

// The stepper copies the state: it owns what it restarts from.
int StepperReset(Stepper* st, sunrealtype tR, N_Vector yR, const char* func) {
  Halves in;
  int flag = SplitVector(st, yR, st->io_view, &in, func);
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
  bool& keep = st->forcing.end.valid;
  if (keep) {
    N_VLinearSum(1, yR, -1, st->y_own, st->ytmp);
    const sunrealtype tol = 100 * SUN_UNIT_ROUNDOFF * (std::fabs(tR) + std::fabs(st->t_own));
    keep = std::fabs(tR - st->t_own) <= tol && N_VMaxNorm(st->ytmp) == 0;
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
  int flag = CE_SUCCESS;
  for (int k = 0; k < nf && flag == CE_SUCCESS; ++k) {
    flag = SplitFirstOrder(st->ce, F[k], st->forcing_view[k], &Fx[k], &Fv[k], func);
  }
  if (flag != CE_SUCCESS) nf = 0;  // no forcing rather than half of one
  const int set = SetForcing(st->ce, &st->forcing, tshift, tscale, nf, Fx, Fv, func);
  return flag != CE_SUCCESS ? flag : set;
}

// Restart CEODE at (t0, x, u = v + r_x(t0)) with the largest step <= h_max that
// lands on tout, keeping the counters and the guard's frequency.
int RestartInner(Stepper* st, sunrealtype t0, sunrealtype tout, const Halves& own,
                 const char* func) {
  CEodeMemRec* ce = st->ce;
  const sunrealtype span = tout - t0;
  int flag = CE_SUCCESS;
  if (st->adaptive) {
    flag = CEodeSetStopTime(ce, tout);
    if (flag == CE_SUCCESS) flag = CEodeSetInitStep(ce, std::min(st->h_last, span));
  } else {
    const long int nsub = std::max(1L, static_cast<long int>(std::ceil(span / st->h_max - 1e-8)));
    flag = CEodeSetFixedStep(ce, span / static_cast<sunrealtype>(nsub));
  }
  if (flag != CE_SUCCESS) return flag;
  ForcingX(st->forcing, t0, 1, own.v, 1, st->u);
  ++st->nrestarts;
  ResetOptions opt;
  opt.keep_frequency = true;  // the first run estimates omega_max, later ones check h against it
  if (CanCarry(ce, st->forcing, t0)) {
    opt.history = [&] { return CarryHistory(ce, &st->forcing, t0, own.x, own.v, func); };
  }
  st->forcing.end.valid = false;
  return Reset(ce, func, t0, own.x, st->u, opt);
}

// Integrates the owned state from t_own to tout (> t_own) and copies it to y.
int StepperEvolve(Stepper* st, sunrealtype tout, N_Vector y, const char* func) {
  CEodeMemRec* ce = st->ce;
  int flag = StepperCheckMemory(ce, st, func);
  if (flag != CE_SUCCESS) return flag;
  Halves own, io;
  if ((flag = SplitVector(st, y, st->io_view, &io, func)) != CE_SUCCESS) return flag;
  if (st->y_own == nullptr && (flag = Allocate(st, y, func)) != CE_SUCCESS) return flag;
  if ((flag = SplitVector(st, st->y_own, st->own_view, &own, func)) != CE_SUCCESS) return flag;
  if (!st->have_state) {
    // Without a reset, the stepper starts where the CEODE memory stands (CEodeInit's x0, v0 at
    // t0), as ARKODE's own SUNSteppers do; y only gives the vector shape.
    N_VScale(1, ce->xcur, own.x);
    N_VScale(1, ce->D[1], own.v);
    st->t_own = ce->tcur;
    st->have_state = true;
  }
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
  if (tout - t0 > tol) {
    if ((flag = RestartInner(st, t0, tout, own, func)) != CE_SUCCESS) return flag;
    sunrealtype tret = t0;
    // Events of this memory's root functions are not the outer method's: the inner step goes on
    // through them to tout.
    do {
      flag = CEodeEvolve(ce, tout, own.x, st->u, &tret, CE_NORMAL);
    } while (flag == CE_ROOT_RETURN);
    if (flag < 0) return flag;
    if (st->adaptive) CEodeGetLastStep(ce, &st->h_last);
    // The output is the method's own state at tcur (no interpolation) only if the run ended on
    // a step; only then is the history's D_2 the acceleration at the returned state.
    if (OnGrid(ce, tout)) KeepEnd(ce, &st->forcing);
    ForcingX(st->forcing, tout, 1, st->u, -1, own.v);
    st->t_own = tout;
  }
  if (!IsFinite(st->y_own)) {  // a forcing that overflows over the step, as CEodeEvolve's outputs
    return ProcessError(ce, CE_UNSTABLE, func,
                        "The inner state at t = %.17g is not finite: the forcing or h overflowed "
                        "the state; reduce the slow step or rescale the forcing.",
                        static_cast<double>(st->t_own));
  }
  N_VScale(1, st->y_own, y);
  return CE_SUCCESS;
}

// The unforced fast right-hand side f = [v; g(t, x, v)].
int StepperFullRhs(Stepper* st, sunrealtype t, N_Vector y, N_Vector f, const char* func) {
  Halves in, out;
  int flag = SplitVector(st, y, st->io_view, &in, func);
  if (flag != CE_SUCCESS) return flag;
  if ((flag = SplitVector(st, f, st->io2_view, &out, func)) != CE_SUCCESS) return flag;
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

// --- Version-specific glue: each callback unpacks its stepper and calls the above. ---
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
  int flag = StepperSetForcing(st, tshift, tscale, F, nf, func);
  if (flag == CE_SUCCESS) flag = StepperReset(st, t0, y, func);
  if (flag == CE_SUCCESS) flag = StepperEvolve(st, tout, y, func);
  return flag;
}

int MriFullRhs(MRIStepInnerStepper s, sunrealtype t, N_Vector y, N_Vector f, int /*mode*/) {
  Stepper* st = MriContent(s);
  return st == nullptr ? CE_MEM_NULL : StepperFullRhs(st, t, y, f, "CEodeMRIStepFullRhs");
}

int MriReset(MRIStepInnerStepper s, sunrealtype tR, N_Vector yR) {
  Stepper* st = MriContent(s);
  return st == nullptr ? CE_MEM_NULL : StepperReset(st, tR, yR, "CEodeMRIStepReset");
}

#ifdef CEODE_HAVE_SUNSTEPPER
Stepper* SunContent(SUNStepper s) {
  void* content = nullptr;
  return SUNStepper_GetContent(s, &content) == SUN_SUCCESS ? static_cast<Stepper*>(content)
                                                           : nullptr;
}

// Runs call(st) on the stepper of s (SUN_ERR_ARG_CORRUPT without one). CEODE's own flag becomes
// the stepper's last flag; a failure returns `fail`.
template <class Call>
SUNErrCode OnSun(SUNStepper s, Call call, SUNErrCode fail = SUN_ERR_OP_FAIL) {
  Stepper* st = SunContent(s);
  if (st == nullptr) return SUN_ERR_ARG_CORRUPT;
  const int flag = call(st);
  SUNStepper_SetLastFlag(s, flag);
  return flag < 0 ? fail : SUN_SUCCESS;
}

SUNErrCode SunEvolve(SUNStepper s, sunrealtype tout, N_Vector vret, sunrealtype* tret) {
  if (tret == nullptr) return SUN_ERR_ARG_CORRUPT;
  return OnSun(s, [&](Stepper* st) {
    const int flag = StepperEvolve(st, tout, vret, "CEodeSUNStepperEvolve");
    *tret = st->t_own;
    return flag;
  });
}

SUNErrCode SunFullRhs(SUNStepper s, sunrealtype t, N_Vector v, N_Vector f, SUNFullRhsMode) {
  return OnSun(s,
               [&](Stepper* st) { return StepperFullRhs(st, t, v, f, "CEodeSUNStepperFullRhs"); });
}

SUNErrCode SunReset(SUNStepper s, sunrealtype tR, N_Vector vR) {
  return OnSun(s, [&](Stepper* st) { return StepperReset(st, tR, vR, "CEodeSUNStepperReset"); });
}

SUNErrCode SunSetStopTime(SUNStepper s, sunrealtype tstop) {
  return OnSun(s, [&](Stepper* st) {
    const int flag = ValidateTime(st->ce, "CEodeSUNStepperSetStopTime", "tstop", tstop);
    if (flag != CE_SUCCESS) return flag;
    st->tstop = tstop;
    st->tstop_set = true;
    return CE_SUCCESS;
  });
}

SUNErrCode SunSetStepDirection(SUNStepper s, sunrealtype stepdir) {
  const auto check = [&](Stepper* st) {
    if (std::isnan(stepdir)) {
      return ProcessError(st->ce, CE_ILL_INPUT, "CEodeSUNStepperSetStepDirection",
                          "Step direction NaN: pass a positive direction.");
    }
    if (!(stepdir < 0)) return CE_SUCCESS;
    return ProcessError(st->ce, CE_BAD_T, "CEodeSUNStepperSetStepDirection",
                        "Step direction %g: CEODE integrates forward only (a splitting method "
                        "of order > 2 takes negative substeps); use a second-order splitting "
                        "such as Strang, or another inner stepper.",
                        static_cast<double>(stepdir));
  };
  return OnSun(s, check, SUN_ERR_ARG_OUTOFRANGE);
}

SUNErrCode SunSetForcing(SUNStepper s, sunrealtype tshift, sunrealtype tscale, N_Vector* F,
                         int nf) {
  return OnSun(s, [&](Stepper* st) {
    return StepperSetForcing(st, tshift, tscale, F, nf, "CEodeSUNStepperForcing");
  });
}

SUNErrCode SunGetNumSteps(SUNStepper s, suncountertype* nst) {
  if (nst == nullptr) return SUN_ERR_ARG_CORRUPT;
  return OnSun(s, [&](Stepper* st) {
    *nst = static_cast<suncountertype>(st->ce->nst);
    return CE_SUCCESS;
  });
}

SUNErrCode SunDestroy(SUNStepper s) {
  StepperDestroy(SunContent(s));
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
  const int flag = Access(ce_mem, func, ce, true);
  if (flag != CE_SUCCESS) return flag;
  if (out == nullptr) return ProcessError(*ce, CE_ILL_INPUT, func, "stepper = NULL.");
  *out = nullptr;
  return StepperCreate(*ce, st, func);
}

}  // namespace
}  // namespace ceode

using ceode::Stepper;

extern "C" {

int CEodeCreateMRIStepInnerStepper(void* ce_mem, MRIStepInnerStepper* stepper) {
  CEodeMemRec* ce = nullptr;
  Stepper* st = nullptr;
  const int flag = ceode::BeginCreate(ce_mem, stepper, __func__, &ce, &st);
  if (flag != CE_SUCCESS) return flag;
  int rv = MRIStepInnerStepper_Create(ce->sunctx, stepper);
  if (rv == 0) rv = MRIStepInnerStepper_SetContent(*stepper, st);
  if (rv == 0) rv = MRIStepInnerStepper_SetEvolveFn(*stepper, ceode::MriEvolve);
  if (rv == 0) rv = MRIStepInnerStepper_SetFullRhsFn(*stepper, ceode::MriFullRhs);
  if (rv == 0) rv = MRIStepInnerStepper_SetResetFn(*stepper, ceode::MriReset);
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
  ceode::StepperDestroy(ceode::MriContent(*stepper));
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
  const auto* st = static_cast<const Stepper*>(ce->adapters.stepper);
  if (st == nullptr) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "This CEODE memory drives no inner stepper.");
  }
  *nrestarts = st->nrestarts;
  return CE_SUCCESS;
}

#ifdef CEODE_HAVE_SUNSTEPPER
int CEodeCreateSUNStepper(void* ce_mem, SUNStepper* stepper) {
  CEodeMemRec* ce = nullptr;
  Stepper* st = nullptr;
  const int flag = ceode::BeginCreate(ce_mem, stepper, __func__, &ce, &st);
  if (flag != CE_SUCCESS) return flag;
  int rv = SUNStepper_Create(ce->sunctx, stepper);
  if (rv == 0) rv = ceode::SunAttach(*stepper, st);
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
