// Index-3 constraints without index reduction (method.md section 3).
//
// At a step at time t the unknowns are a = x''(t) and lambda(t):
//   F1 = f(t, x_t, v(a)) - M a - G(x_t)^T lambda = 0,   v(a) = V0 + kappa a
//   F2 = Phi(x(t+h; a), t+h) = 0,                       x(t+h; a) = X0 + mu (a - B_2)
// Newton in (a, lambda), linearising Phi at the current iterate x_i of x(t+h), H = G(x_i):
//   (M - kappa J) da + G_t^T dlambda = F1,   mu H da = -Phi(x_i).
// In (da, dlambda) the matrix is useless for small h (the second block row carries mu ~ h^2..h^4).
// With the position increment delta = mu da and the scaled multiplier s = mu dlambda, and the
// first block row multiplied by mu:
//   [ M - kappa J   G_t^T ] [ delta ]   [ mu F1  ]
//   [ H             0     ] [   s   ] = [ -Phi_i ]
// Every block is O(1) for every h. Note the M block is M - kappa J, not M - (kappa/mu) J as
// method.md writes: the ratio of the two terms is fixed by the equation, not by the unknowns'
// scaling, and kappa/mu ~ 1/h would make the damping term dominate for small h.
//
// The residual is always exact (current G_t, current Phi); the matrix may be stale (simplified
// Newton across iterations and steps) and is refreshed when the contraction slows. Convergence is
// measured on delta, the change of x(t+h), down to round-off of x.
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <algorithm>
#include <cmath>
#include <new>
#include <vector>

#include "ceode_impl.hpp"

