// Creation, initialisation, time integration and destruction of CEODE memory,
// and the single error path. The step itself lives in ceode_step.cpp.
#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <new>

#include "ceode_adapt.hpp"
#include "ceode_impl.hpp"
#include "ceode_kernels.hpp"

namespace ceode {

int ProcessError(CEodeMemRec* ce, int flag, const char* func, const char* fmt, ...) {
  char msg[1024];
  va_list ap;
  va_start(ap, fmt);
  std::vsnprintf(msg, sizeof(msg), fmt, ap);
  va_end(ap);
  if (ce == nullptr) {
    std::fprintf(stderr, "\n[CEODE ERROR]  %s (%s)\n  %s\n\n", func, FlagName(flag), msg);
    return flag;
  }
  try {
    ce->last_msg = msg;
  } catch (...) {  // no exception crosses the C API, even out of memory
    ce->last_msg.clear();
  }
  if (ce->ehfun != nullptr) {
    ce->ehfun(flag, "CEODE", func, msg, ce->eh_data);
  } else if (ce->to_context) {
    sun::ReportToContext(ce->sunctx, flag, FlagName(flag), func, msg);
  } else if (ce->errfp != nullptr) {
    std::fprintf(ce->errfp, "\n[CEODE %s]  %s (%s)\n  %s\n\n",
                 flag == CE_WARNING ? "WARNING" : "ERROR", func, FlagName(flag), msg);
  }
  return flag;
}

int AccessFailed(CEodeMemRec* ce, const char* func) {
  if (ce == nullptr) {
    return ProcessError(nullptr, CE_MEM_NULL, func,
                        "The CEODE memory is NULL: create it with CEodeCreate first.");
  }
  return ProcessError(ce, CE_NO_MALLOC, func,
                      "The CEODE memory is not initialised: call CEodeInit first.");
}

void Restart(CEodeMemRec* ce) {
  ce->started = false;
  StepRestart(ce);
  ce->adapters.history_preset = false;  // it holds for the configuration it was made for
}

bool IsFinite(N_Vector v) {
  // NaN propagates through the L1 norm; +Inf is either an Inf entry or the sum overflowing
  // (finite entries near 1e308), which the max norm tells apart.
  const sunrealtype l1 = N_VL1Norm(v);
  if (std::isfinite(l1)) return true;
  return !std::isnan(l1) && std::isfinite(N_VMaxNorm(v));
}

int ReportNotFinite(CEodeMemRec* ce, const char* func, N_Vector xout) {
  return ProcessError(ce, CE_UNSTABLE, func,
                      "The %s at t = %.17g is not finite although every step passed its growth "
                      "check: h = %g is beyond what %s can represent (its velocity weights "
                      "overflow); reduce h or choose another set, then call CEodeReInit.",
                      IsFinite(xout) ? "velocity" : "position", static_cast<double>(ce->tcur),
                      static_cast<double>(ce->h), ce->method_name.c_str());
}

namespace {

// Every object whose size is the problem's: the modules' workspaces and the vectors.
void FreeSized(CEodeMemRec* ce) {
  NlsFree(ce);
  PcFree(ce);
  LsFree(ce);
  ConstrFree(ce);
  GuardFree(ce);
  AdaptFree(ce);
  RootFreeVectors(ce);
  FreeVectors(ce);
}

int CheckInitialData(CEodeMemRec* ce, const char* func, N_Vector x0, N_Vector v0) {
  if (x0 == nullptr || v0 == nullptr) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "x0 = NULL or v0 = NULL: pass both initial vectors.");
  }
  if (N_VGetLength(x0) != N_VGetLength(v0)) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "x0 has %ld entries but v0 has %ld: they must have the same length.",
                        static_cast<long>(N_VGetLength(x0)), static_cast<long>(N_VGetLength(v0)));
  }
  if (!IsFinite(x0) || !IsFinite(v0)) {
    return ProcessError(ce, CE_ILL_INPUT, func, "x0 or v0 contains NaN or Inf.");
  }
  return CE_SUCCESS;
}

