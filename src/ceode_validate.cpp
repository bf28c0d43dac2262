// One validation point per attached object. Every object the user hands over (mass matrix,
// linear solver and its matrix, nonlinear solver, constraint template, method parameters, step
// size) is checked where it enters (its setter) and again at the first CEodeEvolve after a
// configuration change, because the problem size can change after the object was attached
// (CEodeInit with a new n, constraints added or removed). An object that does not fit is refused
// with a message naming it; it is never used, so a wrong size cannot reach SUNDIALS' kernels.
#include <sunlinsol/sunlinsol_band.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunlinsol/sunlinsol_pcg.h>
#include <sunlinsol/sunlinsol_spbcgs.h>
#include <sunlinsol/sunlinsol_spfgmr.h>
#include <sunlinsol/sunlinsol_spgmr.h>
#include <sunlinsol/sunlinsol_sptfqmr.h>
#include <sunmatrix/sunmatrix_band.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>
#include <sunnonlinsol/sunnonlinsol_newton.h>

#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstring>

#include "ceode_impl.hpp"

namespace ceode {

namespace {

// Why a method or step was refused, filled by the pure checks below.
void SetWhy(char* why, size_t len, const char* fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
void SetWhy(char* why, size_t len, const char* fmt, ...) {
  if (why == nullptr || len == 0) return;
  va_list ap;
  va_start(ap, fmt);
  std::vsnprintf(why, len, fmt, ap);
  va_end(ap);
}

bool FiniteNonzero(sunrealtype v) { return std::isfinite(v) && v != 0; }

// Every coefficient of one step of size h finite, and the ones that divide or carry the update
// (kappa, the powers h^i / i! up to the dense output's h^d) also nonzero.
bool StepCoeffsUsable(int degree, const sunrealtype* params, sunrealtype h, bool need_mu, char* why,
                      size_t len) {
  StepCoeffs co;
  ComputeStepCoeffs(degree, params, h, &co);
  sunrealtype hp = 1;
  for (int i = 1; i <= degree; ++i) {
    hp = hp * h / i;  // h^i / i! as a running product
    if (!FiniteNonzero(hp)) {
      SetWhy(why, len, "h^%d/%d! = %g is %s in floating point", i, i, static_cast<double>(hp),
             hp == 0 ? "zero" : "not finite");
      return false;
    }
  }
  bool finite = std::isfinite(co.wz_old) && std::isfinite(co.wz_new);
  for (int k = 0; k < kMaxDegree; ++k) {
    finite = finite && std::isfinite(co.c[k]) && std::isfinite(co.w[k]) && std::isfinite(co.V0[k]);
    for (int j = 0; j < kMaxDegree; ++j) finite = finite && std::isfinite(co.T[k][j]);
  }
  if (!finite || !FiniteNonzero(co.kappa) || !std::isfinite(co.mu) || (need_mu && co.mu == 0)) {
    SetWhy(why, len,
           "the step's coefficients are not usable (kappa = %g, mu = %g; a coefficient "
           "overflows, underflows to zero or divides by zero)",
           static_cast<double>(co.kappa), static_cast<double>(co.mu));
    return false;
  }
  return true;
}

// Rows and columns of the SUNDIALS matrix types CEODE can read; false for other types.
bool MatrixShape(SUNMatrix A, sunindextype* rows, sunindextype* cols) {
  switch (SUNMatGetID(A)) {
    case SUNMATRIX_DENSE:
      *rows = SUNDenseMatrix_Rows(A);
      *cols = SUNDenseMatrix_Columns(A);
      return true;
    case SUNMATRIX_BAND:
      *rows = *cols = SUNBandMatrix_Columns(A);
      return true;
    case SUNMATRIX_SPARSE:
      *rows = SUNSparseMatrix_Rows(A);
      *cols = SUNSparseMatrix_Columns(A);
      return true;
    default:
      return false;
  }
}

const char* MatrixKind(SUNMatrix A) {
  switch (SUNMatGetID(A)) {
    case SUNMATRIX_DENSE:
      return "dense";
    case SUNMATRIX_BAND:
      return "band";
    case SUNMATRIX_SPARSE:
      return "sparse";
    default:
      return "custom";
  }
}

// The size the linear solver's matrix must have now: the saddle-point system with constraints.
sunindextype SolverSize(const CEodeMemRec* ce) {
  return ce->n + (HasConstraints(ce) ? ce->con.nc : 0);
}

// SUNDIALS' dense and band solvers keep pivots of the length they were created with: a solver
// made for a smaller matrix would write past them in its factorisation.
int CheckSolverMatrixPair(CEodeMemRec* ce, const char* func, SUNLinearSolver LS, SUNMatrix A,
                          sunindextype cols) {
  const SUNLinearSolver_ID id = SUNLinSolGetID(LS);
  const SUNMatrix_ID mid = SUNMatGetID(A);
  sunindextype ls_n = -1;
  if (id == SUNLINEARSOLVER_DENSE && mid == SUNMATRIX_DENSE) {
    ls_n = static_cast<SUNLinearSolverContent_Dense>(LS->content)->N;
  } else if (id == SUNLINEARSOLVER_BAND && mid == SUNMATRIX_BAND) {
    ls_n = static_cast<SUNLinearSolverContent_Band>(LS->content)->N;
  } else if ((id == SUNLINEARSOLVER_DENSE && mid != SUNMATRIX_DENSE) ||
             (id == SUNLINEARSOLVER_BAND && mid != SUNMATRIX_BAND) ||
             (id == SUNLINEARSOLVER_KLU && mid != SUNMATRIX_SPARSE)) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "The linear solver and its matrix are incompatible: a %s matrix was "
                        "passed to a %s solver. Create the solver from the matrix you pass.",
                        MatrixKind(A),
                        id == SUNLINEARSOLVER_DENSE  ? "dense"
                        : id == SUNLINEARSOLVER_BAND ? "band"
                                                     : "sparse (KLU)");
  }
  if (ls_n >= 0 && ls_n != cols) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "The linear solver was created for %ld unknowns but its matrix A is "
                        "%ld x %ld: create the solver from A (e.g. SUNLinSol_Dense(y, A, ctx)).",
                        static_cast<long>(ls_n), static_cast<long>(cols), static_cast<long>(cols));
  }
  return CE_SUCCESS;
}