namespace ceode {

namespace {

constexpr int kMaxIters = 12;            // Newton iterations per solve, refreshes included
constexpr sunrealtype kSlowRate = 0.2;   // refresh the matrix when the contraction is slower
constexpr sunrealtype kTolUlps = 8;      // convergence: |delta| below this many ulps of |x|
constexpr sunrealtype kFloorUlps = 1e3;  // round-off stagnation is accepted below this

struct Entry {
  sunindextype r, c;
  sunrealtype v;
};

// Private workspace of the saddle-point solver (ce->con).
struct ConWork {
  sunindextype n = 0, nc = 0, N = 0;
  int degree = 0;
  bool sparse = false;  // A is a SUNSparseMatrix
  bool csr = true;
  bool klu = false;
  bool own_ls = false;
  SUNLinearSolver LS = nullptr;
  SUNMatrix A = nullptr;
  SUNMatrix Gt = nullptr;        // G(x(t), t): the direction of the constraint forces
  SUNMatrix Gh = nullptr;        // G at the iterate of x(t+h): linearises Phi
  SUNMatrix J = nullptr;         // df/dv from the user's CEodeVelJacFn
  std::vector<sunrealtype> Jdq;  // df/dv by difference quotients, dense column-major
  N_Vector b = nullptr;          // serial saddle vectors of length n + nc
  N_Vector sol = nullptr;
  N_Vector xtrial = nullptr, fval = nullptr, r1 = nullptr, delta = nullptr, vtmp = nullptr;
  N_Vector inc = nullptr, xpt = nullptr, vpt = nullptr, fpt = nullptr, a0 = nullptr;
  N_Vector vbase = nullptr;  // velocity offset V0 of v(a) = V0 + kappa a
  N_Vector lam = nullptr, lam_prev = nullptr, s = nullptr, gam = nullptr;
  std::vector<Entry> entries;
  std::vector<sunindextype> pat_ptr, pat_idx;  // pattern of the last sparse factorization
  bool factored = false;  // the LS holds a step matrix usable for simplified Newton
  sunrealtype kappa_fact = 0;
  long int nst_fact = -1;
  bool lam_prev_valid = false;  // lam_prev holds lambda(t - 2h) for the predictor
};

ConWork* Work(CEodeMemRec* ce) { return static_cast<ConWork*>(ce->con); }

void Destroy(N_Vector* v) {
  if (*v != nullptr) N_VDestroy(*v);
  *v = nullptr;
}
void Destroy(SUNMatrix* m) {
  if (*m != nullptr) SUNMatDestroy(*m);
  *m = nullptr;
}

void FreeWork(CEodeMemRec* ce) {
  ConWork* w = Work(ce);
  if (w == nullptr) return;
  N_Vector* vecs[] = {&w->b,     &w->sol, &w->xtrial,   &w->fval, &w->r1,  &w->delta,
                      &w->vtmp,  &w->inc, &w->xpt,      &w->vpt,  &w->fpt, &w->a0,
                      &w->vbase, &w->lam, &w->lam_prev, &w->s,    &w->gam};
  for (N_Vector* v : vecs) Destroy(v);
  if (w->own_ls) {
    if (w->LS != nullptr) SUNLinSolFree(w->LS);
    Destroy(&w->A);
  }
  Destroy(&w->Gt);
  Destroy(&w->Gh);
  Destroy(&w->J);
  delete w;
  ce->con = nullptr;
}

// Calls fn(row, col, value) for every stored entry; dense matrices give their nonzeros (and the
// diagonal, so that a sparse pattern does not change when a diagonal value passes through 0).
template <class Fn>
void ForEachEntry(SUNMatrix M, Fn fn) {
  if (SUNMatGetID(M) == SUNMATRIX_DENSE) {
    const sunindextype m = SUNDenseMatrix_Rows(M);
    const sunindextype n = SUNDenseMatrix_Columns(M);
    const sunrealtype* data = SUNDenseMatrix_Data(M);  // column-major, leading dimension m
    for (sunindextype j = 0; j < n; ++j) {
      const sunrealtype* col = data + j * m;
      for (sunindextype i = 0; i < m; ++i) {
        if (col[i] != 0 || i == j) fn(i, j, col[i]);
      }
    }
    return;
  }
  const sunindextype np = SUNSparseMatrix_NP(M);
  const sunindextype* ptr = SUNSparseMatrix_IndexPointers(M);
  const sunindextype* idx = SUNSparseMatrix_IndexValues(M);
  const sunrealtype* val = SUNSparseMatrix_Data(M);
  const bool csr = SUNSparseMatrix_SparseType(M) == CSR_MAT;
  for (sunindextype p = 0; p < np; ++p) {
    for (sunindextype k = ptr[p]; k < ptr[p + 1]; ++k) {
      if (csr) {
        fn(p, idx[k], val[k]);
      } else {
        fn(idx[k], p, val[k]);
      }
    }
  }
}

// y += alpha G^T lam (G is nc x n); arrays of local data.
void AddGTransposeTimes(SUNMatrix G, sunrealtype alpha, const sunrealtype* lam, sunrealtype* y) {
  ForEachEntry(G,
               [&](sunindextype r, sunindextype c, sunrealtype v) { y[c] += alpha * v * lam[r]; });
}

bool AllFinite(N_Vector v) { return IsFinite(v); }

// x(t+h) from the acceleration a = Dnew[2] by TakeStep's own update (FormUpdate), so
// the predictor is exactly the position TakeStep will form. The iterates then move
// x(t+h) by the Newton increments, and the final x agrees with TakeStep's to a few ulps.
void StepPosition(CEodeMemRec* ce, N_Vector a, N_Vector xout) {
  if (a != ce->Dnew[2]) N_VScale(1, a, ce->Dnew[2]);
  FormUpdate(ce);
  N_VScale(1, ce->xnew, xout);
}

// The first position of the method: the Taylor polynomial of the derivatives at t0 with the
// acceleration a (the unknown of the constrained first step).
void StartPosition(CEodeMemRec* ce, ConWork* w, N_Vector x0, N_Vector a, N_Vector xout) {
  const int d = ce->degree;
  const sunrealtype h = ce->h;
  sunrealtype cw[kMaxDegree];
  N_Vector vw[kMaxDegree];
  sunrealtype hp = 1;
  for (int i = 1; i < d; ++i) {
    hp *= h / i;
    cw[i - 1] = hp;
    vw[i - 1] = (i == 2) ? a : ce->D[i];
  }
  N_VLinearCombination(d - 1, cw, vw, w->inc);
  N_VLinearSum(1, x0, 1, w->inc, xout);
}

int EvalPhi(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector phi, const char* func) {
  const int rv = ce->phifn(t, x, phi, ce->user_data);
  ++ce->nce;
  if (rv != 0) {
    return ProcessError(ce, CE_CONSTR_FAIL, func,
                        "The constraint function failed (returned %d) at t = %.17g. The step was "
                        "not taken; the state is the last good one.",
                        rv, static_cast<double>(t));
  }
  if (!AllFinite(phi)) {
    return ProcessError(ce, CE_CONSTR_FAIL, func,
                        "The constraint function returned NaN or Inf at t = %.17g: check Phi (and "
                        "that h is small enough to keep the positions in its domain).",
                        static_cast<double>(t));
  }
  return CE_SUCCESS;
}

int EvalG(CEodeMemRec* ce, sunrealtype t, N_Vector x, SUNMatrix G, const char* func) {
  SUNMatZero(G);
  const int rv = ce->Gfn(t, x, G, ce->user_data);
  if (rv != 0) {
    return ProcessError(ce, CE_CONSTR_FAIL, func,
                        "The constraint Jacobian function failed (returned %d) at t = %.17g.", rv,
                        static_cast<double>(t));
  }
  bool finite = true;
  ForEachEntry(G, [&](sunindextype, sunindextype, sunrealtype v) { finite &= std::isfinite(v); });
  if (!finite) {
    return ProcessError(ce, CE_CONSTR_FAIL, func,
                        "The constraint Jacobian contains NaN or Inf at t = %.17g.",
                        static_cast<double>(t));
  }
  return CE_SUCCESS;
}

int EvalF(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector v, N_Vector f, const char* func) {
  const int flag = EvalRhs(ce, t, x, v, f, func);
  if (flag != CE_SUCCESS) return flag;
  if (!AllFinite(f)) {
    return ProcessError(ce, CE_RHSFUNC_FAIL, func,
                        "The right-hand side returned NaN or Inf at t = %.17g.",
                        static_cast<double>(t));
  }
  return CE_SUCCESS;
}

// df/dv at (t, x, v) with f(t, x, v) = fv, from the user's function or by difference quotients.
int EvalVelJac(CEodeMemRec* ce, ConWork* w, sunrealtype t, N_Vector x, N_Vector v, N_Vector fv,
               const char* func) {
  ++ce->nje;
  int rv = 0;
  if (ce->jac != nullptr) {
    SUNMatZero(w->J);
    rv = ce->jac(t, x, v, fv, w->J, ce->user_data, ce->tmp1, ce->tmp2, ce->tmp3);
  } else {
    const sunindextype n = w->n;
    w->Jdq.assign(static_cast<size_t>(n * n), 0);
    N_VScale(1, v, w->vpt);
    sunrealtype* vp = N_VGetArrayPointer(w->vpt);
    const sunrealtype* vd = N_VGetArrayPointer(v);
    const sunrealtype vscale = 1e-3 * N_VMaxNorm(v);
    for (sunindextype j = 0; j < n && rv == 0; ++j) {
      // The floor matters at rest (v = 0): a floor of order sqrt(eps) itself would put the
      // increment at eps and the quotient in round-off.
      const sunrealtype inc =
          std::sqrt(SUN_UNIT_ROUNDOFF) * std::max({std::fabs(vd[j]), vscale, SUN_RCONST(1.0)});
      vp[j] = vd[j] + inc;
      rv = ce->f(t, x, w->vpt, w->fpt, ce->user_data);
      ++ce->nfeDQ;
      vp[j] = vd[j];
      if (rv != 0) break;
      N_VLinearSum(1 / inc, w->fpt, -1 / inc, fv, w->fpt);
      const sunrealtype* col = N_VGetArrayPointer(w->fpt);
      std::copy(col, col + n, w->Jdq.begin() + static_cast<size_t>(j * n));
    }
  }
  if (rv != 0) {
    return ProcessError(ce, CE_JACFUNC_FAIL, func,
                        "The velocity Jacobian df/dv could not be evaluated (returned %d) at "
                        "t = %.17g.",
                        rv, static_cast<double>(t));
  }
  return CE_SUCCESS;
}

// Assembles [[M - kappa J, Gt^T], [H, 0]] into A (dense, or CSR/CSC sparse) and factors it.
int SetupSaddle(CEodeMemRec* ce, ConWork* w, sunrealtype kappa, bool with_jac, SUNMatrix H,
                sunrealtype t, const char* func) {
  const sunindextype n = w->n;
  std::vector<Entry>& e = w->entries;
  e.clear();
  if (ce->M != nullptr) {
    ForEachEntry(ce->M, [&](sunindextype r, sunindextype c, sunrealtype v) {
      e.push_back({r, c, v});
    });
  }
  const sunrealtype diag = ce->M != nullptr ? 0 : 1;  // no mass function: M = I
  for (sunindextype i = 0; i < n; ++i) e.push_back({i, i, diag});
  if (with_jac && kappa != 0) {
    if (ce->jac != nullptr) {
      ForEachEntry(w->J, [&](sunindextype r, sunindextype c, sunrealtype v) {
        e.push_back({r, c, -kappa * v});
      });
    } else {
      for (sunindextype j = 0; j < n; ++j) {
        for (sunindextype i = 0; i < n; ++i) {
          const sunrealtype v = w->Jdq[static_cast<size_t>(j * n + i)];
          if (v != 0) e.push_back({i, j, -kappa * v});
        }
      }
    }
  }
  ForEachEntry(w->Gt, [&](sunindextype r, sunindextype c, sunrealtype v) {
    e.push_back({c, n + r, v});
  });
  ForEachEntry(H, [&](sunindextype r, sunindextype c, sunrealtype v) {
    e.push_back({n + r, c, v});
  });

  SUNMatrix A = w->A;
  if (!w->sparse) {
    SUNMatZero(A);
    sunrealtype* data = SUNDenseMatrix_Data(A);  // column-major, leading dimension w->N
    for (const Entry& x : e) data[x.c * w->N + x.r] += x.v;
  } else {
    const bool csr = w->csr;
    std::sort(e.begin(), e.end(), [csr](const Entry& p, const Entry& q) {
      const sunindextype pm = csr ? p.r : p.c, qm = csr ? q.r : q.c;
      const sunindextype pn = csr ? p.c : p.r, qn = csr ? q.c : q.r;
      return pm != qm ? pm < qm : pn < qn;
    });
    // Merge duplicates in place.
    size_t m = 0;
    for (size_t k = 0; k < e.size(); ++k) {
      if (m > 0 && e[m - 1].r == e[k].r && e[m - 1].c == e[k].c) {
        e[m - 1].v += e[k].v;
      } else {
        e[m++] = e[k];
      }
    }
    e.resize(m);
    const sunindextype nnz = static_cast<sunindextype>(m);
    if (SUNSparseMatrix_NNZ(A) < nnz && SUNSparseMatrix_Reallocate(A, nnz) != 0) {
      return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory (saddle-point matrix).");
    }
    sunindextype* ptr = SUNSparseMatrix_IndexPointers(A);
    sunindextype* idx = SUNSparseMatrix_IndexValues(A);
    sunrealtype* val = SUNSparseMatrix_Data(A);
    std::fill(ptr, ptr + w->N + 1, 0);
    for (size_t k = 0; k < m; ++k) {
      const sunindextype major = csr ? e[k].r : e[k].c;
      idx[k] = csr ? e[k].c : e[k].r;
      val[k] = e[k].v;
      ++ptr[major + 1];
    }
    for (sunindextype p = 0; p < w->N; ++p) ptr[p + 1] += ptr[p];
    // KLU keeps its symbolic analysis between setups: it must be redone when the pattern moves.
    const bool same = w->pat_ptr.size() == static_cast<size_t>(w->N + 1) &&
                      std::equal(ptr, ptr + w->N + 1, w->pat_ptr.begin()) &&
                      w->pat_idx.size() == m && std::equal(idx, idx + m, w->pat_idx.begin());
    if (!same) {
      if (w->klu && !w->pat_ptr.empty()) {
        SUNLinSol_KLUReInit(w->LS, A, SUNSparseMatrix_NNZ(A), SUNKLU_REINIT_PARTIAL);
      }
      w->pat_ptr.assign(ptr, ptr + w->N + 1);
      w->pat_idx.assign(idx, idx + m);
    }
  }
  const int rv = SUNLinSolSetup(w->LS, A);
  ++ce->nsetups;
  if (rv != 0) {
    w->factored = false;
    return ProcessError(ce, CE_LSETUP_FAIL, func,
                        "The constraint saddle-point matrix [[M - kappa df/dv, G^T], [G, 0]] is "
                        "singular (linear solver setup returned %d) at t = %.17g. Either the "
                        "constraints are redundant or G lost rank (remove duplicate or dependent "
                        "constraints; check CEodeConstrJacFn), or M is singular on the motions the "
                        "constraints leave free (a massless coordinate no constraint fixes).",
                        rv, static_cast<double>(t));
  }
  return CE_SUCCESS;
}

// sol = A^{-1} [top; bottom] with the factored saddle matrix. top, bottom: local-data vectors.
int SolveSaddle(CEodeMemRec* ce, ConWork* w, sunrealtype top_scale, N_Vector top,
                sunrealtype bot_scale, N_Vector bottom, sunrealtype t, const char* func) {
  sunrealtype* bd = N_VGetArrayPointer(w->b);
  const sunrealtype* td = N_VGetArrayPointer(top);
  const sunrealtype* pd = N_VGetArrayPointer(bottom);
  for (sunindextype i = 0; i < w->n; ++i) bd[i] = top_scale * td[i];
  for (sunindextype i = 0; i < w->nc; ++i) bd[w->n + i] = bot_scale * pd[i];
  N_VConst(0, w->sol);
  const int rv = SUNLinSolSolve(w->LS, w->A, w->sol, w->b, 0);
  ++ce->nls_solves;
  if (rv != 0 || !AllFinite(w->sol)) {
    w->factored = false;
    return ProcessError(
        ce, rv != 0 ? CE_LSOLVE_FAIL : CE_LSETUP_FAIL, func,
        "The constraint saddle-point solve failed (returned %d%s) at t = %.17g: the "
        "matrix is singular or nearly so (redundant constraints?).",
        rv, rv == 0 ? ", non-finite solution" : "", static_cast<double>(t));
  }
  return CE_SUCCESS;
}

// Split sol into the state-sized part (into xs) and the multiplier part (into ls).
void SplitSolution(ConWork* w, N_Vector xs, N_Vector ls) {
  const sunrealtype* sd = N_VGetArrayPointer(w->sol);
  std::copy(sd, sd + w->n, N_VGetArrayPointer(xs));
  std::copy(sd + w->n, sd + w->N, N_VGetArrayPointer(ls));
}

// gamma = d^2/ds^2 Phi(x + s v, t + s) at s = 0: the part of the second time derivative of Phi
// along the motion that does not involve the acceleration (d^2 Phi/dt^2 = G a + gamma).
// Sixth-order central differences: the truncation error is O(s^6), round-off O(eps / s^2).
int ConstraintCurvature(CEodeMemRec* ce, ConWork* w, sunrealtype t, N_Vector x, N_Vector v,
                        N_Vector gam, const char* func) {
  static const sunrealtype kW[4] = {-49.0 / 18.0, 3.0 / 2.0, -3.0 / 20.0, 1.0 / 90.0};
  const sunrealtype vn = N_VMaxNorm(v);
  const sunrealtype ell = std::max(N_VMaxNorm(x), SUN_RCONST(1e-3));
  const sunrealtype eta = std::pow(SUN_UNIT_ROUNDOFF, SUN_RCONST(1.0) / 8);
  sunrealtype s = 100 * ce->h;  // explicit time dependence: resolved on the step's time scale
  if (vn > 0) s = std::min(s, eta * ell / vn);
  N_VConst(0, gam);
  int flag = EvalPhi(ce, t, x, w->s, func);
  if (flag != CE_SUCCESS) return flag;
  N_VLinearSum(kW[0], w->s, 1, gam, gam);
  for (int j = 1; j <= 3 && flag == CE_SUCCESS; ++j) {
    for (int sg = -1; sg <= 1 && flag == CE_SUCCESS; sg += 2) {
      const sunrealtype sj = sg * j * s;
      N_VLinearSum(1, x, sj, v, w->xpt);
      flag = EvalPhi(ce, t + sj, w->xpt, w->s, func);
      if (flag == CE_SUCCESS) N_VLinearSum(kW[j], w->s, 1, gam, gam);
    }
  }
  if (flag == CE_SUCCESS) N_VScale(1 / (s * s), gam, gam);
  return flag;
}

// The index-1 acceleration: [[M, G^T], [G, 0]] [a; lambda] = [f; -gamma] at (t, x, v).
int Index1Accel(CEodeMemRec* ce, ConWork* w, sunrealtype t, N_Vector x, N_Vector v, N_Vector a,
                N_Vector lam, const char* func) {
  w->factored = false;  // A is about to hold a matrix that is not a step matrix
  int flag = MassUpdate(ce, t, x, func);
  if (flag == CE_SUCCESS) flag = EvalG(ce, t, x, w->Gt, func);
  if (flag == CE_SUCCESS) flag = EvalF(ce, t, x, v, w->fval, func);
  if (flag == CE_SUCCESS) flag = ConstraintCurvature(ce, w, t, x, v, w->gam, func);
  if (flag == CE_SUCCESS) flag = SetupSaddle(ce, w, 0, false, w->Gt, t, func);
  if (flag == CE_SUCCESS) flag = SolveSaddle(ce, w, 1, w->fval, -1, w->gam, t, func);
  if (flag != CE_SUCCESS) return flag;
  SplitSolution(w, a, lam);
  return CE_SUCCESS;
}

// What one constrained solve is: the force equation at (t, x_t), the constraint at tc.
struct SolveSpec {
  sunrealtype t;
  N_Vector xt;
  sunrealtype tc;
  sunrealtype mu;
  sunrealtype kappa;  // v(a) = V0 + kappa a when vdep
  bool vdep;
  N_Vector V0;  // the velocity f sees when !vdep
  bool start;   // position from StartPosition instead of StepPosition
  bool reuse;   // a factored step matrix may be reused
};

// Newton on (a, lam) for one step; a and lam hold the predictor on entry, the solution on exit;
// xout (if not NULL) receives x(t+h; a) for the final a.
int ConstrainedNewton(CEodeMemRec* ce, ConWork* w, const SolveSpec& sp, N_Vector a, N_Vector lam,
                      N_Vector xout, const char* func) {
  int flag = MassUpdate(ce, sp.t, sp.xt, func);
  if (flag == CE_SUCCESS) flag = EvalG(ce, sp.t, sp.xt, w->Gt, func);
  if (flag == CE_SUCCESS && !sp.vdep) flag = EvalF(ce, sp.t, sp.xt, sp.V0, w->fval, func);
  if (flag != CE_SUCCESS) return flag;

  // The matrix is refreshed at the first iterate of every step. Reusing it across steps looked
  // attractive, but the convergence test on x(t+h) cannot see an unconverged force balance: its
  // effect on x(t+h) is scaled by mu ~ h^2, while its effect on the velocity (kappa ~ h) is what
  // the energy sees. With G(x(t)) exact in the matrix and f independent of v, the force rows are
  // solved exactly by every iteration, and only the linearisation of Phi is approximate.
  bool have_matrix = sp.reuse && w->factored && w->kappa_fact == sp.kappa && w->nst_fact == ce->nst;
  bool fresh = false;
  sunrealtype dprev = 0;
  sunrealtype dnorm = 0;
  sunrealtype tol = 0;
  if (sp.start) {
    StartPosition(ce, w, sp.xt, a, w->xtrial);
  } else {
    StepPosition(ce, a, w->xtrial);
  }
  for (int it = 0; it < kMaxIters; ++it) {
    flag = EvalPhi(ce, sp.tc, w->xtrial, ce->phi, func);
    if (flag != CE_SUCCESS) return flag;
    if (sp.vdep) {
      N_VLinearSum(1, sp.V0, sp.kappa, a, w->vtmp);
      flag = EvalF(ce, sp.t, sp.xt, w->vtmp, w->fval, func);
      if (flag != CE_SUCCESS) return flag;
    }
    // r1 = f - M a - Gt^T lam, and the size of its terms for the force-balance test.
    sunrealtype fscale = N_VMaxNorm(w->fval);
    if (ce->M != nullptr) {
      if (SUNMatMatvec(ce->M, a, w->r1) != 0) {
        return ProcessError(ce, CE_LSETUP_FAIL, func, "M a failed: check the mass matrix size.");
      }
      fscale += N_VMaxNorm(w->r1);
      N_VLinearSum(1, w->fval, -1, w->r1, w->r1);
    } else {
      fscale += N_VMaxNorm(a);
      N_VLinearSum(1, w->fval, -1, a, w->r1);
    }
    fscale += N_VMaxNorm(w->r1);  // ~ |Gt^T lam|
    AddGTransposeTimes(w->Gt, -1, N_VGetArrayPointer(lam), N_VGetArrayPointer(w->r1));
    const sunrealtype r1norm = N_VMaxNorm(w->r1);

    if (!have_matrix) {
      flag = EvalG(ce, sp.tc, w->xtrial, w->Gh, func);
      if (flag == CE_SUCCESS && sp.vdep)
        flag = EvalVelJac(ce, w, sp.t, sp.xt, w->vtmp, w->fval, func);
      if (flag == CE_SUCCESS) flag = SetupSaddle(ce, w, sp.kappa, sp.vdep, w->Gh, sp.t, func);
      if (flag != CE_SUCCESS) return flag;
      w->factored = true;
      w->kappa_fact = sp.kappa;
      w->nst_fact = ce->nst;
      have_matrix = true;
      fresh = true;
    }
    flag = SolveSaddle(ce, w, sp.mu, w->r1, -1, ce->phi, sp.t, func);
    if (flag != CE_SUCCESS) return flag;
    SplitSolution(w, w->delta, w->s);
    ++ce->nni;
    N_VLinearSum(1, w->xtrial, 1, w->delta, w->xtrial);  // x(t+h; a) is affine in a, slope mu
    N_VLinearSum(1, a, 1 / sp.mu, w->delta, a);
    N_VLinearSum(1, lam, 1 / sp.mu, w->s, lam);

    dnorm = N_VMaxNorm(w->delta);
    const sunrealtype xscale = std::max(N_VMaxNorm(w->xtrial), SUN_RCONST(1e-300));
    tol = kTolUlps * SUN_UNIT_ROUNDOFF * xscale;
    if (!std::isfinite(dnorm)) break;
    // f independent of v and a matrix of this step: the force rows are linear and solved exactly,
    // so only x(t+h) needs testing. Otherwise the force balance must have converged as well.
    const bool force_ok = (!sp.vdep && fresh) || r1norm <= kTolUlps * SUN_UNIT_ROUNDOFF * fscale;
    bool converged = dnorm <= tol && force_ok;
    if (!converged && it > 0 && dprev > 0) {
      const sunrealtype rate = dnorm / dprev;
      if (force_ok && rate < 1 && dnorm * rate / (1 - rate) <= tol) converged = true;
      // Round-off stagnation: the change no longer shrinks but is already at the noise level.
      if (force_ok && rate >= 0.5 && dnorm <= kFloorUlps * SUN_UNIT_ROUNDOFF * xscale) {
        converged = true;
      }
      if (!converged && rate > kSlowRate) {
        if (fresh && rate > 2) break;  // diverging with a matrix of this solve
        have_matrix = false;           // slow: refresh at the next iterate (full Newton)
      }
    }
    if (converged) {
      if (!AllFinite(a) || !AllFinite(lam)) break;
      if (xout != nullptr) N_VScale(1, w->xtrial, xout);
      return CE_SUCCESS;
    }
    dprev = dnorm;
  }
  ++ce->nnf;
  return ProcessError(ce, CE_CONV_FAILURE, func,
                      "The constraint Newton iteration did not converge at t = %.17g (last change "
                      "of x(t+h) %g, target %g, %d iterations): reduce h, and check that "
                      "CEodeConstrJacFn is the exact derivative of the constraint function and "
                      "that the constraints are consistent.",
                      static_cast<double>(sp.t), static_cast<double>(dnorm),
                      static_cast<double>(tol), kMaxIters);
}

bool LocalData(N_Vector v) {
  return N_VGetArrayPointer(v) != nullptr && N_VGetCommunicator(v) == nullptr;
}

}  // namespace

bool HasConstraints(const CEodeMemRec* ce) { return ce->phifn != nullptr; }

int ConstrInitialize(CEodeMemRec* ce, const char* func) {
  if (!HasConstraints(ce)) return CE_SUCCESS;
  FreeWork(ce);
  const sunindextype n = ce->n;
  const sunindextype nc = ce->nc;
  if (!LocalData(ce->xcur) || !LocalData(ce->lambda)) {
    return ProcessError(ce, CE_LINIT_FAIL, func,
                        "Constraints need state and multiplier vectors with local data "
                        "(N_VGetArrayPointer, e.g. serial or OpenMP N_Vectors): the saddle-point "
                        "system is solved by a direct solver on one process.");
  }
  auto* w = new (std::nothrow) ConWork;
  if (w == nullptr) return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
  ce->con = w;
  w->n = n;
  w->nc = nc;
  w->N = n + nc;
  w->degree = ce->degree;

  if (ce->LS == nullptr) {
    if (ce->M != nullptr && SUNMatGetID(ce->M) != SUNMATRIX_DENSE) {
      return ProcessError(ce, CE_LINIT_FAIL, func,
                          "A sparse mass matrix with constraints needs a sparse saddle-point "
                          "solver: attach SUNLinSol_KLU with an (n+nc) x (n+nc) CSR "
                          "SUNSparseMatrix via CEodeSetLinearSolver.");
    }
    w->A = SUNDenseMatrix(w->N, w->N, ce->sunctx);
    w->b = N_VNew_Serial(w->N, ce->sunctx);
    if (w->A == nullptr || w->b == nullptr)
      return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
    w->LS = SUNLinSol_Dense(w->b, w->A, ce->sunctx);
    w->own_ls = true;
    if (w->LS == nullptr) return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
  } else {
    w->LS = ce->LS;
    w->A = ce->A;
    if (w->A == nullptr ||
        (SUNMatGetID(w->A) != SUNMATRIX_DENSE && SUNMatGetID(w->A) != SUNMATRIX_SPARSE)) {
      return ProcessError(ce, CE_LINIT_FAIL, func,
                          "With constraints the linear solver factors the saddle-point matrix "
                          "[[M, G^T], [G, 0]]: attach a dense (SUNLinSol_Dense) or sparse "
                          "(SUNLinSol_KLU) solver with its (n+nc) x (n+nc) matrix.");
    }
    w->sparse = SUNMatGetID(w->A) == SUNMATRIX_SPARSE;
    const sunindextype rows = w->sparse ? SUNSparseMatrix_Rows(w->A) : SUNDenseMatrix_Rows(w->A);
    const sunindextype cols =
        w->sparse ? SUNSparseMatrix_Columns(w->A) : SUNDenseMatrix_Columns(w->A);
    if (rows != w->N || cols != w->N) {
      return ProcessError(ce, CE_LINIT_FAIL, func,
                          "The linear solver's matrix is %ld x %ld, but with constraints it must "
                          "hold the saddle-point matrix of size n + nc = %ld.",
                          static_cast<long>(rows), static_cast<long>(cols),
                          static_cast<long>(w->N));
    }
    if (w->sparse) w->csr = SUNSparseMatrix_SparseType(w->A) == CSR_MAT;
    w->klu = SUNLinSolGetID(w->LS) == SUNLINEARSOLVER_KLU;
    w->b = N_VNew_Serial(w->N, ce->sunctx);
  }
  if (ce->M != nullptr) {
    const bool msparse = SUNMatGetID(ce->M) == SUNMATRIX_SPARSE;
    if (!msparse && SUNMatGetID(ce->M) != SUNMATRIX_DENSE) {
      return ProcessError(ce, CE_LINIT_FAIL, func,
                          "With constraints the mass matrix must be dense or sparse.");
    }
  }
  // Constraint (and velocity) Jacobians come in the kind of A, as the user fills them.
  auto make = [&](sunindextype r, sunindextype c) -> SUNMatrix {
    if (!w->sparse) return SUNDenseMatrix(r, c, ce->sunctx);
    const sunindextype nnz = std::min<sunindextype>(r * c, 4 * (r + c) + 16);
    return SUNSparseMatrix(r, c, nnz, w->csr ? CSR_MAT : CSC_MAT, ce->sunctx);
  };
  w->Gt = make(nc, n);
  w->Gh = make(nc, n);
  if (ce->vel_dependent && ce->jac != nullptr) w->J = make(n, n);
  w->sol = N_VClone(w->b);
  N_Vector* svecs[] = {&w->xtrial, &w->fval, &w->r1,  &w->delta, &w->vtmp, &w->inc,
                       &w->xpt,    &w->vpt,  &w->fpt, &w->a0,    &w->vbase};
  for (N_Vector* v : svecs) *v = N_VClone(ce->xcur);
  N_Vector* lvecs[] = {&w->lam, &w->lam_prev, &w->s, &w->gam};
  for (N_Vector* v : lvecs) *v = N_VClone(ce->lambda);
  bool ok = w->Gt && w->Gh && (w->J || !(ce->vel_dependent && ce->jac)) && w->sol && w->b;
  for (N_Vector* v : svecs) ok = ok && *v != nullptr;
  for (N_Vector* v : lvecs) ok = ok && *v != nullptr;
  if (!ok) return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
  const int rv = SUNLinSolInitialize(w->LS);
  if (rv != 0) {
    return ProcessError(ce, CE_LINIT_FAIL, func, "SUNLinSolInitialize failed (returned %d).", rv);
  }
  return CE_SUCCESS;
}

int ConstrStart(CEodeMemRec* ce, const char* func) {
  ConWork* w = Work(ce);
  if (w == nullptr || w->degree != ce->degree) {
    const int flag = ConstrInitialize(ce, func);
    if (flag != CE_SUCCESS) return flag;
    w = Work(ce);
  }
  const int d = ce->degree;
  const sunrealtype h = ce->h;
  const sunrealtype t0 = ce->tcur;
  N_Vector x0 = ce->xcur;
  N_Vector v0 = ce->D[1];
  w->factored = false;
  w->lam_prev_valid = false;
  int flag = CE_SUCCESS;

  if (ce->zero_start) {
    // The paper's start: history (v0, a0, 0, ...), a0 the acceleration of the constrained
    // Taylor step x(t0 + h) = x0 + h v0 + h^2/2 a0.
    for (int k = 3; k < d; ++k) N_VConst(0, ce->D[k]);
    N_VConst(0, ce->D[2]);
    N_VConst(0, w->lam);
  } else {
    // Consistent start: a0, lambda0 from the index-1 system; higher derivatives by symmetric
    // differences of the index-1 acceleration along the Taylor curve of what is already known
    // (the scheme of StartMethod for ODEs, with the index-1 acceleration as the right-hand side).
    flag = Index1Accel(ce, w, t0, x0, v0, ce->D[2], w->lam, func);
    if (flag != CE_SUCCESS) return flag;
    N_VScale(1, w->lam, w->lam_prev);  // lambda0, kept while the differences reuse w->lam
    if (flag == CE_SUCCESS) {
      flag = StartDerivatives(ce, t0, w->xtrial, w->r1, w->a0,
                              [&](sunrealtype ts, N_Vector xs, N_Vector vs, N_Vector as) {
                                return Index1Accel(ce, w, ts, xs, vs, as, w->lam, func);
                              });
    }
    if (flag != CE_SUCCESS) return flag;
    N_VScale(1, w->lam_prev, w->lam);
  }

  // The first position: a constrained Taylor step. Its acceleration is the unknown; the velocity
  // is v0 (kappa = 0), so the force equation is f(t0, x0, v0).
  N_VScale(1, ce->D[2], w->a0);
  N_VScale(1, w->lam, w->lam_prev);
  SolveSpec sp{t0, x0, t0 + h, h * h / 2, 0, false, v0, true, false};
  flag = ConstrainedNewton(ce, w, sp, w->a0, w->lam, w->xpt, func);
  if (flag != CE_SUCCESS) return flag;
  w->factored = false;  // the start matrix has kappa = 0 and the start's mu: not a step matrix
  N_VScale(1, w->xpt, ce->xnext);
  if (ce->zero_start) {
    N_VScale(1, w->a0, ce->D[2]);
    N_VScale(1, w->lam, ce->lambda);
  } else {
    // The index-1 values are the consistent derivatives at t0; the start's own (a, lambda) only
    // served to put x(t0 + h) on the constraint manifold.
    N_VScale(1, w->lam_prev, ce->lambda);
  }
  if (!AllFinite(ce->D[2]) || !AllFinite(ce->lambda) || !AllFinite(ce->xnext)) {
    return ProcessError(ce, CE_FIRST_RHSFUNC_ERR, func,
                        "The constrained start produced NaN or Inf at t0 = %.17g.",
                        static_cast<double>(t0));
  }
  return CE_SUCCESS;
}

int ConstrSolveStep(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector a, const char* func) {
  ConWork* w = Work(ce);
  if (w == nullptr) {
    return ProcessError(ce, CE_LINIT_FAIL, func, "The constraint solver is not initialised.");
  }
  const int d = ce->degree;
  const StepCoeffs& co = ce->co;
  const sunrealtype tc = ce->t_start_h + static_cast<sunrealtype>(ce->nsteps_h + 2) * ce->h;
  // Predictors: Taylor of the acceleration from t - h, linear extrapolation of lambda.
  sunrealtype c[kMaxDegree];
  N_Vector X[kMaxDegree];
  sunrealtype hp = 1;
  for (int i = 0; i + 2 < d; ++i) {
    c[i] = hp;
    X[i] = ce->D[2 + i];
    hp *= co.h / (i + 1);
  }
  N_VLinearCombination(d - 2, c, X, a);
  if (w->lam_prev_valid) {
    N_VLinearSum(2, ce->lambda, -1, w->lam_prev, w->lam);
  } else {
    N_VScale(1, ce->lambda, w->lam);
  }
  N_Vector V0 = ce->D[1];  // f independent of v: it sees the last velocity, as the ODE path
  if (ce->vel_dependent) {
    for (int j = 1; j < d; ++j) {
      c[j - 1] = co.V0[j];
      X[j - 1] = ce->D[j];
    }
    N_VLinearCombination(d - 1, c, X, w->vbase);
    V0 = w->vbase;
  }
  const SolveSpec sp{t,  x,     tc,  co.mu, ce->vel_dependent ? co.kappa : 0, ce->vel_dependent,
                     V0, false, true};
  const int flag = ConstrainedNewton(ce, w, sp, a, w->lam, nullptr, func);
  if (flag != CE_SUCCESS) return flag;
  N_VScale(1, ce->lambda, w->lam_prev);
  N_VScale(1, w->lam, ce->lambda);
  w->lam_prev_valid = true;
  return CE_SUCCESS;
}

void ConstrFree(CEodeMemRec* ce) {
  FreeWork(ce);
  if (ce->lambda != nullptr) N_VDestroy(ce->lambda);
  if (ce->phi != nullptr) N_VDestroy(ce->phi);
  ce->lambda = ce->phi = nullptr;
  ce->phifn = nullptr;
  ce->Gfn = nullptr;
  ce->nc = 0;
}

}  // namespace ceode