int CheckOutputVector(CEodeMemRec* ce, const char* func, N_Vector y, const char* name) {
  if (y == nullptr) {
    return ProcessError(ce, CE_ILL_INPUT, func, "%s = NULL: pass a vector cloned from x0.", name);
  }
  if (VectorLength(y) != ce->n) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "%s has %ld entries but the problem has %ld: clone it from x0.", name,
                        static_cast<long>(N_VGetLength(y)), static_cast<long>(ce->n));
  }
  return CE_SUCCESS;
}

// Builds whatever the configuration needs (linear, nonlinear, constraint solvers)
// and the starting history; runs once per configuration change.
int Prepare(CEodeMemRec* ce, const char* func) {
  if (ce->h <= 0 && !AdaptOn(ce)) {
    return ProcessError(
        ce, CE_ILL_INPUT, func,
        "No step size: call CEodeSetFixedStep(mem, h) with h > 0 before CEodeEvolve.");
  }
  if (ce->started) return CE_SUCCESS;
  // First: a detected velocity dependence needs the solvers and checks of a declared one.
  int flag = DetectVelocityDependence(ce);
  if (flag == CE_SUCCESS && NeedsSolverWork(ce)) flag = AllocSolverWork(ce, func);
  if (flag == CE_SUCCESS) flag = ValidateConfiguration(ce, func);
  if (flag == CE_SUCCESS) flag = IcCheck(ce, func);
  if (flag == CE_SUCCESS) flag = LsInitialize(ce, func);
  if (flag != CE_SUCCESS) return flag;
  flag = NlsInitialize(ce, func);
  if (flag != CE_SUCCESS) return flag;
  flag = ConstrInitialize(ce, func);
  if (flag != CE_SUCCESS) return flag;
  flag = StartMethod(ce);
  return flag == CE_SUCCESS ? ValidateStart(ce, func) : flag;
}

int CheckEvolveArgs(CEodeMemRec* ce, const char* func, sunrealtype tout, N_Vector xout,
                    N_Vector vout, const sunrealtype* tret, int itask) {
  int flag = CheckOutputVector(ce, func, xout, "xout");
  if (flag == CE_SUCCESS) flag = CheckOutputVector(ce, func, vout, "vout");
  if (flag != CE_SUCCESS) return flag;
  if (tret == nullptr) return ProcessError(ce, CE_ILL_INPUT, func, "tret = NULL.");
  if (itask != CE_NORMAL && itask != CE_ONE_STEP) {
    return ProcessError(ce, CE_ILL_INPUT, func, "itask = %d: use CE_NORMAL or CE_ONE_STEP.", itask);
  }
  return std::isfinite(tout) ? CE_SUCCESS : ValidateTime(ce, func, "tout", tout);
}

void ReturnCurrentState(const CEodeMemRec* ce, N_Vector xout, N_Vector vout, sunrealtype* tret) {
  N_VScale(1.0, ce->xcur, xout);
  N_VScale(1.0, ce->D[1], vout);
  *tret = ce->tcur;
}

// The end of a fixed-step CEodeEvolve that reached target: the outputs there (the method's own
// values when target is tcur), tested as they are written.
__attribute__((always_inline)) inline int ReturnAtTarget(CEodeMemRec* ce, const char* func,
                                                         sunrealtype target, N_Vector xout,
                                                         N_Vector vout, sunrealtype* tret,
                                                         bool hit_tstop) {
  // On the grid: the method's own values, returned at tcur, or at the stop time itself, which
  // CE_TSTOP_RETURN promises exactly.
  const sunrealtype s = OnGrid(ce, target) ? 0 : target - ce->tcur;
  const bool finite =
      s == 0 ? CopyPairFinite(ce->xcur, ce->D[1], xout, vout) : OutputState(ce, s, xout, vout);
  if (s == 0 && !hit_tstop) target = ce->tcur;
  *tret = target;
  ce->tretlast = target;
  if (hit_tstop) ce->tstop_set = false;
  return CheckReturned(ce, func, finite, xout, hit_tstop ? CE_TSTOP_RETURN : CE_SUCCESS);
}

