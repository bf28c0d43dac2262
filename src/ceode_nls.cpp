// The implicit (velocity-dependent) case: F(a) = M a - f(t, x, V0 + kappa a) = 0
// handed to a SUNNonlinearSolver. The unknown is the correction to the
// predicted acceleration, as CVODE solves for the correction to its predictor.
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>
#include <sunnonlinsol/sunnonlinsol_newton.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "ceode_impl.hpp"

namespace ceode {

namespace {

constexpr const char* kFunc = "CEodeEvolve";
constexpr sunrealtype kCrDown = 0.3;  // as CVODE: convergence-rate memory
constexpr sunrealtype kRDiv = 2.0;    // divergence when the correction grows this much

}  // namespace

// f(t, x, vtmp) into ftmp inside a solve, counted; the failure is recorded for the step (a
// fixed step cannot retry), and the solver gets SUNDIALS' recoverable/unrecoverable sign.
int NlsRhs(CEodeMemRec* ce) {
  const int rv = CallRhs(ce, ce->nls.t_eval, ce->nls.x_eval, ce->vtmp, ce->ftmp);
  ++ce->nfe;
  if (rv == 0) return 0;
  ProcessError(ce, CE_RHSFUNC_FAIL, kFunc,
               "The right-hand side function failed (returned %d) inside the nonlinear solve at "
               "t = %.17g.",
               rv, static_cast<double>(ce->nls.t_eval));
  ce->nls.cb_flag = CE_RHSFUNC_FAIL;
  return rv > 0 ? 1 : -1;
}

namespace {

// a = apred + ycor; v = V0 + kappa a; ftmp = f(t, x, v)
int EvalAtCorrection(CEodeMemRec* ce, N_Vector ycor) {
  N_VLinearSum(1, ce->apred, 1, ycor, ce->atmp);
  N_VLinearSum(1, ce->V0, ce->co.kappa, ce->atmp, ce->vtmp);
  return NlsRhs(ce);
}

int NewtonResidual(N_Vector ycor, N_Vector F, void* mem) {
  auto* ce = static_cast<CEodeMemRec*>(mem);
  const int rv = EvalAtCorrection(ce, ycor);
  if (rv != 0) return rv;
  if (ce->ls.M != nullptr) {
    if (SUNMatMatvec(ce->ls.M, ce->atmp, F) != 0) return -1;
    N_VLinearSum(1, F, -1, ce->ftmp, F);
  } else {
    N_VLinearSum(1, ce->atmp, -1, ce->ftmp, F);
  }
  return 0;
}

int FixedPointMap(N_Vector ycor, N_Vector G, void* mem) {
  auto* ce = static_cast<CEodeMemRec*>(mem);
  const int rv = EvalAtCorrection(ce, ycor);
  if (rv != 0) return rv;
  N_VScale(1, ce->ftmp, G);
  if (MassSolve(ce, G, kFunc) != CE_SUCCESS) {
    ce->nls.cb_flag = CE_LSOLVE_FAIL;
    return -1;
  }
  N_VLinearSum(1, G, -1, ce->apred, G);
  return 0;
}

}  // namespace

int NlsLinearSetup(sunbooleantype /*jbad*/, sunbooleantype* jcur, void* mem) {
  auto* ce = static_cast<CEodeMemRec*>(mem);
  const int flag =
      NewtonSetup(ce, ce->nls.t_eval, ce->nls.x_eval, ce->vtmp, ce->ftmp, ce->co.kappa, kFunc);
  *jcur = SUNTRUE;
  ce->nls.crate = 1;
  if (flag == CE_SUCCESS) return 0;
  ce->nls.cb_flag = flag;  // NewtonSetup has reported
  return -1;
}

int NlsLinearSolve(N_Vector b, void* mem) {
  auto* ce = static_cast<CEodeMemRec*>(mem);
  const int rv = NewtonSolve(ce, b, kFunc);
  if (rv < 0) ce->nls.cb_flag = CE_LSOLVE_FAIL;
  return rv;
}

// CVODE-style test of iteration m: the estimated remaining error delnrm * min(1, crate) below
// tol (delnrm: the weighted RMS norm of the last correction).
int NlsConvTest(CEodeMemRec* ce, int m, sunrealtype delnrm, sunrealtype tol) {
  ++ce->nls.nni;
  if (!std::isfinite(delnrm)) {
    // A non-finite f is the user's to fix: a fresh Jacobian or a retry cannot
    // help, and "did not converge, reduce h" would send the user the wrong way.
    if (!IsFinite(ce->ftmp)) {
      ce->nls.cb_flag =
          ProcessError(ce, CE_RHSFUNC_FAIL, kFunc,
                       "The acceleration became NaN or Inf inside the nonlinear solve at "
                       "t = %.17g: f returned non-finite values.",
                       static_cast<double>(ce->nls.t_eval));
      return -1;
    }
    return SUN_NLS_CONV_RECVR;
  }
  if (m > 0) ce->nls.crate = std::max(kCrDown * ce->nls.crate, delnrm / ce->nls.delp);
  const sunrealtype dcon = delnrm * std::min(SUN_RCONST(1.0), ce->nls.crate) / tol;
  if (dcon <= 1) return SUN_NLS_SUCCESS;
  if (m >= 1 && delnrm > kRDiv * ce->nls.delp) return SUN_NLS_CONV_RECVR;
  ce->nls.delp = delnrm;
  return SUN_NLS_CONTINUE;
}

namespace {

int ConvTest(SUNNonlinearSolver nls, N_Vector /*ycor*/, N_Vector del, sunrealtype tol, N_Vector ewt,
             void* mem) {
  int m = 0;
  SUNNonlinSolGetCurIter(nls, &m);
  return NlsConvTest(static_cast<CEodeMemRec*>(mem), m, N_VWrmsNorm(del, ewt), tol);
}

// Weights: relative to the predicted acceleration, floored by its largest entry.
void ErrorWeights(CEodeMemRec* ce) {
  const sunrealtype amax = N_VMaxNorm(ce->apred);
  const sunrealtype atol =
      ce->nls.abstol > 0 ? ce->nls.abstol : ce->nls.reltol * (amax > 0 ? amax : 1);
  N_VAbs(ce->apred, ce->ewt);
  N_VScale(ce->nls.reltol, ce->ewt, ce->ewt);
  N_VAddConst(ce->ewt, atol, ce->ewt);
  N_VInv(ce->ewt, ce->ewt);
}

}  // namespace

int NlsInitialize(CEodeMemRec* ce, const char* func) {
  if (!ce->vel_dependent || HasConstraints(ce)) return CE_SUCCESS;
  if (ce->nls.delta == nullptr && (ce->nls.delta = CloneVector(ce->ycor)) == nullptr) {
    return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
  }
  if (ce->nls.NLS == nullptr) {
    ce->nls.NLS = ce->ls.LS != nullptr ? SUNNonlinSol_Newton(ce->ycor, ce->sunctx)
                                       : SUNNonlinSol_FixedPoint(ce->ycor, 0, ce->sunctx);
    if (ce->nls.NLS == nullptr) return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
    ce->nls.own = true;
  }
  const bool newton = SUNNonlinSolGetType(ce->nls.NLS) == SUNNONLINEARSOLVER_ROOTFIND;
  int rv = 0;
  if (newton) {
    if (ce->ls.LS == nullptr) {
      return ProcessError(ce, CE_NLS_INIT_FAIL, func,
                          "A Newton nonlinear solver needs a linear solver: attach one with "
                          "CEodeSetLinearSolver, or use a fixed-point solver.");
    }
    rv = SUNNonlinSolSetSysFn(ce->nls.NLS, NewtonResidual);
    if (rv == 0) rv = SUNNonlinSolSetLSetupFn(ce->nls.NLS, NlsLinearSetup);
    if (rv == 0) rv = SUNNonlinSolSetLSolveFn(ce->nls.NLS, NlsLinearSolve);
  } else {
    if (ce->ls.M != nullptr && ce->ls.LS == nullptr) {
      return ProcessError(ce, CE_NLS_INIT_FAIL, func,
                          "A fixed-point solve with a mass matrix needs a linear solver for M.");
    }
    rv = SUNNonlinSolSetSysFn(ce->nls.NLS, FixedPointMap);
  }
  if (rv == 0) rv = SUNNonlinSolSetConvTestFn(ce->nls.NLS, ConvTest, ce);
  if (rv == 0) rv = SUNNonlinSolSetMaxIters(ce->nls.NLS, ce->nls.maxcor);
  if (rv == 0) rv = SUNNonlinSolInitialize(ce->nls.NLS);
  // The serial backend, when it applies, from here to the next restart.
  ce->nls.direct = DirectNewtonApplies(ce);
  if (ce->nls.direct) DirectArrays(ce);
  LsUseOwnLu(ce, ce->nls.direct);
  if (rv != 0) {
    return ProcessError(ce, CE_NLS_INIT_FAIL, func,
                        "Setting up the nonlinear solver failed (returned %d).", rv);
  }
  return CE_SUCCESS;
}

void NlsFree(CEodeMemRec* ce) {
  if (ce->nls.delta != nullptr) N_VDestroy(ce->nls.delta);
  ce->nls.delta = nullptr;
  if (ce->nls.NLS != nullptr && ce->nls.own) SUNNonlinSolFree(ce->nls.NLS);
  if (ce->nls.own) ce->nls.NLS = nullptr;
  ce->nls.own = false;
}

int SolveImplicit(CEodeMemRec* ce, sunrealtype t, sunrealtype /*tnext*/, N_Vector x, N_Vector a,
                  const char* func) {
  NlsMem& nls = ce->nls;
  const int flag = MassUpdate(ce, t, x, func);
  if (flag != CE_SUCCESS) return flag;
  // Velocity offset and predictor (v(a) = V0 + kappa a; a0 = Taylor of a from t - h), weights.
  if (nls.direct) {
    DirectPrepare(ce);
  } else {
    VelocityOffset(ce->degree, ce->co, ce->D, ce->V0);
    PredictAccel(ce, ce->apred);
    ErrorWeights(ce);
  }
  nls.t_eval = t;
  nls.x_eval = x;
  nls.cb_flag = 0;
  nls.delp = 0;
  const bool newton = SUNNonlinSolGetType(nls.NLS) == SUNNONLINEARSOLVER_ROOTFIND;
  bool setup = newton && NewtonMatrixStale(ce, ce->co.kappa);
  int rv = 0;
  for (int attempt = 0; attempt < 2; ++attempt) {
    if (nls.direct) {
      rv = DirectSolve(ce, setup);
    } else {
      N_VConst(0, ce->ycor);
      rv = SUNNonlinSolSolve(nls.NLS, ce->zero, ce->ycor, ce->ewt, 1, setup ? SUNTRUE : SUNFALSE,
                             ce);
    }
    if (rv == SUN_NLS_SUCCESS || rv < 0 || nls.cb_flag < 0) break;
    ++nls.nnf;
    if (!newton || setup) break;  // a fresh Jacobian was already used
    setup = true;
    nls.crate = 1;
  }
  if (rv < 0 || nls.cb_flag != 0) {
    if (nls.cb_flag != 0) return nls.cb_flag;  // the callback already reported
    return ProcessError(ce, CE_NLS_FAIL, func, "The nonlinear solver failed (returned %d).", rv);
  }
  if (rv != SUN_NLS_SUCCESS) {
    ++nls.nnf;
    return ProcessError(ce, CE_CONV_FAILURE, func,
                        "The %s iteration for the acceleration did not converge in %d iterations "
                        "at t = %.17g: reduce h (the velocity coupling kappa*df/dv grows with h), "
                        "attach a linear solver for Newton, or raise CEodeSetMaxNonlinIters.",
                        newton ? "Newton" : "fixed-point", nls.maxcor, static_cast<double>(t));
  }
  if (nls.direct) {
    DirectAccel(ce, a);
  } else {
    N_VLinearSum(1, ce->apred, 1, ce->ycor, a);
  }
  ++nls.nsteps;
  return CE_SUCCESS;
}

void NlsLastResidual(const CEodeMemRec* ce, N_Vector* v, N_Vector* fv) {
  *v = ce->vtmp;
  *fv = ce->ftmp;
}

void NlsReset(CEodeMemRec* ce, bool counters) {
  if (counters) ce->nls.nni = ce->nls.nnf = ce->nls.nsteps = 0;
}

}  // namespace ceode