// Length of the vectors inside SUNDIALS' own nonlinear solvers; -1 for any other solver, whose
// memory CEODE cannot inspect. The solve function identifies the implementation, so the content
// is only read when its layout is the one declared in the SUNDIALS header.
sunindextype NlsVectorLength(SUNNonlinearSolver NLS) {
  if (NLS->ops == nullptr || NLS->content == nullptr) return -1;
  if (NLS->ops->solve == SUNNonlinSolSolve_Newton) {
    N_Vector d = static_cast<SUNNonlinearSolverContent_Newton>(NLS->content)->delta;
    return d != nullptr ? N_VGetLength(d) : -1;
  }
  if (NLS->ops->solve == SUNNonlinSolSolve_FixedPoint) {
    N_Vector y = static_cast<SUNNonlinearSolverContent_FixedPoint>(NLS->content)->yprev;
    return y != nullptr ? N_VGetLength(y) : -1;
  }
  return -1;
}

// Length of the work vectors inside SUNDIALS' own Krylov solvers, which a matrix-free solve runs
// on the problem's vectors; -1 for any other solver, whose memory CEODE cannot inspect.
sunindextype KrylovVectorLength(SUNLinearSolver LS) {
  if (LS->content == nullptr) return -1;
  N_Vector w = nullptr;
  switch (SUNLinSolGetID(LS)) {
    case SUNLINEARSOLVER_SPGMR:
      w = static_cast<SUNLinearSolverContent_SPGMR>(LS->content)->vtemp;
      break;
    case SUNLINEARSOLVER_SPFGMR:
      w = static_cast<SUNLinearSolverContent_SPFGMR>(LS->content)->vtemp;
      break;
    case SUNLINEARSOLVER_SPBCGS:
      w = static_cast<SUNLinearSolverContent_SPBCGS>(LS->content)->vtemp;
      break;
    case SUNLINEARSOLVER_SPTFQMR:
      w = static_cast<SUNLinearSolverContent_SPTFQMR>(LS->content)->vtemp1;
      break;
    case SUNLINEARSOLVER_PCG:
      w = static_cast<SUNLinearSolverContent_PCG>(LS->content)->r;
      break;
    default:
      break;
  }
  return w != nullptr ? N_VGetLength(w) : -1;
}