// Where this call ends: tout (CE_NORMAL) or one step on (CE_ONE_STEP), cut at the stop time.
int EvolveTarget(CEodeMemRec* ce, const char* func, sunrealtype tout, int itask,
                 sunrealtype* target, bool* hit_tstop) {
  const sunrealtype h = ce->h;
  const sunrealtype troundoff = 100 * SUN_UNIT_ROUNDOFF * (std::fabs(ce->tcur) + h);
  if (itask == CE_NORMAL && tout < ce->tcur - troundoff) {
    return ProcessError(ce, CE_BAD_T, func,
                        "tout = %.17g is behind the current time %.17g: CEODE integrates "
                        "forward only; call CEodeReInit to go back.",
                        static_cast<double>(tout), static_cast<double>(ce->tcur));
  }
  *target = (itask == CE_NORMAL) ? tout : ce->tcur + h;
  *hit_tstop = false;
  if (!ce->tstop_set) return CE_SUCCESS;
  if (ce->tstop < ce->tcur - troundoff) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "The stop time %.17g is behind the current time %.17g.",
                        static_cast<double>(ce->tstop), static_cast<double>(ce->tcur));
  }
  if (*target >= ce->tstop - troundoff) {
    *target = ce->tstop;
    *hit_tstop = true;
  }
  return CE_SUCCESS;
}

int TooMuchWork(CEodeMemRec* ce, const char* func, long int nsteps, sunrealtype target) {
  return ProcessError(ce, CE_TOO_MUCH_WORK, func,
                      "%ld steps taken before reaching tout = %.17g (t = %.17g): raise "
                      "the limit with CEodeSetMaxNumSteps or use a larger h.",
                      nsteps, static_cast<double>(target), static_cast<double>(ce->tcur));
}

// Steps while the target lies beyond the current interval [tcur, tcur + h].
int StepTo(CEodeMemRec* ce, const char* func, sunrealtype target) {
  long int nsteps = 0;
  while (StepsRemain(ce, target)) {
    if (nsteps >= ce->mxstep) return TooMuchWork(ce, func, nsteps, target);
    long int taken = 0;
    const int flag = TakeSteps(ce, target, ce->mxstep - nsteps, &taken);
    nsteps += taken;
    if (flag != CE_SUCCESS) return flag;
  }
  return CE_SUCCESS;
}

// StepTo with root finding: every interval [tcur, tcur + h] (up to target) is checked before
// the step past it, one step at a time. CE_ROOT_RETURN: a root at RootTime, inside the interval.
int StepToRoots(CEodeMemRec* ce, const char* func, sunrealtype target) {
  long int nsteps = 0;
  for (;;) {
    int flag = RootCheck(ce, std::min(ce->tcur + ce->h, target), func);
    if (flag != CE_SUCCESS) return flag;
    if (!StepsRemain(ce, target)) return CE_SUCCESS;
    if (nsteps >= ce->mxstep) return TooMuchWork(ce, func, nsteps, target);
    long int taken = 0;
    flag = TakeSteps(ce, target, 1, &taken);
    nsteps += taken;
    if (flag != CE_SUCCESS) return flag;
  }
}

// The state at the root, as its time.
int ReturnRoot(CEodeMemRec* ce, N_Vector xout, N_Vector vout, sunrealtype* tret) {
  const sunrealtype tr = RootTime(ce);
  Interpolate(ce, tr - ce->tcur, 0, xout);
  Interpolate(ce, tr - ce->tcur, 1, vout);
  *tret = ce->tretlast = tr;
  return CE_ROOT_RETURN;
}

