// Mass matrix, linear solver and velocity Jacobian: the linear algebra glue.
// The attached SUNLinearSolver factors either M (explicit path) or the Newton
// matrix M - kappa df/dv (implicit path); a_holds records which one it holds.
#include <sunmatrix/sunmatrix_band.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <algorithm>
#include <cmath>

#include "ceode_impl.hpp"

namespace ceode {

namespace {

// Matrix-free product for iterative solvers: M w, or (M - kappa df/dv) w with
// df/dv w from one difference quotient at the current Newton iterate.
int ATimes(void* data, N_Vector w, N_Vector z) {
  auto* ce = static_cast<CEodeMemRec*>(data);
  if (ce->M != nullptr) {
    if (SUNMatMatvec(ce->M, w, z) != 0) return -1;
  } else {
    N_VScale(1, w, z);
  }
  if (ce->a_holds != Holds::kNewton) return 0;
  // The increment perturbs the velocity, so it is scaled by |v| (as the dense
  // difference quotients are), not by the acceleration's error weights: those
  // carry the 1e-12 Newton tolerance and would put sig*w below v's round-off.
  const sunrealtype wmax = N_VMaxNorm(w);
  if (wmax == 0) return 0;
  const sunrealtype vmax = std::max(N_VMaxNorm(ce->vtmp), SUN_RCONST(1e-8));
  const sunrealtype sig = std::sqrt(SUN_UNIT_ROUNDOFF) * vmax / wmax;
  N_VLinearSum(1, ce->vtmp, sig, w, ce->tmp1);
  const int rv = CallRhs(ce, ce->t_eval, ce->x_eval, ce->tmp1, ce->tmp2);
  ++ce->nfeDQ;
  if (rv != 0) return rv;
  // z <- z - kappa (f(v + sig w) - f(v)) / sig
  N_VLinearSum(1, ce->tmp2, -1, ce->ftmp, ce->tmp2);
  N_VLinearSum(1, z, -ce->kappa_setup / sig, ce->tmp2, z);
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
    ++ce->nfeDQ;
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
    ++ce->nfeDQ;
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

int LsInitialize(CEodeMemRec* ce, const char* func) {
  ce->a_holds = Holds::kNothing;
  ce->mass_dirty = true;
  ce->mass_evaluated = false;
  ce->nst_lastsetup = -1;
  ce->jac_current = false;
  if (HasConstraints(ce)) return CE_SUCCESS;  // the saddle-point solver owns the LS
  if (ce->M != nullptr && ce->LS == nullptr) {
    return ProcessError(ce, CE_LINIT_FAIL, func,
                        "A mass matrix is set but no linear solver: attach one with "
                        "CEodeSetLinearSolver (e.g. SUNLinSol_Dense with a dense matrix).");
  }
  if (ce->LS == nullptr) return CE_SUCCESS;
  if (ce->A == nullptr && !ce->ls_matrix_free) {
    return ProcessError(
        ce, CE_LINIT_FAIL, func,
        "The attached linear solver needs a matrix: pass A to CEodeSetLinearSolver.");
  }
  if (ce->A != nullptr && SUNMatGetID(ce->A) != SUNMATRIX_DENSE &&
      SUNMatGetID(ce->A) != SUNMATRIX_BAND && ce->vel_dependent && ce->jac == nullptr) {
    return ProcessError(
        ce, CE_LINIT_FAIL, func,
        "Difference-quotient Jacobians support dense and band matrices only: supply "
        "df/dv with CEodeSetVelJacFn for this matrix type (e.g. sparse/KLU).");
  }
  if (ce->A != nullptr && ce->vel_dependent && ce->jac == nullptr && !HasLocalData(ce->xcur)) {
    return ProcessError(ce, CE_LINIT_FAIL, func,
                        "Difference-quotient Jacobians need vectors with local data "
                        "(N_VGetArrayPointer): supply df/dv with CEodeSetVelJacFn.");
  }
  if (ce->A != nullptr && ce->vel_dependent && ce->Jsave == nullptr) {
    ce->Jsave = SUNMatClone(ce->A);
    if (ce->Jsave == nullptr) return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
  }
  if (ce->ls_matrix_free && SUNLinSolSetATimes(ce->LS, ce, ATimes) != 0) {
    return ProcessError(
        ce, CE_LINIT_FAIL, func,
        "The linear solver does not accept a matrix-free product: attach a matrix.");
  }
  return InitLinearSolver(ce, ce->LS, func);
}

int InitLinearSolver(CEodeMemRec* ce, SUNLinearSolver LS, const char* func) {
  const int rv = SUNLinSolInitialize(LS);
  if (rv != 0) {
    return ProcessError(ce, CE_LINIT_FAIL, func, "SUNLinSolInitialize failed (returned %d).", rv);
  }
  return CE_SUCCESS;
}

void LsFree(CEodeMemRec* ce) {
  if (ce->Jsave != nullptr) SUNMatDestroy(ce->Jsave);
  ce->Jsave = nullptr;
}

int MassUpdate(CEodeMemRec* ce, sunrealtype t, N_Vector x, const char* func) {
  if (ce->mfn == nullptr) return CE_SUCCESS;
  if (ce->mass_constant && ce->mass_evaluated) return CE_SUCCESS;
  SUNMatZero(ce->M);
  const int rv = ce->mfn(t, x, ce->M, ce->user_data, ce->tmp1, ce->tmp2, ce->tmp3);
  ++ce->nme;
  if (rv != 0) {
    return ProcessError(ce, CE_MASSFUNC_FAIL, func,
                        "The mass matrix function failed (returned %d) at t = %.17g.", rv,
                        static_cast<double>(t));
  }
  ce->mass_evaluated = true;
  ce->mass_dirty = true;
  return CE_SUCCESS;
}

int MassSolve(CEodeMemRec* ce, N_Vector b, const char* func) {
  if (ce->M == nullptr) return CE_SUCCESS;
  if (ce->a_holds != Holds::kMass || ce->mass_dirty) {
    int rv = 0;
    if (ce->A != nullptr) rv = SUNMatCopy(ce->M, ce->A);
    ce->a_holds = Holds::kMass;
    if (rv == 0) rv = SUNLinSolSetup(ce->LS, ce->A);
    ++ce->nsetups;
    if (rv != 0) {
      ce->a_holds = Holds::kNothing;
      return ProcessError(ce, CE_LSETUP_FAIL, func,
                          "The mass matrix could not be factored (linear solver setup returned "
                          "%d): M is singular. Check CEodeMassFn; a system with massless "
                          "coordinates needs constraints (CEodeSetConstraints).",
                          rv);
    }
    ce->mass_dirty = false;
    ce->jac_current = false;  // A no longer holds the Newton matrix
  }
  N_VConst(0, ce->lstmp);
  // Direct solvers ignore the tolerance; an iterative one must solve M a = f to
  // near round-off, unscaled, or the acceleration itself carries its residual.
  sunrealtype tol = 0;
  if (SUNLinSolGetType(ce->LS) != SUNLINEARSOLVER_DIRECT) {
    SUNLinSolSetScalingVectors(ce->LS, nullptr, nullptr);
    tol = SUN_RCONST(1e-13) * std::sqrt(N_VDotProd(b, b));
  }
  const int rv = SUNLinSolSolve(ce->LS, ce->A, ce->lstmp, b, tol);
  ++ce->nls_solves;
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
  if (ce->jac != nullptr) {
    SUNMatZero(J);
    rv = ce->jac(t, x, v, fv, J, ce->user_data, ce->tmp1, ce->tmp2, ce->tmp3);
  } else if (SUNMatGetID(J) == SUNMATRIX_DENSE) {
    rv = DenseDqJac(ce, t, x, v, fv, J);
  } else {
    rv = BandDqJac(ce, t, x, v, fv, J);
  }
  ++ce->nje;
  if (rv != 0) {
    // A fixed step cannot retry with a smaller h, so every failure is final.
    return ProcessError(ce, CE_JACFUNC_FAIL, func,
                        "The velocity Jacobian df/dv could not be evaluated (f or the Jacobian "
                        "function returned %d) at t = %.17g.",
                        rv, static_cast<double>(t));
  }
  return CE_SUCCESS;
}

int NewtonSetup(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector v, N_Vector fv,
                sunrealtype kappa, const char* func) {
  ce->kappa_setup = kappa;
  if (ce->A != nullptr) {
    const int flag = VelJacobian(ce, t, x, v, fv, ce->Jsave, func);
    if (flag != CE_SUCCESS) {
      ce->cb_flag = flag;
      return -1;
    }
    int rv;
    rv = SUNMatCopy(ce->Jsave, ce->A);
    if (rv == 0) rv = ce->M ? SUNMatScaleAdd(-kappa, ce->A, ce->M) : SUNMatScaleAddI(-kappa, ce->A);
    if (rv != 0) {
      ce->cb_flag = ProcessError(ce, CE_LSETUP_FAIL, func,
                                 "Forming M - kappa df/dv failed (%d): M, A and the Jacobian must "
                                 "share a matrix type and size.",
                                 rv);
      return -1;
    }
  }
  ce->mass_dirty = false;  // A is built from the current M
  ce->a_holds = Holds::kNewton;
  const int rv = SUNLinSolSetup(ce->LS, ce->A);
  ++ce->nsetups;
  ce->nst_lastsetup = ce->nst;
  ce->jac_current = true;
  if (rv != 0) {
    ce->a_holds = Holds::kNothing;
    ce->cb_flag = ProcessError(ce, CE_LSETUP_FAIL, func,
                               "The Newton matrix M - kappa df/dv is singular or could not be "
                               "factored (linear solver setup returned %d) at t = %.17g: check "
                               "M and df/dv, or reduce h.",
                               rv, static_cast<double>(t));
    return -1;
  }
  return 0;
}

int NewtonSolve(CEodeMemRec* ce, N_Vector b, const char* func) {
  if (ce->ls_matrix_free) SUNLinSolSetScalingVectors(ce->LS, ce->ewt, ce->ewt);
  N_VConst(0, ce->lstmp);
  // Iterative solvers stop at a fraction of the Newton tolerance (weighted norm 1).
  const int rv = SUNLinSolSolve(ce->LS, ce->A, ce->lstmp, b, SUN_RCONST(0.05));
  ++ce->nls_solves;
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
  ce->mfn = mfn;
  ce->M = M;
  ce->mass_constant = constant != SUNFALSE;
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
  if (ce->own_nls) ceode::NlsFree(ce);  // CEODE's own choice (fixed point/Newton) is made anew
  ce->LS = LS;
  ce->A = A;
  ce->ls_matrix_free = (A == nullptr);
  if (ce->Jsave != nullptr) {
    SUNMatDestroy(ce->Jsave);
    ce->Jsave = nullptr;
  }
  ceode::Restart(ce);
  return CE_SUCCESS;
}

int CEodeSetVelJacFn(void* mem, CEodeVelJacFn jac) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  ce->jac = jac;
  ce->jac_current = false;
  ceode::Restart(ce);  // solver workspaces (e.g. the constrained Jacobian) are sized at start
  return CE_SUCCESS;
}

}  // extern "C"