// A matrix-free solver works on vectors of length n (constraints refuse it at the start).
int CheckKrylovLength(CEodeMemRec* ce, const char* func, SUNLinearSolver LS) {
  const sunindextype len = KrylovVectorLength(LS);
  if (!ce->initialized || len < 0 || len == ce->n) return CE_SUCCESS;
  return ProcessError(ce, CE_ILL_INPUT, func,
                      "The matrix-free linear solver was created for vectors of length %ld but the "
                      "problem has n = %ld: create it from a vector of the length of x0 (e.g. "
                      "SUNLinSol_SPGMR(x0, SUN_PREC_NONE, 0, ctx)).",
                      static_cast<long>(len), static_cast<long>(ce->n));
}

}  // namespace

int ValidateMethodParams(int degree, const sunrealtype* params, char* why, size_t len) {
  if (degree < kMinDegree || degree > kMaxDegree) {
    SetWhy(why, len, "degree = %d: supported degrees are %d..%d", degree, kMinDegree, kMaxDegree);
    return CE_ILL_INPUT;
  }
  if (params == nullptr) {
    SetWhy(why, len, "params = NULL: pass degree-1 parameters (alpha, beta, gamma, ...)");
    return CE_ILL_INPUT;
  }
  for (int i = 0; i < degree - 1; ++i) {
    if (!std::isfinite(params[i])) {
      SetWhy(why, len, "params[%d] is not finite", i);
      return CE_ILL_INPUT;
    }
  }
  // p_1 (and p_2 for d >= 4) divide in kappa = c_1 / c_2 and z = (a - B_2)/c_2.
  if ((degree >= 4 && params[2] == 0) || params[1] == 0) {
    SetWhy(why, len, "beta%s must be nonzero: the velocity would not depend on the acceleration",
           degree >= 4 ? " and gamma" : "");
    return CE_ILL_INPUT;
  }
  // The step of size 1 is the one the stability analysis builds (CEodeStabilityLimit): a set
  // whose coefficients overflow there (gamma = 5e-324) cannot be analysed or integrated.
  char inner[256] = "";
  if (!StepCoeffsUsable(degree, params, 1, false, inner, sizeof(inner))) {
    SetWhy(why, len, "these parameters give a degenerate step: %s", inner);
    return CE_ILL_INPUT;
  }
  return CE_SUCCESS;
}

int ValidateTime(CEodeMemRec* ce, const char* func, const char* name, sunrealtype t) {
  // A non-finite time would reach every output with CE_SUCCESS (tret, dense output, stop time).
  if (std::isfinite(t)) return CE_SUCCESS;
  return ProcessError(ce, CE_ILL_INPUT, func, "%s = %g is not finite: pass a finite time.", name,
                      static_cast<double>(t));
}

int ValidateNonlinTolerances(CEodeMemRec* ce, const char* func, sunrealtype reltol,
                             sunrealtype abstol) {
  if (!(reltol > 0) || !std::isfinite(reltol) || !(abstol >= 0) || !std::isfinite(abstol)) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "reltol = %g, abstol = %g: need a finite reltol > 0 and a finite "
                        "abstol >= 0.",
                        static_cast<double>(reltol), static_cast<double>(abstol));
  }
  return CE_SUCCESS;
}

