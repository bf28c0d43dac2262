// The implicit (velocity-dependent) case: F(a) = M a - f(t, x, V0 + kappa a) = 0
// handed to a SUNNonlinearSolver. The unknown is the correction to the
// predicted acceleration, as CVODE solves for the correction to its predictor.
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>
#include <sunnonlinsol/sunnonlinsol_newton.h>

#include <cmath>

#include "ceode_impl.hpp"

namespace ceode {

namespace {

constexpr const char* kFunc = "CEodeEvolve";
constexpr sunrealtype kCrDown = 0.3;  // as CVODE: convergence-rate memory
constexpr sunrealtype kRDiv = 2.0;    // divergence when the correction grows this much

// a = apred + ycor; v = V0 + kappa a; ftmp = f(t, x, v)
int EvalAtCorrection(CEodeMemRec* ce, N_Vector ycor) {
  N_VLinearSum(1, ce->apred, 1, ycor, ce->atmp);
  N_VLinearSum(1, ce->V0, ce->co.kappa, ce->atmp, ce->vtmp);
  const int rv = ce->f(ce->t_eval, ce->x_eval, ce->vtmp, ce->ftmp, ce->user_data);
  ++ce->nfe;
  if (rv != 0) {
    ProcessError(ce, CE_RHSFUNC_FAIL, kFunc,
                 "The right-hand side function failed (returned %d) inside the nonlinear solve at "
                 "t = %.17g.",
                 rv, static_cast<double>(ce->t_eval));
    ce->cb_flag = CE_RHSFUNC_FAIL;
    return rv > 0 ? 1 : -1;
  }
  return 0;
}

int NewtonResidual(N_Vector ycor, N_Vector F, void* mem) {
  auto* ce = static_cast<CEodeMemRec*>(mem);
  const int rv = EvalAtCorrection(ce, ycor);
  if (rv != 0) return rv;
  if (ce->M != nullptr) {
    if (SUNMatMatvec(ce->M, ce->atmp, F) != 0) return -1;
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
    ce->cb_flag = CE_LSOLVE_FAIL;
    return -1;
  }
  N_VLinearSum(1, G, -1, ce->apred, G);
  return 0;
}

int LinearSetup(sunbooleantype /*jbad*/, sunbooleantype* jcur, void* mem) {
  auto* ce = static_cast<CEodeMemRec*>(mem);
  const int rv = NewtonSetup(ce, ce->t_eval, ce->x_eval, ce->vtmp, ce->ftmp, ce->co.kappa, kFunc);
  *jcur = SUNTRUE;
  ce->crate = 1;
  return rv;  // NewtonSetup has reported and set cb_flag on failure
}

int LinearSolve(N_Vector b, void* mem) {
  auto* ce = static_cast<CEodeMemRec*>(mem);
  const int rv = NewtonSolve(ce, b, kFunc);
  if (rv < 0) ce->cb_flag = CE_LSOLVE_FAIL;
  return rv;
}

// CVODE-style test: the estimated remaining error del * min(1, crate) below tol.
int ConvTest(SUNNonlinearSolver nls, N_Vector /*ycor*/, N_Vector del, sunrealtype tol, N_Vector ewt,
             void* mem) {
  auto* ce = static_cast<CEodeMemRec*>(mem);
  int m = 0;
  SUNNonlinSolGetCurIter(nls, &m);
  ++ce->nni;
  const sunrealtype delnrm = N_VWrmsNorm(del, ewt);
  if (!std::isfinite(delnrm)) {
    // A non-finite f is the user's to fix: a fresh Jacobian or a retry cannot
    // help, and "did not converge, reduce h" would send the user the wrong way.
    if (!IsFinite(ce->ftmp)) {
      ce->cb_flag = ProcessError(ce, CE_RHSFUNC_FAIL, kFunc,
                                 "The acceleration became NaN or Inf inside the nonlinear solve at "
                                 "t = %.17g: f returned non-finite values.",
                                 static_cast<double>(ce->t_eval));
      return -1;
    }
    return SUN_NLS_CONV_RECVR;
  }
  if (m > 0) ce->crate = std::max(kCrDown * ce->crate, delnrm / ce->delp);
  const sunrealtype dcon = delnrm * std::min(SUN_RCONST(1.0), ce->crate) / tol;
  if (dcon <= 1) return SUN_NLS_SUCCESS;
  if (m >= 1 && delnrm > kRDiv * ce->delp) return SUN_NLS_CONV_RECVR;
  ce->delp = delnrm;
  return SUN_NLS_CONTINUE;
}

}  // namespace

int NlsInitialize(CEodeMemRec* ce, const char* func) {
  if (!ce->vel_dependent || HasConstraints(ce)) return CE_SUCCESS;
  if (ce->NLS == nullptr) {
    ce->NLS = ce->LS != nullptr ? SUNNonlinSol_Newton(ce->ycor, ce->sunctx)
                                : SUNNonlinSol_FixedPoint(ce->ycor, 0, ce->sunctx);
    if (ce->NLS == nullptr) return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
    ce->own_nls = true;
  }
  const bool newton = SUNNonlinSolGetType(ce->NLS) == SUNNONLINEARSOLVER_ROOTFIND;
  int rv = 0;
  if (newton) {
    if (ce->LS == nullptr) {
      return ProcessError(ce, CE_NLS_INIT_FAIL, func,
                          "A Newton nonlinear solver needs a linear solver: attach one with "
                          "CEodeSetLinearSolver, or use a fixed-point solver.");
    }
    rv = SUNNonlinSolSetSysFn(ce->NLS, NewtonResidual);
    if (rv == 0) rv = SUNNonlinSolSetLSetupFn(ce->NLS, LinearSetup);
    if (rv == 0) rv = SUNNonlinSolSetLSolveFn(ce->NLS, LinearSolve);
  } else {
    if (ce->M != nullptr && ce->LS == nullptr) {
      return ProcessError(ce, CE_NLS_INIT_FAIL, func,
                          "A fixed-point solve with a mass matrix needs a linear solver for M.");
    }
    rv = SUNNonlinSolSetSysFn(ce->NLS, FixedPointMap);
  }
  if (rv == 0) rv = SUNNonlinSolSetConvTestFn(ce->NLS, ConvTest, ce);
  if (rv == 0) rv = SUNNonlinSolSetMaxIters(ce->NLS, ce->maxcor);
  if (rv == 0) rv = SUNNonlinSolInitialize(ce->NLS);
  if (rv != 0) {
    return ProcessError(ce, CE_NLS_INIT_FAIL, func,
                        "Setting up the nonlinear solver failed (returned %d).", rv);
  }
  return CE_SUCCESS;
}

void NlsFree(CEodeMemRec* ce) {
  if (ce->NLS != nullptr && ce->own_nls) SUNNonlinSolFree(ce->NLS);
  if (ce->own_nls) ce->NLS = nullptr;
  ce->own_nls = false;
}

int SolveImplicit(CEodeMemRec* ce, sunrealtype t, sunrealtype /*tnext*/, N_Vector x, N_Vector a,
                  const char* func) {
  const StepCoeffs& co = ce->co;
  int flag = MassUpdate(ce, t, x, func);
  if (flag != CE_SUCCESS) return flag;

  // Velocity offset and predictor: v(a) = V0 + kappa a; a0 = Taylor of a from t - h.
  VelocityOffset(ce->degree, co, ce->D, ce->V0);
  PredictAccel(ce, ce->apred);

  // Weights: relative to the predicted acceleration, floored by its largest entry.
  const sunrealtype amax = N_VMaxNorm(ce->apred);
  const sunrealtype atol =
      ce->nls_abstol > 0 ? ce->nls_abstol : ce->nls_reltol * (amax > 0 ? amax : 1);
  N_VAbs(ce->apred, ce->ewt);
  N_VScale(ce->nls_reltol, ce->ewt, ce->ewt);
  N_VAddConst(ce->ewt, atol, ce->ewt);
  N_VInv(ce->ewt, ce->ewt);

  ce->t_eval = t;
  ce->x_eval = x;
  ce->cb_flag = 0;
  ce->delp = 0;
  const bool newton = SUNNonlinSolGetType(ce->NLS) == SUNNONLINEARSOLVER_ROOTFIND;
  bool setup = newton && (ce->a_holds != Holds::kNewton || !ce->jac_current ||
                          ce->nst_lastsetup < 0 || ce->nst - ce->nst_lastsetup >= ce->msbj ||
                          ce->mass_dirty || ce->kappa_setup != co.kappa);
  int rv = 0;
  for (int attempt = 0; attempt < 2; ++attempt) {
    N_VConst(0, ce->ycor);
    rv = SUNNonlinSolSolve(ce->NLS, ce->zero, ce->ycor, ce->ewt, 1, setup ? SUNTRUE : SUNFALSE, ce);
    if (rv == SUN_NLS_SUCCESS || rv < 0 || ce->cb_flag < 0) break;
    ++ce->nnf;
    if (!newton || setup) break;  // a fresh Jacobian was already used
    setup = true;
    ce->crate = 1;
  }
  if (rv < 0 || ce->cb_flag != 0) {
    if (ce->cb_flag != 0) return ce->cb_flag;  // the callback already reported
    return ProcessError(ce, CE_NLS_FAIL, func, "The nonlinear solver failed (returned %d).", rv);
  }
  if (rv != SUN_NLS_SUCCESS) {
    ++ce->nnf;
    return ProcessError(ce, CE_CONV_FAILURE, func,
                        "The %s iteration for the acceleration did not converge in %d iterations "
                        "at t = %.17g: reduce h (the velocity coupling kappa*df/dv grows with h), "
                        "attach a linear solver for Newton, or raise CEodeSetMaxNonlinIters.",
                        newton ? "Newton" : "fixed-point", ce->maxcor, static_cast<double>(t));
  }
  N_VLinearSum(1, ce->apred, 1, ce->ycor, a);
  ++ce->nnls_steps;
  return CE_SUCCESS;
}

}  // namespace ceode

extern "C" int CEodeSetNonlinearSolver(void* mem, SUNNonlinearSolver NLS) {
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
  ce->NLS = NLS;
  ce->own_nls = false;
  ceode::Restart(ce);
  return CE_SUCCESS;
}
