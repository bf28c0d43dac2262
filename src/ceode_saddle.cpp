// The saddle-point linear system of the constrained step (docs/theory.md section 8):
// assembly of [[M - kappa J, Gt^T], [H, 0]] into the matrix of a SUNLinearSolver, its
// factorisation and its solves. The integrator sees only SaddleSetup and SaddleSolve.
#include "ceode_saddle.hpp"

#include <nvector/nvector_serial.h>
#include <sundials/sundials_dense.h>
#include <sunlinsol/sunlinsol_band.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunlinsol/sunlinsol_klu.h>

#include <algorithm>
#include <cmath>

namespace ceode {

namespace {

sunindextype Rows(SUNMatrix A) {
  return SUNMatGetID(A) == SUNMATRIX_SPARSE ? SUNSparseMatrix_Rows(A) : SUNDenseMatrix_Rows(A);
}
sunindextype Cols(SUNMatrix A) {
  return SUNMatGetID(A) == SUNMATRIX_SPARSE ? SUNSparseMatrix_Columns(A)
                                            : SUNDenseMatrix_Columns(A);
}

// No linear solver attached: a dense one of size n + nc, owned by CEODE.
int CreateDenseSolver(CEodeMemRec* ce, Saddle* s, const char* func) {
  if (ce->ls.M != nullptr && SUNMatGetID(ce->ls.M) != SUNMATRIX_DENSE) {
    return ProcessError(ce, CE_LINIT_FAIL, func,
                        "A sparse mass matrix with constraints needs a sparse saddle-point "
                        "solver: attach SUNLinSol_KLU with an (n+nc) x (n+nc) CSR "
                        "SUNSparseMatrix via CEodeSetLinearSolver.");
  }
  s->own_ls = true;
  s->A = SUNDenseMatrix(s->N, s->N, ce->sunctx);
  s->b = N_VNew_Serial(s->N, ce->sunctx);
  if (s->A == nullptr || s->b == nullptr) {
    return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
  }
  s->LS = SUNLinSol_Dense(s->b, s->A, ce->sunctx);
  if (s->LS == nullptr) return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
  return CE_SUCCESS;
}

// The user's solver and matrix factor the saddle-point matrix: dense or sparse, size n + nc.
int AdoptUserSolver(CEodeMemRec* ce, Saddle* s, const char* func) {
  s->LS = ce->ls.LS;
  s->A = ce->ls.A;
  if (s->A == nullptr ||
      (SUNMatGetID(s->A) != SUNMATRIX_DENSE && SUNMatGetID(s->A) != SUNMATRIX_SPARSE)) {
    return ProcessError(ce, CE_LINIT_FAIL, func,
                        "With constraints the linear solver factors the saddle-point matrix "
                        "[[M, G^T], [G, 0]]: attach a dense (SUNLinSol_Dense) or sparse "
                        "(SUNLinSol_KLU) solver with its (n+nc) x (n+nc) matrix.");
  }
  if (Rows(s->A) != s->N || Cols(s->A) != s->N) {
    return ProcessError(ce, CE_LINIT_FAIL, func,
                        "The linear solver's matrix is %ld x %ld, but with constraints it must "
                        "hold the saddle-point matrix of size n + nc = %ld.",
                        static_cast<long>(Rows(s->A)), static_cast<long>(Cols(s->A)),
                        static_cast<long>(s->N));
  }
  s->sparse = SUNMatGetID(s->A) == SUNMATRIX_SPARSE;
  if (s->sparse) s->csr = SUNSparseMatrix_SparseType(s->A) == CSR_MAT;
  s->b = N_VNew_Serial(s->N, ce->sunctx);
  return s->b != nullptr ? CE_SUCCESS : ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
}

// Every entry of the saddle-point matrix, in assembly order (duplicates are summed later).
void CollectEntries(const CEodeMemRec* ce, Saddle* s, sunrealtype kappa, SUNMatrix J, SUNMatrix Gt,
                    SUNMatrix H) {
  const sunindextype n = s->n;
  std::vector<SaddleEntry>& e = s->entries;
  e.clear();
  if (ce->ls.M != nullptr) {
    ForEachEntry(ce->ls.M, [&](sunindextype r, sunindextype c, sunrealtype v) {
      e.push_back({r, c, v});
    });
  }
  const sunrealtype diag = ce->ls.M != nullptr ? 0 : 1;  // no mass function: M = I
  for (sunindextype i = 0; i < n; ++i) e.push_back({i, i, diag});
  if (J != nullptr && kappa != 0) {
    ForEachEntry(J, [&](sunindextype r, sunindextype c, sunrealtype v) {
      e.push_back({r, c, -kappa * v});
    });
  }
  ForEachEntry(Gt, [&](sunindextype r, sunindextype c, sunrealtype v) {
    e.push_back({c, n + r, v});
  });
  ForEachEntry(H, [&](sunindextype r, sunindextype c, sunrealtype v) {
    e.push_back({n + r, c, v});
  });
}

void AssembleDense(Saddle* s) {
  SUNMatZero(s->A);
  sunrealtype* data = SUNDenseMatrix_Data(s->A);  // column-major, leading dimension N
  for (const SaddleEntry& x : s->entries) data[x.c * s->N + x.r] += x.v;
}

// Sorts the entries in the matrix's storage order and sums duplicates in place.
void SortAndMerge(Saddle* s) {
  std::vector<SaddleEntry>& e = s->entries;
  const bool csr = s->csr;
  std::sort(e.begin(), e.end(), [csr](const SaddleEntry& p, const SaddleEntry& q) {
    const sunindextype pm = csr ? p.r : p.c, qm = csr ? q.r : q.c;
    const sunindextype pn = csr ? p.c : p.r, qn = csr ? q.c : q.r;
    return pm != qm ? pm < qm : pn < qn;
  });
  size_t m = 0;
  for (size_t k = 0; k < e.size(); ++k) {
    if (m > 0 && e[m - 1].r == e[k].r && e[m - 1].c == e[k].c) {
      e[m - 1].v += e[k].v;
    } else {
      e[m++] = e[k];
    }
  }
  e.resize(m);
}

// KLU keeps its symbolic analysis between setups: it must be redone when the pattern moves.
void PatternChanged(Saddle* s) {
  if (SUNLinSolGetID(s->LS) == SUNLINEARSOLVER_KLU && !s->pat_ptr.empty()) {
    SUNLinSol_KLUReInit(s->LS, s->A, SUNSparseMatrix_NNZ(s->A), SUNKLU_REINIT_PARTIAL);
  }
}

int AssembleSparse(CEodeMemRec* ce, Saddle* s, const char* func) {
  SortAndMerge(s);
  const std::vector<SaddleEntry>& e = s->entries;
  const size_t m = e.size();
  SUNMatrix A = s->A;
  if (SUNSparseMatrix_NNZ(A) < static_cast<sunindextype>(m) &&
      SUNSparseMatrix_Reallocate(A, static_cast<sunindextype>(m)) != 0) {
    return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory (saddle-point matrix).");
  }
  sunindextype* ptr = SUNSparseMatrix_IndexPointers(A);
  sunindextype* idx = SUNSparseMatrix_IndexValues(A);
  sunrealtype* val = SUNSparseMatrix_Data(A);
  std::fill(ptr, ptr + s->N + 1, 0);
  for (size_t k = 0; k < m; ++k) {
    idx[k] = s->csr ? e[k].c : e[k].r;
    val[k] = e[k].v;
    ++ptr[(s->csr ? e[k].r : e[k].c) + 1];
  }
  for (sunindextype p = 0; p < s->N; ++p) ptr[p + 1] += ptr[p];
  const bool same = s->pat_ptr.size() == static_cast<size_t>(s->N + 1) &&
                    std::equal(ptr, ptr + s->N + 1, s->pat_ptr.begin()) && s->pat_idx.size() == m &&
                    std::equal(idx, idx + m, s->pat_idx.begin());
  if (!same) {
    PatternChanged(s);
    s->pat_ptr.assign(ptr, ptr + s->N + 1);
    s->pat_idx.assign(idx, idx + m);
  }
  return CE_SUCCESS;
}

// X (rows x cols, any kind) into column-major dense storage.
void ToDense(SUNMatrix X, sunindextype rows, sunindextype cols, std::vector<sunrealtype>* out) {
  out->assign(static_cast<size_t>(rows * cols), 0);
  ForEachEntry(X,
               [&](sunindextype r, sunindextype c, sunrealtype v) { (*out)[c * rows + r] += v; });
}

// The nonzeros of a constraint Jacobian (nc x n): G's rows touch few coordinates, and every
// product of the Schur path runs over them alone.
void Nonzeros(SUNMatrix G, std::vector<SaddleEntry>* nz) {
  nz->clear();
  ForEachEntry(G, [&](sunindextype r, sunindextype c, sunrealtype v) {
    if (v != 0) nz->push_back({r, c, v});
  });
}

sunrealtype MaxAbs(const std::vector<sunrealtype>& v) {
  sunrealtype m = 0;
  for (sunrealtype x : v) m = std::max(m, std::fabs(x));
  return m;
}

// LU in place of the k x k column-major a; false if a pivot is below tiny.
bool DenseLU(std::vector<sunrealtype>* a, sunindextype k, sunrealtype tiny,
             std::vector<sunrealtype*>* cols, std::vector<sunindextype>* piv) {
  cols->resize(static_cast<size_t>(k));
  piv->resize(static_cast<size_t>(k));
  for (sunindextype j = 0; j < k; ++j) (*cols)[j] = a->data() + j * k;
  if (SUNDlsMat_denseGETRF(cols->data(), k, k, piv->data()) != 0) return false;
  for (sunindextype j = 0; j < k; ++j) {
    if (!(std::fabs((*a)[j * k + j]) > tiny)) return false;
  }
  return true;
}

// B's LU (with no pivot below tiny) and its explicit inverse: B is applied at every setup and
// solve, and for the small n of this path a product costs less than two triangular solves.
bool FactorB(SchurFactor* f, sunindextype n, sunrealtype tiny) {
  if (!DenseLU(&f->B, n, tiny, &f->colsB, &f->pivB)) return false;
  f->Binv.assign(static_cast<size_t>(n * n), 0);
  for (sunindextype j = 0; j < n; ++j) {
    f->Binv[j * n + j] = 1;
    SUNDlsMat_denseGETRS(f->colsB.data(), n, f->pivB.data(), f->Binv.data() + j * n);
  }
  return true;
}

// out (n x nc, column-major) = B^{-1} G^T: column r sums B^{-1}'s columns over row r of G.
void SolveTransposed(SchurFactor* f, sunindextype n, sunindextype nc,
                     const std::vector<SaddleEntry>& gnz, std::vector<sunrealtype>* out) {
  out->assign(static_cast<size_t>(n * nc), 0);
  for (const SaddleEntry& e : gnz) {
    const sunrealtype* col = f->Binv.data() + e.c * n;
    sunrealtype* o = out->data() + e.r * n;
    for (sunindextype i = 0; i < n; ++i) o[i] += e.v * col[i];
  }
}

// K(r, c) += scale (X Y)(r, c), c < nc, for X given by its nonzeros and the n x nc column-major
// Y; K has leading dimension ld.
void AddRowTimes(const std::vector<SaddleEntry>& xnz, const std::vector<sunrealtype>& Y,
                 sunindextype n, sunindextype nc, sunrealtype scale, sunrealtype* K,
                 sunindextype ld) {
  for (const SaddleEntry& e : xnz) {
    const sunrealtype v = scale * e.v;
    for (sunindextype c = 0; c < nc; ++c) K[c * ld + e.r] += v * Y[c * n + e.c];
  }
}

// B = A = M - kappa J when its LU has no pivot below 1e-8 max|A| (rho = 0); else (a singular M)
// B = A + rho G0^T G0, G0 = Gt, rho = max|A| / max|G0|^2 so that both terms have one size: B is
// nonsingular when G0 covers A's null space. With rho > 0 also P = B^{-1} G0^T, C = rho G0 P - I.
bool SchurRefresh(const CEodeMemRec* ce, Saddle* s, sunrealtype kappa, SUNMatrix J, SUNMatrix Gt) {
  SchurFactor* f = &s->sc;
  const sunindextype n = s->n, nc = s->nc;
  f->valid = false;
  std::vector<sunrealtype>& A = f->Binv;  // A until FactorB
  if (ce->ls.M != nullptr) {
    ToDense(ce->ls.M, n, n, &A);
  } else {
    A.assign(static_cast<size_t>(n * n), 0);
    for (sunindextype i = 0; i < n; ++i) A[i * n + i] = 1;
  }
  if (J != nullptr && kappa != 0) {
    ForEachEntry(J,
                 [&](sunindextype r, sunindextype c, sunrealtype v) { A[c * n + r] -= kappa * v; });
  }
  const sunrealtype amax = MaxAbs(A), tiny = 1e-8 * amax;
  f->B = A;
  f->rho = 0;
  if (FactorB(f, n, tiny)) return f->valid = true;
  f->B = A;
  Nonzeros(Gt, &f->g0nz);
  sunrealtype gmax = 0;
  for (const SaddleEntry& e : f->g0nz) gmax = std::max(gmax, std::fabs(e.v));
  if (gmax == 0) return false;
  f->rho = (amax > 0 ? amax : 1) / (gmax * gmax);
  for (const SaddleEntry& p : f->g0nz) {
    for (const SaddleEntry& q : f->g0nz) {
      if (p.r == q.r) f->B[q.c * n + p.c] += f->rho * p.v * q.v;
    }
  }
  if (!FactorB(f, n, 0)) return false;
  SolveTransposed(f, n, nc, f->g0nz, &f->P);
  f->C.assign(static_cast<size_t>(nc * nc), 0);
  AddRowTimes(f->g0nz, f->P, n, nc, f->rho, f->C.data(), nc);
  for (sunindextype r = 0; r < nc; ++r) f->C[r * nc + r] -= 1;
  return f->valid = true;
}

// rho = 0: K = -H Q, Q = B^{-1} Gt^T, the plain Schur complement: K s = bottom - H t0,
// t0 = B^{-1} top, delta = t0 - Q s. rho > 0, with y = rho G0 delta the saddle system becomes
// B delta - G0^T y + Gt^T s = top, rho G0 delta - y = 0, H delta = bottom; eliminating
// delta = B^{-1}(top + G0^T y - Gt^T s) leaves K [y; s] = [-rho G0 t0; bottom - H t0] with
//   K = [[C, -rho G0 Q], [H P, -H Q]].
bool SchurFactorK(Saddle* s, SUNMatrix Gt, SUNMatrix H) {
  SchurFactor* f = &s->sc;
  const sunindextype n = s->n, nc = s->nc, na = f->rho > 0 ? nc : 0, k = na + nc;
  Nonzeros(Gt, &f->gnz);
  SolveTransposed(f, n, nc, f->gnz, &f->Q);
  Nonzeros(H, &f->hnz);
  f->K.assign(static_cast<size_t>(k * k), 0);
  sunrealtype* K = f->K.data();
  AddRowTimes(f->hnz, f->Q, n, nc, -1, K + na * k + na, k);
  if (na > 0) {
    AddRowTimes(f->g0nz, f->Q, n, nc, -f->rho, K + na * k, k);
    AddRowTimes(f->hnz, f->P, n, nc, 1, K + na, k);
    for (sunindextype c = 0; c < nc; ++c) std::copy_n(&f->C[c * nc], nc, K + c * k);
  }
  return DenseLU(&f->K, k, 0, &f->colsK, &f->pivK);
}

// s->sol = [delta; s] of the system SchurFactorK factored, for [top_scale top; bot_scale bottom].
void SchurSolve(Saddle* s, sunrealtype top_scale, const sunrealtype* td, sunrealtype bot_scale,
                const sunrealtype* pd) {
  SchurFactor* f = &s->sc;
  const sunindextype n = s->n, nc = s->nc, na = f->rho > 0 ? nc : 0;
  sunrealtype* sd = N_VGetArrayPointer(s->sol);
  std::fill(sd, sd + n, 0);
  for (sunindextype j = 0; j < n; ++j) {  // delta = t0 = B^{-1} top first
    const sunrealtype x = top_scale * td[j];
    const sunrealtype* col = f->Binv.data() + j * n;
    for (sunindextype i = 0; i < n; ++i) sd[i] += x * col[i];
  }
  f->r.assign(static_cast<size_t>(na + nc), 0);
  sunrealtype* ry = f->r.data();
  sunrealtype* rs = ry + na;
  for (sunindextype r = 0; r < nc; ++r) rs[r] = bot_scale * pd[r];
  for (const SaddleEntry& e : f->hnz) rs[e.r] -= e.v * sd[e.c];
  if (na > 0) {
    for (const SaddleEntry& e : f->g0nz) ry[e.r] -= f->rho * e.v * sd[e.c];
  }
  SUNDlsMat_denseGETRS(f->colsK.data(), na + nc, f->pivK.data(), ry);
  for (sunindextype r = 0; r < nc; ++r) {
    const sunrealtype* q = &f->Q[r * n];
    for (sunindextype i = 0; i < n; ++i) sd[i] -= q[i] * rs[r];
  }
  for (sunindextype r = 0; r < na; ++r) {
    const sunrealtype* p = &f->P[r * n];
    for (sunindextype i = 0; i < n; ++i) sd[i] += p[i] * ry[r];
  }
  std::copy_n(rs, nc, sd + n);
}

}  // namespace

// With PatternChanged the library's only solver-specific calls (KLU is named here alone).
SUNLinearSolver DirectSolverFor(SUNMatrix A, N_Vector tmpl, SUNContext ctx) {
  switch (SUNMatGetID(A)) {
    case SUNMATRIX_DENSE:
      return SUNLinSol_Dense(tmpl, A, ctx);
    case SUNMATRIX_BAND:
      return SUNLinSol_Band(tmpl, A, ctx);
    case SUNMATRIX_SPARSE:
      return SUNLinSol_KLU(tmpl, A, ctx);
    default:
      return nullptr;
  }
}

int SaddleInit(CEodeMemRec* ce, Saddle* s, const char* func) {
  s->n = ce->n;
  s->nc = ce->con.nc;
  s->N = ce->n + ce->con.nc;
  s->schur_fits = s->N <= kSchurMaxSize;
  s->sc = SchurFactor();
  int flag = ce->ls.LS == nullptr ? CreateDenseSolver(ce, s, func) : AdoptUserSolver(ce, s, func);
  if (flag != CE_SUCCESS) return flag;
  if (ce->ls.M != nullptr && SUNMatGetID(ce->ls.M) != SUNMATRIX_SPARSE &&
      SUNMatGetID(ce->ls.M) != SUNMATRIX_DENSE) {
    return ProcessError(ce, CE_LINIT_FAIL, func,
                        "With constraints the mass matrix must be dense or sparse.");
  }
  s->sol = CloneVector(s->b);
  if (s->sol == nullptr) return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
  return InitLinearSolver(ce, s->LS, func);
}

void SaddleFree(Saddle* s) {
  if (s->b != nullptr) N_VDestroy(s->b);
  if (s->sol != nullptr) N_VDestroy(s->sol);
  s->b = s->sol = nullptr;
  if (s->own_ls) {
    if (s->LS != nullptr) SUNLinSolFree(s->LS);
    if (s->A != nullptr) SUNMatDestroy(s->A);
  }
  s->LS = nullptr;
  s->A = nullptr;
}

int SaddleSetup(CEodeMemRec* ce, Saddle* s, sunrealtype kappa, SUNMatrix J, SUNMatrix Gt,
                SUNMatrix H, sunrealtype t, const char* func, bool reuse_a, bool* refreshed) {
  *refreshed = false;
  s->sc.active = false;
  if (s->schur_fits && ce->con.schur) {
    if (!reuse_a || !s->sc.valid) *refreshed = SchurRefresh(ce, s, kappa, J, Gt);
    // A singular K means a singular saddle matrix: the full path below reports it.
    if (s->sc.valid && SchurFactorK(s, Gt, H)) {
      s->sc.active = true;
      ++ce->con.nsetups;
      return CE_SUCCESS;
    }
  }
  CollectEntries(ce, s, kappa, J, Gt, H);
  if (!s->sparse) {
    AssembleDense(s);
  } else {
    const int flag = AssembleSparse(ce, s, func);
    if (flag != CE_SUCCESS) return flag;
  }
  const int rv = SUNLinSolSetup(s->LS, s->A);
  ++ce->con.nsetups;
  if (rv != 0) {
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

int SaddleSolve(CEodeMemRec* ce, Saddle* s, sunrealtype top_scale, N_Vector top,
                sunrealtype bot_scale, N_Vector bottom, sunrealtype t, const char* func) {
  sunrealtype* bd = N_VGetArrayPointer(s->b);
  const sunrealtype* td = N_VGetArrayPointer(top);
  const sunrealtype* pd = N_VGetArrayPointer(bottom);
  int rv = 0;
  if (s->sc.active) {
    SchurSolve(s, top_scale, td, bot_scale, pd);
  } else {
    for (sunindextype i = 0; i < s->n; ++i) bd[i] = top_scale * td[i];
    for (sunindextype i = 0; i < s->nc; ++i) bd[s->n + i] = bot_scale * pd[i];
    N_VConst(0, s->sol);
    rv = SUNLinSolSolve(s->LS, s->A, s->sol, s->b, 0);
  }
  ++ce->con.nsolves;
  if (rv != 0 || !IsFinite(s->sol)) {
    return ProcessError(
        ce, rv != 0 ? CE_LSOLVE_FAIL : CE_LSETUP_FAIL, func,
        "The constraint saddle-point solve failed (returned %d%s) at t = %.17g: the "
        "matrix is singular or nearly so (redundant constraints?).",
        rv, rv == 0 ? ", non-finite solution" : "", static_cast<double>(t));
  }
  return CE_SUCCESS;
}

void SaddleSplit(const Saddle& s, N_Vector xs, N_Vector ls) {
  const sunrealtype* sd = N_VGetArrayPointer(s.sol);
  std::copy(sd, sd + s.n, N_VGetArrayPointer(xs));
  std::copy(sd + s.n, sd + s.N, N_VGetArrayPointer(ls));
}

}  // namespace ceode