int ValidateStep(CEodeMemRec* ce, const char* func) {
  if (AdaptOn(ce)) return CE_SUCCESS;  // the start chooses h (ceode_adapt.cpp)
  const sunrealtype h = ce->h;
  if (!(h > 0) || !std::isfinite(h)) {
    return ProcessError(
        ce, CE_ILL_INPUT, func,
        "No step size: call CEodeSetFixedStep(mem, h) with h > 0 before CEodeEvolve.");
  }
  if (!(ce->tcur + h > ce->tcur) || !std::isfinite(ce->tcur + h)) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "h = %g is too small for t = %.17g: t + h == t in floating point, so the "
                        "run could not advance. Use a larger h (or shift t0 towards 0).",
                        static_cast<double>(h), static_cast<double>(ce->tcur));
  }
  char why[256] = "";
  if (!StepCoeffsUsable(ce->degree, ce->params, h, HasConstraints(ce), why, sizeof(why))) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "h = %g cannot be used with %s: %s. Choose h so that the powers h^k "
                        "(k <= degree) neither overflow nor underflow.",
                        static_cast<double>(h), ce->method_name.c_str(), why);
  }
  return CE_SUCCESS;
}

int ValidateMassMatrix(CEodeMemRec* ce, const char* func, SUNMatrix M) {
  if (M == nullptr || !ce->initialized) return CE_SUCCESS;
  sunindextype rows = 0, cols = 0;
  if (!MatrixShape(M, &rows, &cols)) {
    if (HasConstraints(ce)) {
      return ProcessError(ce, CE_ILL_INPUT, func,
                          "With constraints the mass matrix must be a dense or sparse "
                          "SUNMatrix (its entries enter the saddle-point matrix).");
    }
    return CE_SUCCESS;  // a custom type: only its own operations touch it
  }
  if (rows != ce->n || cols != ce->n) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "The mass matrix M is %ld x %ld but the problem has n = %ld: M must be "
                        "n x n (create it for the length of x0).",
                        static_cast<long>(rows), static_cast<long>(cols), static_cast<long>(ce->n));
  }
  if (HasConstraints(ce) && SUNMatGetID(M) == SUNMATRIX_BAND) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "With constraints the mass matrix must be dense or sparse, not band.");
  }
  return CE_SUCCESS;
}

// On the unconstrained path A receives copies of M (SUNMatCopy) and M - kappa J (SUNMatScaleAdd):
// SUNDIALS refuses both for matrices of different type or size ("incompatible matrices").
int ValidateMassAgainstSolver(CEodeMemRec* ce, const char* func) {
  if (ce->ls.M == nullptr || ce->ls.A == nullptr || HasConstraints(ce)) return CE_SUCCESS;
  sunindextype mr = 0, mc = 0, ar = 0, ac = 0;
  const bool known = MatrixShape(ce->ls.M, &mr, &mc) && MatrixShape(ce->ls.A, &ar, &ac);
  if (SUNMatGetID(ce->ls.M) != SUNMatGetID(ce->ls.A) || (known && (mr != ar || mc != ac))) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "The mass matrix (%s, %ld x %ld) and the linear solver's matrix A (%s, "
                        "%ld x %ld) are incompatible: without constraints A holds copies of M, so "
                        "both must have the same type and size n x n (n = %ld).",
                        MatrixKind(ce->ls.M), static_cast<long>(mr), static_cast<long>(mc),
                        MatrixKind(ce->ls.A), static_cast<long>(ar), static_cast<long>(ac),
                        static_cast<long>(ce->n));
  }
  return CE_SUCCESS;
}