extern "C" {

int CEodeSetConstraints(void* mem, N_Vector phi_template, CEodeConstrFn phi, CEodeConstrJacFn G) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (phi == nullptr && G == nullptr) {  // remove the constraints
    ceode::ConstrFree(ce);
    ce->started = false;
    return CE_SUCCESS;
  }
  if (phi == nullptr || G == nullptr || phi_template == nullptr) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "Pass the constraint function, its Jacobian G = dPhi/dx and a "
                               "template vector of length nc (or phi = G = NULL to remove the "
                               "constraints).");
  }
  const sunindextype nc = N_VGetLength(phi_template);
  if (nc <= 0) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "The constraint template vector is empty: its length is nc.");
  }
  ceode::ConstrFree(ce);
  ce->lambda = N_VClone(phi_template);
  ce->phi = N_VClone(phi_template);
  if (ce->lambda == nullptr || ce->phi == nullptr) {
    ceode::ConstrFree(ce);
    return ceode::ProcessError(ce, CE_MEM_FAIL, __func__, "Out of memory.");
  }
  N_VConst(0, ce->lambda);
  ce->phifn = phi;
  ce->Gfn = G;
  ce->nc = nc;
  ce->phi_template_checked = false;  // checked against Phi at the next start
  ce->started = false;
  return CE_SUCCESS;
}

int CEodeGetMultipliers(void* mem, N_Vector lambda) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce, true);
  if (flag != CE_SUCCESS) return flag;
  if (!ceode::HasConstraints(ce)) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "No constraints are set (CEodeSetConstraints): there are no "
                               "multipliers.");
  }
  if (lambda == nullptr || N_VGetLength(lambda) != ce->nc) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "lambda must be a vector of length nc = %ld (clone the constraint "
                               "template).",
                               static_cast<long>(ce->nc));
  }
  if (!ce->started) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "No multipliers yet: call CEodeEvolve first.");
  }
  // lambda(t) belongs to the acceleration at the last step time (CEodeGetCurrentTime).
  N_VScale(1, ce->lambda, lambda);
  return CE_SUCCESS;
}

}  // extern "C"