// CEodeEvolve after the access guard: the arguments, the (re)start, then the steps to the target
// and the outputs there (or error control's own loop).
__attribute__((noinline)) int Evolve(CEodeMemRec* ce, const char* func, sunrealtype tout,
                                     N_Vector xout, N_Vector vout, sunrealtype* tret, int itask) {
  int flag = CheckEvolveArgs(ce, func, tout, xout, vout, tret, itask);
  if (flag != CE_SUCCESS) return flag;
  if (ce->adapt != nullptr) AdaptSetTarget(ce, tout);
  flag = Prepare(ce, func);
  if (flag == CE_SUCCESS && ce->guard.pending) flag = GuardCheckPending(ce, func);
  if (flag < 0) {
    // Nothing was integrated: as CVODE, the outputs are left alone and *tret is the current time.
    *tret = ce->tcur;
    return flag;
  }
  if (AdaptOn(ce)) return AdaptEvolve(ce, func, tout, xout, vout, tret, itask);
  sunrealtype target = 0;
  bool hit_tstop = false;
  flag = EvolveTarget(ce, func, tout, itask, &target, &hit_tstop);
  if (flag != CE_SUCCESS) {
    *tret = ce->tcur;
    return flag;
  }
  flag = ce->root == nullptr ? StepTo(ce, func, target) : StepToRoots(ce, func, target);
  if (flag == CE_ROOT_RETURN) return ReturnRoot(ce, xout, vout, tret);
  if (flag != CE_SUCCESS) {
    // The last good state is returned; the memory stays usable.
    ReturnCurrentState(ce, xout, vout, tret);
    ce->tretlast = ce->tcur;
    return flag;
  }
  return ReturnAtTarget(ce, func, target, xout, vout, tret, hit_tstop);
}

// CE_NORMAL on the direct path: what EvolveTarget and StepTo do for target = tout (a tout behind
// tcur takes the general path, which reports it).
inline int EvolveToTout(CEodeMemRec* ce, const char* func, sunrealtype tout, N_Vector xout,
                        N_Vector vout, sunrealtype* tret) {
  const sunrealtype troundoff = 100 * SUN_UNIT_ROUNDOFF * (std::fabs(ce->tcur) + ce->h);
  if (tout < ce->tcur - troundoff) return Evolve(ce, func, tout, xout, vout, tret, CE_NORMAL);
  const int flag = StepTo(ce, func, tout);
  if (flag != CE_SUCCESS) {  // as CEodeEvolve's general path: the last good state
    ReturnCurrentState(ce, xout, vout, tret);
    ce->tretlast = ce->tcur;
    return flag;
  }
  return ReturnAtTarget(ce, func, tout, xout, vout, tret, false);
}

}  // namespace

// CE_NORMAL (and any other itask, which the general path refuses) where NormalEvolve has no
// direct form: the direct path where the call has its form, else the general one.
int EvolveNormalGeneral(CEodeMemRec* ce, sunrealtype tout, N_Vector xout, N_Vector vout,
                        sunrealtype* tret, int itask) {
  static const char* func = "CEodeEvolve";
  if (itask == CE_NORMAL && DirectEvolve(ce, tout, xout, vout, tret)) {
    return EvolveToTout(ce, func, tout, xout, vout, tret);
  }
  return Evolve(ce, func, tout, xout, vout, tret, itask);
}

int AdaptCall(CEodeMemRec* ce, sunrealtype tout, N_Vector xout, N_Vector vout, sunrealtype* tret,
              int itask) {
  static const char* func = "CEodeEvolve";
  const bool direct = ce->started && !ce->guard.pending && SerialOfLength(xout, ce->n) &&
                      SerialOfLength(vout, ce->n) && tret != nullptr && std::isfinite(tout) &&
                      (itask == CE_NORMAL || itask == CE_ONE_STEP);
  if (!direct) return Evolve(ce, func, tout, xout, vout, tret, itask);
  return AdaptEvolve(ce, func, tout, xout, vout, tret, itask);
}

int EvolveOneStepGeneral(CEodeMemRec* ce, sunrealtype tout, N_Vector xout, N_Vector vout,
                         sunrealtype* tret) {
  static const char* func = "CEodeEvolve";
  if (!DirectEvolve(ce, tout, xout, vout, tret)) {
    return Evolve(ce, func, tout, xout, vout, tret, CE_ONE_STEP);
  }
  // CE_ONE_STEP on the direct path: what EvolveTarget and StepTo do for target = tcur + h.
  // Interval too short for a step (h near t's round-off), or no direct form: the general path.
  const sunrealtype target = ce->tcur + ce->h;
  int flag = CE_SUCCESS;
  if (!StepsRemain(ce, target) || !TakeDirectStep(ce, &flag)) {
    return Evolve(ce, func, target, xout, vout, tret, CE_ONE_STEP);
  }
  return OneStepRest(ce, flag, target, xout, vout, tret);
}