extern "C" {

int CEodeSetNonlinearSolver(void* mem, SUNNonlinearSolver NLS) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (NLS == nullptr) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "NLS = NULL: create one with SUNNonlinSol_Newton or "
                               "SUNNonlinSol_FixedPoint.");
  }
  if ((flag = ceode::ValidateNonlinearSolver(ce, __func__, NLS)) != CE_SUCCESS) return flag;
  ceode::NlsFree(ce);
  ce->nls.NLS = NLS;
  ce->nls.own = false;
  ceode::Restart(ce);
  return CE_SUCCESS;
}

int CEodeSetMaxNonlinIters(void* mem, int maxcor) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (maxcor < 1) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "maxcor = %d: need at least 1 iteration.", maxcor);
  }
  ce->nls.maxcor = maxcor;
  ce->nls.maxcor_set = true;
  if (ce->nls.NLS != nullptr) SUNNonlinSolSetMaxIters(ce->nls.NLS, maxcor);
  return CE_SUCCESS;
}

int CEodeSetNonlinTolerances(void* mem, sunrealtype reltol, sunrealtype abstol) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if ((flag = ceode::ValidateNonlinTolerances(ce, __func__, reltol, abstol)) != CE_SUCCESS)
    return flag;
  ce->nls.reltol = reltol;
  ce->nls.abstol = abstol;
  ce->nls.tol_set = true;
  return CE_SUCCESS;
}

}  // extern "C"
