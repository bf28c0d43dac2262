// Mass matrix, linear solver and velocity Jacobian: the linear algebra glue.
// The attached SUNLinearSolver factors either M (explicit path) or the Newton
// matrix M - kappa df/dv (implicit path); a_holds records which one it holds.
#include <sundials/sundials_dense.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_band.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "ceode_impl.hpp"

namespace ceode {

namespace {

// Matrix-free product for iterative solvers: M w, or (M - kappa df/dv) w with
// df/dv w from one difference quotient at the current Newton iterate.
int ATimes(void* data, N_Vector w, N_Vector z) {
  auto* ce = static_cast<CEodeMemRec*>(data);
  if (ce->ls.M != nullptr) {
    if (SUNMatMatvec(ce->ls.M, w, z) != 0) return -1;
  } else {
    N_VScale(1, w, z);
  }
  if (ce->ls.a_holds != Holds::kNewton) return 0;
  // The increment perturbs the velocity, so it is scaled by |v| (as the dense
  // difference quotients are), not by the acceleration's error weights: those
  // carry the 1e-12 Newton tolerance and would put sig*w below v's round-off.
  const sunrealtype wmax = N_VMaxNorm(w);
  if (wmax == 0) return 0;
  const sunrealtype vmax = std::max(N_VMaxNorm(ce->vtmp), SUN_RCONST(1e-8));
  const sunrealtype sig = std::sqrt(SUN_UNIT_ROUNDOFF) * vmax / wmax;
  N_VLinearSum(1, ce->vtmp, sig, w, ce->tmp1);
  const int rv = CallRhs(ce, ce->nls.t_eval, ce->nls.x_eval, ce->tmp1, ce->tmp2);
  ++ce->ls.nfeDQ;
  if (rv != 0) return rv;
  // z <- z - kappa (f(v + sig w) - f(v)) / sig
  N_VLinearSum(1, ce->tmp2, -1, ce->ftmp, ce->tmp2);
  N_VLinearSum(1, z, -ce->ls.kappa_setup / sig, ce->tmp2, z);
  return 0;
}

// sqrt(eps) relative to the velocity; at rest the unit floor keeps the increment
// far above round-off (an increment of order eps would turn df/dv into noise).
sunrealtype DqIncrement(sunrealtype vj, sunrealtype vscale) {
  return std::sqrt(SUN_UNIT_ROUNDOFF) * std::max({std::fabs(vj), vscale, SUN_RCONST(1.0)});
}

// Dense difference-quotient Jacobian df/dv, one f evaluation per column.
int DenseDqJac(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector v, N_Vector fv, SUNMatrix J) {
  sunrealtype* vd = N_VGetArrayPointer(v);
  N_Vector vp = ce->tmp1;
  N_Vector fp = ce->tmp2;
  const sunindextype n = SUNDenseMatrix_Columns(J);
  const sunrealtype vscale = 1e-3 * N_VMaxNorm(v);
  N_VScale(1, v, vp);
  sunrealtype* vpd = N_VGetArrayPointer(vp);
  for (sunindextype j = 0; j < n; ++j) {
    const sunrealtype inc = DqIncrement(vd[j], vscale);
    vpd[j] = vd[j] + inc;
    const int rv = CallRhs(ce, t, x, vp, fp);
    ++ce->ls.nfeDQ;
    vpd[j] = vd[j];
    if (rv != 0) return rv;
    N_VLinearSum(1 / inc, fp, -1 / inc, fv, fp);
    const sunrealtype* fpd = N_VGetArrayPointer(fp);
    std::copy(fpd, fpd + n, SUNDenseMatrix_Column(J, j));
  }
  return 0;
}

// Banded difference quotients: columns a bandwidth apart share one f evaluation.
int BandDqJac(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector v, N_Vector fv, SUNMatrix J) {
  const sunindextype n = SUNBandMatrix_Columns(J);
  const sunindextype mu = SUNBandMatrix_UpperBandwidth(J);
  const sunindextype ml = SUNBandMatrix_LowerBandwidth(J);
  const sunindextype width = std::min(mu + ml + 1, n);
  N_Vector vp = ce->tmp1;
  N_Vector fp = ce->tmp2;
  N_VScale(1, v, vp);
  const sunrealtype* vd = N_VGetArrayPointer(v);
  sunrealtype* vpd = N_VGetArrayPointer(vp);
  const sunrealtype* fd = N_VGetArrayPointer(fv);
  const sunrealtype vscale = 1e-3 * N_VMaxNorm(v);
  for (sunindextype g = 0; g < width; ++g) {
    for (sunindextype j = g; j < n; j += width) vpd[j] = vd[j] + DqIncrement(vd[j], vscale);
    const int rv = CallRhs(ce, t, x, vp, fp);
    ++ce->ls.nfeDQ;
    if (rv != 0) return rv;
    const sunrealtype* fpd = N_VGetArrayPointer(fp);
    for (sunindextype j = g; j < n; j += width) {
      const sunrealtype inc = vpd[j] - vd[j];
      vpd[j] = vd[j];
      sunrealtype* col = SUNBandMatrix_Column(J, j);
      const sunindextype i1 = std::max<sunindextype>(0, j - mu);
      const sunindextype i2 = std::min<sunindextype>(n - 1, j + ml);
      for (sunindextype i = i1; i <= i2; ++i) col[i - j] = (fpd[i] - fd[i]) / inc;
    }
  }
  return 0;
}

bool HasLocalData(N_Vector v) { return N_VGetArrayPointer(v) != nullptr; }

}  // namespace

void LsReset(CEodeMemRec* ce, bool counters) {
  LsMem& ls = ce->ls;
  ls.a_holds = Holds::kNothing;
  ls.mass_dirty = true;
  ls.mass_evaluated = false;
  ls.nst_lastsetup = -1;
  ls.jac_current = false;
  ls.own_lu = false;
  if (counters) ls.nsetups = ls.nsolves = ls.nje = ls.nfeDQ = ls.nme = 0;
}

int LsInitialize(CEodeMemRec* ce, const char* func) {
  LsReset(ce, false);
  if (HasConstraints(ce)) return CE_SUCCESS;  // the saddle-point solver owns the LS
  if (ce->ls.M != nullptr && ce->ls.LS == nullptr) {
    return ProcessError(ce, CE_LINIT_FAIL, func,
                        "A mass matrix is set but no linear solver: attach one with "
                        "CEodeSetLinearSolver (e.g. SUNLinSol_Dense with a dense matrix).");
  }
  if (ce->ls.LS == nullptr) return CE_SUCCESS;
  if (ce->ls.A == nullptr && !ce->ls.matrix_free) {
    return ProcessError(
        ce, CE_LINIT_FAIL, func,
        "The attached linear solver needs a matrix: pass A to CEodeSetLinearSolver.");
  }
  if (ce->ls.A != nullptr && SUNMatGetID(ce->ls.A) != SUNMATRIX_DENSE &&
      SUNMatGetID(ce->ls.A) != SUNMATRIX_BAND && ce->vel_dependent && ce->ls.jac == nullptr) {
    return ProcessError(
        ce, CE_LINIT_FAIL, func,
        "Difference-quotient Jacobians support dense and band matrices only: supply "
        "df/dv with CEodeSetVelJacFn for this matrix type (e.g. sparse/KLU).");
  }
  if (ce->ls.A != nullptr && ce->vel_dependent && ce->ls.jac == nullptr &&
      !HasLocalData(ce->xcur)) {
    return ProcessError(ce, CE_LINIT_FAIL, func,
                        "Difference-quotient Jacobians need vectors with local data "
                        "(N_VGetArrayPointer): supply df/dv with CEodeSetVelJacFn.");
  }
  if (ce->ls.A != nullptr && ce->vel_dependent && ce->ls.Jsave == nullptr) {
    ce->ls.Jsave = SUNMatClone(ce->ls.A);
    if (ce->ls.Jsave == nullptr) return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
  }
  if (ce->ls.matrix_free && SUNLinSolSetATimes(ce->ls.LS, ce, ATimes) != 0) {
    return ProcessError(
        ce, CE_LINIT_FAIL, func,
        "The linear solver does not accept a matrix-free product: attach a matrix.");
  }
  return InitLinearSolver(ce, ce->ls.LS, func);
}

int InitLinearSolver(CEodeMemRec* ce, SUNLinearSolver LS, const char* func) {
  const int rv = SUNLinSolInitialize(LS);
  if (rv != 0) {
    return ProcessError(ce, CE_LINIT_FAIL, func, "SUNLinSolInitialize failed (returned %d).", rv);
  }
  return CE_SUCCESS;
}

void LsFree(CEodeMemRec* ce) {
  if (ce->ls.Jsave != nullptr) SUNMatDestroy(ce->ls.Jsave);
  ce->ls.Jsave = nullptr;
}

int MassUpdate(CEodeMemRec* ce, sunrealtype t, N_Vector x, const char* func) {
  if (ce->ls.mfn == nullptr) return CE_SUCCESS;
  if (ce->ls.mass_constant && ce->ls.mass_evaluated) return CE_SUCCESS;
  SUNMatZero(ce->ls.M);
  const int rv = ce->ls.mfn(t, x, ce->ls.M, ce->user_data, ce->tmp1, ce->tmp2, ce->tmp3);
  ++ce->ls.nme;
  if (rv != 0) {
    return ProcessError(ce, CE_MASSFUNC_FAIL, func,
                        "The mass matrix function failed (returned %d) at t = %.17g.", rv,
                        static_cast<double>(t));
  }
  ce->ls.mass_evaluated = true;
  ce->ls.mass_dirty = true;
  return CE_SUCCESS;
}

int MassSolve(CEodeMemRec* ce, N_Vector b, const char* func) {
  if (ce->ls.M == nullptr) return CE_SUCCESS;
  if (ce->ls.a_holds != Holds::kMass || ce->ls.mass_dirty) {
    int rv = 0;
    if (ce->ls.A != nullptr) rv = SUNMatCopy(ce->ls.M, ce->ls.A);
    ce->ls.a_holds = Holds::kMass;
    if (rv == 0) rv = SUNLinSolSetup(ce->ls.LS, ce->ls.A);
    ++ce->ls.nsetups;
    if (rv != 0) {
      ce->ls.a_holds = Holds::kNothing;
      return ProcessError(ce, CE_LSETUP_FAIL, func,
                          "The mass matrix could not be factored (linear solver setup returned "
                          "%d): M is singular. Check CEodeMassFn; a system with massless "
                          "coordinates needs constraints (CEodeSetConstraints).",
                          rv);
    }
    ce->ls.mass_dirty = false;
    ce->ls.jac_current = false;  // A no longer holds the Newton matrix
  }
  N_VConst(0, ce->lstmp);
  // Direct solvers ignore the tolerance; an iterative one must solve M a = f to
  // near round-off, unscaled, or the acceleration itself carries its residual.
  sunrealtype tol = 0;
  if (SUNLinSolGetType(ce->ls.LS) != SUNLINEARSOLVER_DIRECT) {
    SUNLinSolSetScalingVectors(ce->ls.LS, nullptr, nullptr);
    tol = SUN_RCONST(1e-13) * std::sqrt(N_VDotProd(b, b));
  }
  const int rv = SUNLinSolSolve(ce->ls.LS, ce->ls.A, ce->lstmp, b, tol);
  ++ce->ls.nsolves;
  if (rv != 0) {
    return ProcessError(ce, CE_LSOLVE_FAIL, func,
                        "The mass-matrix solve failed (linear solver returned %d).", rv);
  }
  N_VScale(1, ce->lstmp, b);
  return CE_SUCCESS;
}

int VelJacobian(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector v, N_Vector fv, SUNMatrix J,
                const char* func) {
  int rv;
  if (ce->ls.jac != nullptr) {
    SUNMatZero(J);
    rv = ce->ls.jac(t, x, v, fv, J, ce->user_data, ce->tmp1, ce->tmp2, ce->tmp3);
  } else if (SUNMatGetID(J) == SUNMATRIX_DENSE) {
    rv = DenseDqJac(ce, t, x, v, fv, J);
  } else {
    rv = BandDqJac(ce, t, x, v, fv, J);
  }
  ++ce->ls.nje;
  if (rv != 0) {
    // A fixed step cannot retry with a smaller h, so every failure is final.
    return ProcessError(ce, CE_JACFUNC_FAIL, func,
                        "The velocity Jacobian df/dv could not be evaluated (f or the Jacobian "
                        "function returned %d) at t = %.17g.",
                        rv, static_cast<double>(t));
  }
  return CE_SUCCESS;
}

// Factors the dense A in place with pivots of this module's own (SUNDIALS' public
// SUNDlsMat_denseGETRF, the factorisation SUNLinSol_Dense performs), so that the serial direct
// Newton iteration solves with factors and pivots it owns.
int FactorOwnLu(CEodeMemRec* ce) {
  LsMem& ls = ce->ls;
  const sunindextype n = SUNDenseMatrix_Columns(ls.A);
  if (static_cast<sunindextype>(ls.pivots.size()) != n) ls.pivots.assign(n, 0);
  ls.lu_cols = SUNDenseMatrix_Cols(ls.A);
  return static_cast<int>(SUNDlsMat_denseGETRF(SUNDenseMatrix_Cols(ls.A), n, n, ls.pivots.data()));
}

int NewtonSetup(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector v, N_Vector fv,
                sunrealtype kappa, const char* func) {
  LsMem& ls = ce->ls;
  ls.kappa_setup = kappa;
  if (ls.A != nullptr) {
    const int flag = VelJacobian(ce, t, x, v, fv, ls.Jsave, func);
    if (flag != CE_SUCCESS) return flag;
    int rv = SUNMatCopy(ls.Jsave, ls.A);
    if (rv == 0) rv = ls.M ? SUNMatScaleAdd(-kappa, ls.A, ls.M) : SUNMatScaleAddI(-kappa, ls.A);
    if (rv != 0) {
      return ProcessError(ce, CE_LSETUP_FAIL, func,
                          "Forming M - kappa df/dv failed (%d): M, A and the Jacobian must "
                          "share a matrix type and size.",
                          rv);
    }
  }
  ls.mass_dirty = false;  // A is built from the current M
  ls.a_holds = Holds::kNewton;
  const int rv = ls.own_lu ? FactorOwnLu(ce) : SUNLinSolSetup(ls.LS, ls.A);
  ++ls.nsetups;
  ls.nst_lastsetup = ce->nst;
  ls.jac_current = true;
  if (rv != 0) {
    ls.a_holds = Holds::kNothing;
    return ProcessError(ce, CE_LSETUP_FAIL, func,
                        "The Newton matrix M - kappa df/dv is singular or could not be "
                        "factored (linear solver setup returned %d) at t = %.17g: check "
                        "M and df/dv, or reduce h.",
                        rv, static_cast<double>(t));
  }
  return CE_SUCCESS;
}

namespace {

// A factored Newton matrix M - kappa_setup df/dv still serves a kappa within kKappaReuse of
// kappa_setup (relative, CVODE's DGMAX): on the velocity coupling the iteration then contracts by
// about |kappa / kappa_setup - 1| per iteration, an extra iteration costs a solve where a new
// factorisation costs many, and a solve that fails is retried with a fresh matrix. Matrix-free
// products (no factorisation to save) and the first setup want kappa itself.
constexpr sunrealtype kKappaReuse = 0.3;

bool KappaServes(const LsMem& ls, sunrealtype kappa) {
  if (ls.kappa_setup == kappa) return true;
  if (ls.matrix_free || ls.A == nullptr || !(ls.kappa_setup > 0)) return false;
  return std::fabs(kappa / ls.kappa_setup - 1) <= kKappaReuse;
}

}  // namespace

bool NewtonMatrixStale(const CEodeMemRec* ce, sunrealtype kappa) {
  const LsMem& ls = ce->ls;
  return ls.a_holds != Holds::kNewton || !ls.jac_current || ls.nst_lastsetup < 0 ||
         ce->nst - ls.nst_lastsetup >= ls.msbj || ls.mass_dirty || !KappaServes(ls, kappa);
}

// Where the own LU replaces SUNLinSol_Dense: on a few unknowns, whose solve costs less than a
// call into SUNDIALS; from there on the two are the same loops.
constexpr sunindextype kOwnLuMaxN = 64;

bool LsUseOwnLu(CEodeMemRec* ce, bool use) {
  LsMem& ls = ce->ls;
  ls.own_lu = use && ce->n <= kOwnLuMaxN && ls.LS != nullptr && ls.A != nullptr &&
              SUNLinSolGetID(ls.LS) == SUNLINEARSOLVER_DENSE &&
              SUNMatGetID(ls.A) == SUNMATRIX_DENSE;
  return ls.own_lu;
}

// SUNLinSolSolve_Dense's triangular solves on the factors FactorOwnLu left (SUNDlsMat_denseGETRS's
// permutation and loops, in its order): the same numbers, without a call into SUNDIALS per
// Newton iteration, which at n of a few costs more than the solve.
void LsSolveOwnLu(CEodeMemRec* ce, sunrealtype* x) {
  LsMem& ls = ce->ls;
  sunrealtype* const* cols = ls.lu_cols;
  const auto n = static_cast<sunindextype>(ls.pivots.size());
  for (sunindextype k = 0; k < n; ++k) std::swap(x[k], x[ls.pivots[k]]);
  for (sunindextype k = 0; k + 1 < n; ++k) {
    const sunrealtype* col = cols[k];
    for (sunindextype i = k + 1; i < n; ++i) x[i] -= col[i] * x[k];
  }
  for (sunindextype k = n - 1; k > 0; --k) {
    const sunrealtype* col = cols[k];
    x[k] /= col[k];
    for (sunindextype i = 0; i < k; ++i) x[i] -= col[i] * x[k];
  }
  x[0] /= cols[0][0];
  ++ls.nsolves;
}

int NewtonSolve(CEodeMemRec* ce, N_Vector b, const char* func) {
  if (ce->ls.matrix_free) SUNLinSolSetScalingVectors(ce->ls.LS, ce->ewt, ce->ewt);
  N_VConst(0, ce->lstmp);
  // Iterative solvers stop at a fraction of the Newton tolerance (weighted norm 1).
  const int rv = SUNLinSolSolve(ce->ls.LS, ce->ls.A, ce->lstmp, b, SUN_RCONST(0.05));
  ++ce->ls.nsolves;
  if (rv != 0) {
    if (rv < 0) {
      ProcessError(ce, CE_LSOLVE_FAIL, func, "The Newton linear solve failed (returned %d).", rv);
    }
    return rv > 0 ? 1 : -1;
  }
  N_VScale(1, ce->lstmp, b);
  return 0;
}

}  // namespace ceode