int ValidateLinearSolver(CEodeMemRec* ce, const char* func, SUNLinearSolver LS, SUNMatrix A,
                         bool at_start) {
  if (LS != nullptr && A == nullptr) return CheckKrylovLength(ce, func, LS);
  if (LS == nullptr || A == nullptr) return CE_SUCCESS;
  sunindextype rows = 0, cols = 0;
  if (!MatrixShape(A, &rows, &cols)) return CE_SUCCESS;  // custom matrix: its solver's business
  if (rows != cols) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "The linear solver's matrix A is %ld x %ld: it must be square.",
                        static_cast<long>(rows), static_cast<long>(cols));
  }
  int flag = CheckSolverMatrixPair(ce, func, LS, A, cols);
  if (flag != CE_SUCCESS || !ce->initialized) return flag;
  const sunindextype need = SolverSize(ce);
  // Before the start a larger A may wait for constraints still to be set; at the start the
  // size is final.
  const bool wrong = (at_start || HasConstraints(ce)) ? rows != need : rows < ce->n;
  if (wrong) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "The linear solver's matrix A is %ld x %ld but %s: attach a solver and "
                        "matrix of size %ld (after CEodeInit with a new size or a change of the "
                        "constraints, attach a new one with CEodeSetLinearSolver).",
                        static_cast<long>(rows), static_cast<long>(cols),
                        HasConstraints(ce) ? "with constraints it must hold the saddle-point "
                                             "matrix of size n + nc"
                                           : "the problem without constraints has size n",
                        static_cast<long>(need));
  }
  return CE_SUCCESS;
}

int ValidateNonlinearSolver(CEodeMemRec* ce, const char* func, SUNNonlinearSolver NLS) {
  if (NLS == nullptr || !ce->initialized) return CE_SUCCESS;
  const sunindextype len = NlsVectorLength(NLS);
  if (len >= 0 && len != ce->n) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "The nonlinear solver was created for vectors of length %ld but the "
                        "problem has n = %ld: create it from a vector of the length of x0 (e.g. "
                        "SUNNonlinSol_Newton(x0, ctx)).",
                        static_cast<long>(len), static_cast<long>(ce->n));
  }
  return CE_SUCCESS;
}

int ValidateConfiguration(CEodeMemRec* ce, const char* func) {
  int flag = ValidateStep(ce, func);
  if (flag == CE_SUCCESS) flag = ValidateMassMatrix(ce, func, ce->ls.M);
  if (flag == CE_SUCCESS) flag = ValidateLinearSolver(ce, func, ce->ls.LS, ce->ls.A, true);
  if (flag == CE_SUCCESS) flag = ValidateMassAgainstSolver(ce, func);
  if (flag == CE_SUCCESS && ce->vel_dependent && !HasConstraints(ce)) {
    flag = ValidateNonlinearSolver(ce, func, ce->nls.NLS);
  }
  if (flag == CE_SUCCESS) flag = ValidateConstraintTemplate(ce, func);
  return flag;
}

int ValidateStart(CEodeMemRec* ce, const char* func) {
  for (int k = 1; k < ce->degree; ++k) {
    if (!IsFinite(ce->D[k])) {
      Restart(ce);
      return ProcessError(ce, CE_FIRST_RHSFUNC_ERR, func,
                          "The %s start produced a non-finite derivative D_%d (%s) at t0 = %.17g: "
                          "f (or the mass solve) returned NaN or Inf %s. The initial data are "
                          "outside the range where f stays finite; rescale the problem, reduce h, "
                          "or use CEodeSetZeroStart.",
                          ce->zero_start ? "zero" : "consistent", k,
                          k == 1 ? "velocity" : (k == 2 ? "acceleration" : "higher derivative"),
                          static_cast<double>(ce->tcur),
                          k <= 2 ? "at t0"
                                 : "on the start stencil t0 +- j h (the Taylor curve "
                                   "of the initial data)");
    }
  }
  if (!IsFinite(ce->xnext)) {
    Restart(ce);
    return ProcessError(ce, CE_FIRST_RHSFUNC_ERR, func,
                        "The start produced a non-finite first position x(t0 + h) at t0 = %.17g: "
                        "the initial derivatives overflow over one step of h = %g; reduce h or "
                        "rescale the problem.",
                        static_cast<double>(ce->tcur), static_cast<double>(ce->h));
  }
  return CE_SUCCESS;
}

sunrealtype MaxNormOrNaN(N_Vector v) { return IsFinite(v) ? N_VMaxNorm(v) : NAN; }

}  // namespace ceode
