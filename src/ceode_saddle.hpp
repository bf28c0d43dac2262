// The saddle-point linear system of the constrained step (ceode_saddle.cpp), private:
//   [ M - kappa J   Gt^T ] [ delta ]   [ top    ]
//   [ H             0    ] [   s   ] = [ bottom ]
// assembled into a dense or sparse (CSR/CSC) matrix and factored by a SUNLinearSolver, or, for
// small systems, solved by the Schur complement of a block kept across steps (SchurFactor).
#ifndef CEODE_SRC_CEODE_SADDLE_HPP_
#define CEODE_SRC_CEODE_SADDLE_HPP_

#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <vector>

#include "ceode_impl.hpp"

namespace ceode {

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
      fn(csr ? p : idx[k], csr ? idx[k] : p, val[k]);
    }
  }
}

struct SaddleEntry {
  sunindextype r, c;
  sunrealtype v;
};

// The Schur-complement form of the same solve (docs/theory.md section 8.3), dense, for
// n + nc <= kSchurMaxSize: B = A + rho G0^T G0 (A = M - kappa J, G0 the Gt of B's refresh) is
// factored once and kept while A stays the same (rho = 0 when A is nonsingular); every setup
// factors only K, nc x nc (rho = 0) or 2nc x 2nc.
struct SchurFactor {
  bool valid = false;   // B, P, C hold the factorisation of a refresh
  bool active = false;  // the last SaddleSetup took this path (its solves follow it)
  sunrealtype rho = 0;
  std::vector<sunrealtype> B, Binv, P, C;   // n x n LU, its inverse, B^{-1} G0^T, rho G0 P - I
  std::vector<SaddleEntry> g0nz, gnz, hnz;  // nonzeros of G0, of the setup's Gt and H
  std::vector<sunrealtype> Q, K, r;         // B^{-1} Gt^T, the LU of K, its right-hand side
  std::vector<sunindextype> pivB, pivK;
  std::vector<sunrealtype*> colsB, colsK;
};

// The saddle-point solver: its matrix, its linear solver (the user's, or a dense one CEODE
// owns) and the serial right-hand side and solution of length N = n + nc.
struct Saddle {
  sunindextype n = 0, nc = 0, N = 0;
  bool sparse = false;  // A is a SUNSparseMatrix
  bool csr = true;
  bool own_ls = false;
  SUNLinearSolver LS = nullptr;
  SUNMatrix A = nullptr;
  N_Vector b = nullptr;
  N_Vector sol = nullptr;
  std::vector<SaddleEntry> entries;
  std::vector<sunindextype> pat_ptr, pat_idx;  // pattern of the last sparse factorization
  bool schur_fits = false;                     // small enough for SchurFactor
  SchurFactor sc;
};

// Largest n + nc solved by the Schur complement (dense work ~ (n + nc)^2 per setup).
constexpr sunindextype kSchurMaxSize = 200;

// A direct solver for A by its matrix type (dense, band, sparse/KLU); NULL for other types.
SUNLinearSolver DirectSolverFor(SUNMatrix A, N_Vector tmpl, SUNContext ctx);
// Validates or creates the solver for the configuration in ce (LS, A, M); sizes from ce.
int SaddleInit(CEodeMemRec* ce, Saddle* s, const char* func);
void SaddleFree(Saddle* s);
// Factors [[M - kappa J, Gt^T], [H, 0]] (J = NULL: no damping term): by the Schur complement
// when it fits and ce->con.schur (reuse_a: the block A is the one of the last call; *refreshed: B was
// formed anew), else assembled into the solver's matrix.
int SaddleSetup(CEodeMemRec* ce, Saddle* s, sunrealtype kappa, SUNMatrix J, SUNMatrix Gt,
                SUNMatrix H, sunrealtype t, const char* func, bool reuse_a, bool* refreshed);
// s->sol = A^{-1} [top_scale top; bot_scale bottom]; local-data vectors of length n and nc.
int SaddleSolve(CEodeMemRec* ce, Saddle* s, sunrealtype top_scale, N_Vector top,
                sunrealtype bot_scale, N_Vector bottom, sunrealtype t, const char* func);
// The state part of the solution into xs, the multiplier part into ls.
void SaddleSplit(const Saddle& s, N_Vector xs, N_Vector ls);

}  // namespace ceode

#endif  // CEODE_SRC_CEODE_SADDLE_HPP_
