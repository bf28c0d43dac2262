// The implicit (velocity-dependent) case: F(a) = M a - f(t, x, V0 + kappa a) = 0
// handed to a SUNNonlinearSolver. The unknown is the correction to the
// predicted acceleration, as CVODE solves for the correction to its predictor.
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
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

// f(t, x, vtmp) into ftmp inside a solve, counted; the failure is recorded for the step (a
// fixed step cannot retry), and the solver gets SUNDIALS' recoverable/unrecoverable sign.
int RhsInSolve(CEodeMemRec* ce) {
  const int rv = CallRhs(ce, ce->t_eval, ce->x_eval, ce->vtmp, ce->ftmp);
  ++ce->nfe;
  if (rv == 0) return 0;
  ProcessError(ce, CE_RHSFUNC_FAIL, kFunc,
               "The right-hand side function failed (returned %d) inside the nonlinear solve at "
               "t = %.17g.",
               rv, static_cast<double>(ce->t_eval));
  ce->cb_flag = CE_RHSFUNC_FAIL;
  return rv > 0 ? 1 : -1;
}

// a = apred + ycor; v = V0 + kappa a; ftmp = f(t, x, v)
int EvalAtCorrection(CEodeMemRec* ce, N_Vector ycor) {
  N_VLinearSum(1, ce->apred, 1, ycor, ce->atmp);
  N_VLinearSum(1, ce->V0, ce->co.kappa, ce->atmp, ce->vtmp);
  return RhsInSolve(ce);
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

// CVODE-style test of iteration m: the estimated remaining error delnrm * min(1, crate) below
// tol (delnrm: the weighted RMS norm of the last correction).
int ConvTestNorm(CEodeMemRec* ce, int m, sunrealtype delnrm, sunrealtype tol) {
  ++ce->nni;
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

int ConvTest(SUNNonlinearSolver nls, N_Vector /*ycor*/, N_Vector del, sunrealtype tol, N_Vector ewt,
             void* mem) {
  int m = 0;
  SUNNonlinSolGetCurIter(nls, &m);
  return ConvTestNorm(static_cast<CEodeMemRec*>(mem), m, N_VWrmsNorm(del, ewt), tol);
}

// ---- The direct Newton iteration (small serial systems, a direct linear solver) ----
// SUNNonlinSol_Newton's algorithm (SUNDIALS 6.4 and 7.x alike: residual, -F, solve, update,
// test; one retry with a fresh matrix when the matrix was not current) with CEODE's residual,
// solve and test, on raw arrays in N_Vector serial's order of operations: the same numbers as
// the generic path, without its dispatch, which at n of a few costs more than f (docs/api.md).
constexpr sunindextype kDirectNewtonMaxN = 64;

bool DirectNewtonApplies(const CEodeMemRec* ce) {
  return ce->own_nls && ce->fused_ready && ce->n <= kDirectNewtonMaxN && ce->A != nullptr &&
         ce->LS != nullptr && SUNLinSolGetType(ce->LS) == SUNLINEARSOLVER_DIRECT &&
         SUNNonlinSolGetType(ce->NLS) == SUNNONLINEARSOLVER_ROOTFIND;
}

// The raw arrays of the direct iteration, looked up once per step. The direct path runs on
// serial vectors only (fused_ready), so the data pointers are read from the vectors' content
// (NV_DATA_S) rather than through the vector operations' dispatch: at n of a few, the
// dispatch of N_VGetArrayPointer was a sixth of a Newton step (bench_implicit_step).
struct Raw {
  sunindextype n;
  sunrealtype *apred, *atmp, *vtmp, *V0, *ftmp, *lstmp, *ewt, *ycor, *delta;
  sunrealtype** cols;  // SUNLinSol_Dense's LU factors (nullptr: another direct solver)
  sunindextype* pivots;
};

Raw RawArrays(const CEodeMemRec* ce) {
  Raw r{ce->n,
        NV_DATA_S(ce->apred),
        NV_DATA_S(ce->atmp),
        NV_DATA_S(ce->vtmp),
        NV_DATA_S(ce->V0),
        NV_DATA_S(ce->ftmp),
        NV_DATA_S(ce->lstmp),
        NV_DATA_S(ce->ewt),
        NV_DATA_S(ce->ycor),
        NV_DATA_S(ce->nls_delta),
        nullptr,
        nullptr};
  if (SUNLinSolGetID(ce->LS) == SUNLINEARSOLVER_DENSE && SUNMatGetID(ce->A) == SUNMATRIX_DENSE) {
    r.cols = SUNDenseMatrix_Cols(ce->A);
    r.pivots = static_cast<SUNLinearSolverContent_Dense>(ce->LS->content)->pivots;
  }
  return r;
}

// z = sum_j c_j X_j (j < m) on raw arrays, with N_VLinearCombination_Serial's values: its
// m = 1 and m = 2 cases are N_VScale and N_VLinearSum, whose a = b and a = -b branches factor.
void RawCombination(sunindextype n, int m, const sunrealtype* c, N_Vector* X, sunrealtype* z) {
  const sunrealtype* x0 = NV_DATA_S(X[0]);
  const sunrealtype* x1 = m >= 2 ? NV_DATA_S(X[1]) : nullptr;
  if (m == 2 && (c[0] == c[1] || c[0] == -c[1])) {
    const sunrealtype sgn = c[0] == c[1] ? 1 : -1;
    for (sunindextype i = 0; i < n; ++i) z[i] = c[0] * (x0[i] + (sgn * x1[i]));
    return;
  }
  for (sunindextype i = 0; i < n; ++i) z[i] = c[0] * x0[i];
  for (int j = 1; j < m; ++j) {
    const sunrealtype* xj = NV_DATA_S(X[j]);
    for (sunindextype i = 0; i < n; ++i) z[i] += c[j] * xj[i];
  }
}

// SolveImplicit's VelocityOffset and PredictAccel (both N_VLinearCombination) on raw arrays.
void DirectOffsetAndPredict(const CEodeMemRec* ce, const Raw& r) {
  const int d = ce->degree;
  RawCombination(r.n, d - 1, ce->co.V0 + 1, const_cast<N_Vector*>(ce->D + 1), r.V0);
  RawCombination(r.n, d - 2, ce->co.pred, const_cast<N_Vector*>(ce->D + 2), r.apred);
}

// SUNLinSolSolve_Dense on raw arrays: x = b, then SUNDlsMat_denseGETRS's permutation and
// triangular solves in its order (SUNDIALS 6.4 and 7.x alike).
void DirectDenseSolve(const Raw& r, const sunrealtype* b, sunrealtype* x) {
  const sunindextype n = r.n;
  for (sunindextype i = 0; i < n; ++i) x[i] = b[i];
  for (sunindextype k = 0; k < n; ++k) std::swap(x[k], x[r.pivots[k]]);
  for (sunindextype k = 0; k + 1 < n; ++k) {
    const sunrealtype* col = r.cols[k];
    for (sunindextype i = k + 1; i < n; ++i) x[i] -= col[i] * x[k];
  }
  for (sunindextype k = n - 1; k > 0; --k) {
    const sunrealtype* col = r.cols[k];
    x[k] /= col[k];
    for (sunindextype i = 0; i < k; ++i) x[i] -= col[i] * x[k];
  }
  x[0] /= r.cols[0][0];
}

// ewt = 1 / (reltol |apred| + atol), atol from max |apred| (SolveImplicit's N_VMaxNorm, N_VAbs,
// N_VScale, N_VAddConst, N_VInv, in their order).
void DirectWeights(const CEodeMemRec* ce, const Raw& r) {
  sunrealtype amax = 0;
  for (sunindextype i = 0; i < r.n; ++i) amax = std::max(amax, std::fabs(r.apred[i]));
  const sunrealtype atol =
      ce->nls_abstol > 0 ? ce->nls_abstol : ce->nls_reltol * (amax > 0 ? amax : 1);
  for (sunindextype i = 0; i < r.n; ++i) {
    r.ewt[i] = 1 / ((ce->nls_reltol * std::fabs(r.apred[i])) + atol);
  }
}

// F(ycor) = M a - f(t, x, V0 + kappa a), a = apred + ycor (NewtonResidual's operations).
int DirectResidual(CEodeMemRec* ce, const Raw& r) {
  const sunrealtype* y = r.ycor;
  const sunrealtype kappa = ce->co.kappa;
  for (sunindextype i = 0; i < r.n; ++i) {
    r.atmp[i] = r.apred[i] + y[i];
    r.vtmp[i] = (kappa * r.atmp[i]) + r.V0[i];
  }
  const int rv = RhsInSolve(ce);
  if (rv != 0) return rv;
  sunrealtype* Fd = r.delta;
  if (ce->M != nullptr && SUNMatMatvec(ce->M, ce->atmp, ce->nls_delta) != 0) return -1;
  const sunrealtype* lhs = ce->M != nullptr ? Fd : r.atmp;
  for (sunindextype i = 0; i < r.n; ++i) Fd[i] = lhs[i] - r.ftmp[i];
  return 0;
}

// delta <- (M - kappa J)^{-1} (-delta), ycor += delta, then the test (one Newton iteration).
int DirectIterate(CEodeMemRec* ce, const Raw& r, int m) {
  sunrealtype* d = r.delta;
  for (sunindextype i = 0; i < r.n; ++i) d[i] = -d[i];
  int rv = 0;
  if (r.cols != nullptr) {
    DirectDenseSolve(r, d, r.lstmp);
  } else {
    rv = SUNLinSolSolve(ce->LS, ce->A, ce->lstmp, ce->nls_delta, SUN_RCONST(0.05));
  }
  ++ce->nls_solves;
  if (rv != 0) {
    if (rv < 0) {
      ce->cb_flag = CE_LSOLVE_FAIL;
      ProcessError(ce, CE_LSOLVE_FAIL, kFunc, "The Newton linear solve failed (returned %d).", rv);
    }
    return rv > 0 ? 1 : -1;
  }
  sunrealtype sum = 0;
  for (sunindextype i = 0; i < r.n; ++i) {
    d[i] = r.lstmp[i];
    r.ycor[i] = r.ycor[i] + d[i];
    const sunrealtype p = d[i] * r.ewt[i];
    sum += p * p;
  }
  return ConvTestNorm(ce, m, std::sqrt(sum / static_cast<sunrealtype>(r.n)), 1);
}

// One SUNNonlinSolSolve: the Newton loop and its one retry with a fresh matrix.
int DirectNewton(CEodeMemRec* ce, const Raw& r, bool setup) {
  bool jbad = false;
  for (;;) {
    int rv = DirectResidual(ce, r);
    if (rv == 0 && setup) {
      sunbooleantype jcur = SUNFALSE;
      rv = LinearSetup(jbad ? SUNTRUE : SUNFALSE, &jcur, ce);
      ce->nls_jcur = jcur != SUNFALSE;
    }
    for (int m = 0; rv == 0;) {
      rv = DirectIterate(ce, r, m);
      if (rv == SUN_NLS_SUCCESS) {
        ce->nls_jcur = false;
        return SUN_NLS_SUCCESS;
      }
      if (rv != SUN_NLS_CONTINUE) break;
      if (++m >= ce->maxcor) {
        rv = SUN_NLS_CONV_RECVR;
        break;
      }
      rv = DirectResidual(ce, r);
    }
    if (rv > 0 && !ce->nls_jcur) {
      setup = jbad = true;
      for (sunindextype i = 0; i < r.n; ++i) r.ycor[i] = 0;
      continue;
    }
    return rv;
  }
}

// Weights: relative to the predicted acceleration, floored by its largest entry.
void ErrorWeights(CEodeMemRec* ce, bool direct, const Raw& raw) {
  if (direct) {
    DirectWeights(ce, raw);
    return;
  }
  const sunrealtype amax = N_VMaxNorm(ce->apred);
  const sunrealtype atol =
      ce->nls_abstol > 0 ? ce->nls_abstol : ce->nls_reltol * (amax > 0 ? amax : 1);
  N_VAbs(ce->apred, ce->ewt);
  N_VScale(ce->nls_reltol, ce->ewt, ce->ewt);
  N_VAddConst(ce->ewt, atol, ce->ewt);
  N_VInv(ce->ewt, ce->ewt);
}

// Velocity offset and predictor (v(a) = V0 + kappa a; a0 = Taylor of a from t - h) and the
// error weights, on raw arrays on the direct path.
void PrepareSolve(CEodeMemRec* ce, bool direct, const Raw& raw) {
  if (direct) {
    DirectOffsetAndPredict(ce, raw);
  } else {
    VelocityOffset(ce->degree, ce->co, ce->D, ce->V0);
    PredictAccel(ce, ce->apred);
  }
  ErrorWeights(ce, direct, raw);
}

void ZeroCorrection(CEodeMemRec* ce, bool direct, const Raw& raw) {
  if (direct) {
    std::fill(raw.ycor, raw.ycor + raw.n, SUN_RCONST(0.0));
  } else {
    N_VConst(0, ce->ycor);
  }
}

// a = apred + ycor (N_VLinearSum's VSum on the direct path).
void CorrectedAccel(CEodeMemRec* ce, bool direct, const Raw& raw, N_Vector a) {
  if (direct) {
    sunrealtype* ad = NV_DATA_S(a);
    for (sunindextype i = 0; i < raw.n; ++i) ad[i] = raw.apred[i] + raw.ycor[i];
  } else {
    N_VLinearSum(1, ce->apred, 1, ce->ycor, a);
  }
}

}  // namespace

int NlsInitialize(CEodeMemRec* ce, const char* func) {
  if (!ce->vel_dependent || HasConstraints(ce)) return CE_SUCCESS;
  if (ce->nls_delta == nullptr && (ce->nls_delta = N_VClone(ce->ycor)) == nullptr) {
    return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
  }
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
  if (ce->nls_delta != nullptr) N_VDestroy(ce->nls_delta);
  ce->nls_delta = nullptr;
  if (ce->pc_dir != nullptr) N_VDestroy(ce->pc_dir);  // CE_IMPLICIT_AUTO's (ceode_pc.cpp)
  ce->pc_dir = nullptr;
  if (ce->NLS != nullptr && ce->own_nls) SUNNonlinSolFree(ce->NLS);
  if (ce->own_nls) ce->NLS = nullptr;
  ce->own_nls = false;
}

int SolveImplicit(CEodeMemRec* ce, sunrealtype t, sunrealtype /*tnext*/, N_Vector x, N_Vector a,
                  const char* func) {
  const StepCoeffs& co = ce->co;
  int flag = MassUpdate(ce, t, x, func);
  if (flag != CE_SUCCESS) return flag;

  const bool direct = DirectNewtonApplies(ce);
  const Raw raw = direct ? RawArrays(ce) : Raw{};
  PrepareSolve(ce, direct, raw);

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
    ZeroCorrection(ce, direct, raw);
    rv = direct ? DirectNewton(ce, raw, setup)
                : SUNNonlinSolSolve(ce->NLS, ce->zero, ce->ycor, ce->ewt, 1,
                                    setup ? SUNTRUE : SUNFALSE, ce);
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
  CorrectedAccel(ce, direct, raw, a);
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