int OneStepRest(CEodeMemRec* ce, int flag, sunrealtype target, N_Vector xout, N_Vector vout,
                sunrealtype* tret) {
  static const char* func = "CEodeEvolve";
  if (flag == CE_SUCCESS && StepsRemain(ce, target)) flag = StepTo(ce, func, target);
  if (flag != CE_SUCCESS) {  // as CEodeEvolve's general path: the last good state
    ReturnCurrentState(ce, xout, vout, tret);
    ce->tretlast = ce->tcur;
    return flag;
  }
  return ReturnAtTarget(ce, func, target, xout, vout, tret, false);
}

namespace {

// What CEodeReInit and Reset share: the state at t0 and a restart of the method and the solvers;
// with counters (CEodeReInit), a fresh start that zeroes them and the guard's warning state.
int RestartAt(CEodeMemRec* ce, const char* func, sunrealtype t0, N_Vector x0, N_Vector v0,
              bool counters) {
  int flag = ValidateTime(ce, func, "t0", t0);
  if (flag == CE_SUCCESS) flag = CheckInitialData(ce, func, x0, v0);
  if (flag != CE_SUCCESS) return flag;
  if (N_VGetLength(x0) != ce->n) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "x0 has %ld entries, CEodeInit had %ld: use CEodeInit to resize.",
                        static_cast<long>(N_VGetLength(x0)), static_cast<long>(ce->n));
  }
  N_VScale(1.0, x0, ce->xcur);
  N_VScale(1.0, v0, ce->D[1]);
  ce->tcur = t0;
  ce->tretlast = t0;
  Restart(ce);
  if (counters) {
    ce->nst = ce->nfe = ce->nfe_start = 0;
    ConstrReset(ce);
    IcRequestCheck(ce);  // the user's new initial conditions
  }
  LsReset(ce, counters);
  NlsReset(ce, counters);
  PcReset(ce, counters);
  GuardReset(ce, counters);
  AdaptReset(ce, counters);
  RootRestart(ce, counters);
  return CE_SUCCESS;
}

}  // namespace

int InitProblem(CEodeMemRec* ce, const char* func, CEodeRhsFn f, sunrealtype t0, N_Vector x0,
                N_Vector v0) {
  int flag = ValidateTime(ce, func, "t0", t0);
  if (flag == CE_SUCCESS) flag = CheckInitialData(ce, func, x0, v0);
  if (flag != CE_SUCCESS) return flag;
  if (ce->initialized) FreeSized(ce);  // a second Init replaces the problem
  flag = AllocVectors(ce, x0);
  if (flag != CE_SUCCESS) return ProcessError(ce, flag, func, "Out of memory.");
  ce->n = N_VGetLength(x0);
  ce->f = f;
  SelectRhs(ce);
  ce->initialized = true;
  PcSetVelocityRequest(ce, ce->pc.vel_request);  // a new problem: its f is probed anew
  return CEodeReInit(ce, t0, x0, v0);
}

int Reset(CEodeMemRec* ce, const char* func, sunrealtype t0, N_Vector x0, N_Vector v0,
          const ResetOptions& opt) {
  int flag = RestartAt(ce, func, t0, x0, v0, false);
  if (flag != CE_SUCCESS) return flag;
  const sunrealtype omega = ce->guard.omega_est;
  if (opt.keep_frequency && !(ce->guard.omega_user > 0) && omega > 0 && std::isfinite(omega)) {
    ce->guard.omega_user = omega;
  }
  if (opt.history) {
    if ((flag = opt.history()) != CE_SUCCESS) return flag;
    ce->adapters.history_preset = true;
  }
  return CE_SUCCESS;
}

}  // namespace ceode