extern "C" {

int CEodeSetMassFn(void* mem, CEodeMassFn mfn, SUNMatrix M, sunbooleantype constant) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if ((mfn == nullptr) != (M == nullptr)) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "Pass both the mass function and its matrix, or both NULL to "
                               "remove the mass matrix.");
  }
  if ((flag = ceode::ValidateMassMatrix(ce, __func__, M)) != CE_SUCCESS) return flag;
  ce->ls.mfn = mfn;
  ce->ls.M = M;
  ce->ls.mass_constant = constant != SUNFALSE;
  ceode::Restart(ce);
  return CE_SUCCESS;
}

int CEodeSetLinearSolver(void* mem, SUNLinearSolver LS, SUNMatrix A) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (LS == nullptr) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "LS = NULL: create a SUNLinearSolver (e.g. SUNLinSol_Dense).");
  }
  const SUNLinearSolver_Type type = SUNLinSolGetType(LS);
  if (type == SUNLINEARSOLVER_DIRECT && A == nullptr) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "A direct linear solver needs its matrix: pass A.");
  }
  if ((flag = ceode::ValidateLinearSolver(ce, __func__, LS, A, false)) != CE_SUCCESS) return flag;
  if (ce->nls.own) ceode::NlsFree(ce);  // CEODE's own choice (fixed point/Newton) is made anew
  ce->ls.LS = LS;
  ce->ls.A = A;
  ce->ls.matrix_free = (A == nullptr);
  if (ce->ls.Jsave != nullptr) {
    SUNMatDestroy(ce->ls.Jsave);
    ce->ls.Jsave = nullptr;
  }
  ceode::Restart(ce);
  return CE_SUCCESS;
}

int CEodeSetVelJacFn(void* mem, CEodeVelJacFn jac) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  ce->ls.jac = jac;
  ce->ls.jac_current = false;
  ceode::Restart(ce);  // solver workspaces (e.g. the constrained Jacobian) are sized at start
  return CE_SUCCESS;
}

int CEodeSetJacEvalFrequency(void* mem, long int msbj) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  ce->ls.msbj = msbj > 0 ? msbj : ceode::kDefaultJacEvalFrequency;
  ce->ls.msbj_set = msbj > 0;
  return CE_SUCCESS;
}

}  // extern "C"