extern "C" {

void* CEodeCreate(SUNContext sunctx) {
  if (sunctx == nullptr) {
    ceode::ProcessError(nullptr, CE_ILL_INPUT, "CEodeCreate",
                        "sunctx = NULL: create a SUNContext with SUNContext_Create first.");
    return nullptr;
  }
  auto* ce = new (std::nothrow) CEodeMemRec;
  if (ce == nullptr) {
    ceode::ProcessError(nullptr, CE_MEM_FAIL, "CEodeCreate", "Out of memory.");
    return nullptr;
  }
  ce->sunctx = sunctx;
  ce->errfp = stderr;
  return ce;
}

int CEodeInit(void* mem, CEodeRhsFn f, sunrealtype t0, N_Vector x0, N_Vector v0) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (f == nullptr) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "f = NULL: pass the right-hand side function f(t, x, v, f, data).");
  }
  flag = ceode::InitProblem(ce, __func__, f, t0, x0, v0);
  if (flag == CE_SUCCESS) ceode::FirstOrderFree(ce);  // the native form replaces it
  return flag;
}

int CEodeReInit(void* mem, sunrealtype t0, N_Vector x0, N_Vector v0) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce, true);
  return flag == CE_SUCCESS ? ceode::RestartAt(ce, __func__, t0, x0, v0, true) : flag;
}

int CEodeReset(void* mem, sunrealtype t0, N_Vector x0, N_Vector v0) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce, true);
  if (flag == CE_SUCCESS) flag = ceode::Reset(ce, __func__, t0, x0, v0, ceode::ResetOptions{});
  // After the checks, so that a refused reset leaves the controller as it was.
  if (flag == CE_SUCCESS) ceode::AdaptKeepStep(ce);  // its next step is the new start's first
  return flag;
}

int CEodeEvolve(void* mem, sunrealtype tout, N_Vector xout, N_Vector vout, sunrealtype* tret,
                int itask) {
  CEodeMemRec* ce = nullptr;
  const int flag = ceode::Access(mem, __func__, &ce, true);
  if (flag != CE_SUCCESS) return flag;
  // With error control a one-step call reaches AdaptCall from OneStepEvolve's checked path, so
  // that the fixed step's fast path tests nothing more.
  if (itask == CE_ONE_STEP) return ceode::OneStepEvolve(ce, tout, xout, vout, tret);
  if (ceode::AdaptOnInline(ce)) return ceode::AdaptCall(ce, tout, xout, vout, tret, itask);
  return ceode::NormalEvolve(ce, tout, xout, vout, tret, itask);
}

int CEodeGetDky(void* mem, sunrealtype t, int k, N_Vector dky) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce, true);
  if (flag != CE_SUCCESS) return flag;
  if ((flag = ceode::CheckOutputVector(ce, __func__, dky, "dky")) != CE_SUCCESS) return flag;
  if (!ce->started) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "No step has been taken yet: call CEodeEvolve first.");
  }
  if (k < 0 || k > ce->degree) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "k = %d: the interpolant of degree %d has derivatives 0..%d.", k,
                               ce->degree, ce->degree);
  }
  const sunrealtype s = t - ce->tcur;
  // The interval of the dense output: the next step, or with error control the last accepted.
  const bool back = ceode::AdaptOn(ce);
  const sunrealtype lo = back ? -ce->adapt->hlast : 0;
  const sunrealtype hi = back ? 0 : ce->h;
  const sunrealtype tol = ceode::GridTolerance(ce, back ? ce->adapt->hlast : ce->h);
  if (!(s >= lo - tol && s <= hi + tol)) {  // also refuses t = NaN
    return ceode::ProcessError(ce, CE_BAD_T, __func__,
                               "t = %.17g is outside the current interval [%.17g, %.17g].",
                               static_cast<double>(t), static_cast<double>(ce->tcur + lo),
                               static_cast<double>(ce->tcur + hi));
  }
  ceode::Interpolate(ce, s, k, dky);
  if (ceode::IsFinite(dky)) return CE_SUCCESS;
  return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                             "The derivative %d at t = %.17g is not finite: the step (%g) is too "
                             "small for it, or the last step failed (start again with "
                             "CEodeReInit).",
                             k, static_cast<double>(t),
                             static_cast<double>(back ? ce->adapt->hlast : ce->h));
}

void CEodeFree(void** mem) {
  if (mem == nullptr || *mem == nullptr) return;
  auto* ce = static_cast<CEodeMemRec*>(*mem);
  ceode::FirstOrderFree(ce);
  ceode::FreeSized(ce);
  delete ce;
  *mem = nullptr;
}

}  // extern "C"
