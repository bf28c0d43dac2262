// -----------------------------------------------------------------------------
// chain_model.h: the planar chain of N point-mass pendulums as an index-3 DAE,
// shared by the chain's bench programs (wp_chain_dae.cpp, chain_scaling.cpp).
//
// N point masses m_i = 1 kg at p_i = (x_i, y_i), i = 1..N, joined by massless
// rigid links of length l = L/N (L = 1 m) to each other and the first to the
// fixed origin p_0 = 0, gravity g = 9.81 m/s^2 along -y:
//     x'' + G(x)^T lambda = f = (0, -g, 0, -g, ...),   M = I (no mass function),
//     Phi_i(x) = |p_i - p_{i-1}|^2 - l^2 = 0,  i = 1..N   (n = 2N, nc = N).
// Start: the chain straight at 60 deg from the downward vertical, at rest.
// There is no reference solution; the chain is conservative, so
//     error = max |E - E0|,  E = sum(1/2 |v_i|^2 + g y_i),
//     drift = max_i |Phi_i|  (in m^2),
// taken after every step, where the solver has x and x' at the same instant.
// -----------------------------------------------------------------------------
#ifndef CEODE_BENCH_CHAIN_MODEL_H_
#define CEODE_BENCH_CHAIN_MODEL_H_

#include <cmath>

#include "wp_common.h"

namespace chain {

constexpr double kGrav = 9.81, kLtot = 1.0;
constexpr double kAngle0 = 1.04719755119659774615;  // 60 deg from the downward vertical

struct Chain {
  long N = 0;    // number of masses = number of constraints
  double l = 0;  // link length
  double e0 = 0;
};

// Entries of the CSR saddle-point matrix [[I, G^T], [G, 0]].
inline long SaddleNnz(long N) { return 2 * N + 2 * (4 * N - 2); }

// The applied force (gravity); M = I.
inline int Gravity(double, const double*, const double*, double* F, void* data) {
  const Chain* c = static_cast<const Chain*>(data);
  for (long i = 0; i < c->N; ++i) {
    F[2 * i] = 0.0;
    F[2 * i + 1] = -kGrav;
  }
  return 0;
}

inline int Phi(sunrealtype, N_Vector x, N_Vector phi, void* data) {
  const Chain* c = static_cast<const Chain*>(data);
  const double* X = N_VGetArrayPointer(x);
  double* P = N_VGetArrayPointer(phi);
  double xp = 0.0, yp = 0.0;
  for (long i = 0; i < c->N; ++i) {
    const double dx = X[2 * i] - xp, dy = X[2 * i + 1] - yp;
    P[i] = dx * dx + dy * dy - c->l * c->l;
    xp = X[2 * i];
    yp = X[2 * i + 1];
  }
  return 0;
}

// G: nc x n, CSR (the KLU path) or dense. Row i: d Phi_i / d(p_{i-1}, p_i).
inline int GDense(const Chain* c, const double* X, SUNMatrix G) {
  if (SUNMatZero(G) != 0) return -1;
  double xp = 0.0, yp = 0.0;
  for (long i = 0; i < c->N; ++i) {
    const double dx = X[2 * i] - xp, dy = X[2 * i + 1] - yp;
    if (i > 0) {
      SM_ELEMENT_D(G, i, 2 * i - 2) = -2.0 * dx;
      SM_ELEMENT_D(G, i, 2 * i - 1) = -2.0 * dy;
    }
    SM_ELEMENT_D(G, i, 2 * i) = 2.0 * dx;
    SM_ELEMENT_D(G, i, 2 * i + 1) = 2.0 * dy;
    xp = X[2 * i];
    yp = X[2 * i + 1];
  }
  return 0;
}

inline int G(sunrealtype, N_Vector x, SUNMatrix G, void* data) {
  const Chain* c = static_cast<const Chain*>(data);
  const double* X = N_VGetArrayPointer(x);
  if (SUNMatGetID(G) == SUNMATRIX_DENSE) return GDense(c, X, G);
  const sunindextype nnz = 4 * c->N - 2;
  if (SUNMatGetID(G) != SUNMATRIX_SPARSE || SUNSparseMatrix_SparseType(G) != CSR_MAT) return -1;
  if (SUNSparseMatrix_NNZ(G) < nnz && SUNSparseMatrix_Reallocate(G, nnz) != 0) return -1;
  sunindextype* ptr = SUNSparseMatrix_IndexPointers(G);
  sunindextype* idx = SUNSparseMatrix_IndexValues(G);
  double* d = SUNSparseMatrix_Data(G);
  sunindextype k = 0;
  double xp = 0.0, yp = 0.0;
  for (long i = 0; i < c->N; ++i) {
    const double dx = X[2 * i] - xp, dy = X[2 * i + 1] - yp;
    ptr[i] = k;
    if (i > 0) {
      idx[k] = 2 * i - 2, d[k++] = -2.0 * dx;
      idx[k] = 2 * i - 1, d[k++] = -2.0 * dy;
    }
    idx[k] = 2 * i, d[k++] = 2.0 * dx;
    idx[k] = 2 * i + 1, d[k++] = 2.0 * dy;
    xp = X[2 * i];
    yp = X[2 * i + 1];
  }
  ptr[c->N] = k;
  return 0;
}

inline double Energy(long N, const double* X, const double* V) {
  double e = 0.0;
  for (long i = 0; i < N; ++i) {
    e += 0.5 * (V[2 * i] * V[2 * i] + V[2 * i + 1] * V[2 * i + 1]) + kGrav * X[2 * i + 1];
  }
  return e;
}

// max_i |Phi_i|
inline double Drift(const Chain* c, const double* X) {
  double xp = 0.0, yp = 0.0, dm = 0.0;
  for (long i = 0; i < c->N; ++i) {
    const double dx = X[2 * i] - xp, dy = X[2 * i + 1] - yp;
    const double ph = std::fabs(dx * dx + dy * dy - c->l * c->l);
    if (ph > dm || ph != ph) dm = ph;
    xp = X[2 * i];
    yp = X[2 * i + 1];
  }
  return dm;
}

inline void InitialState(const Chain& c, double* X, double* V) {
  for (long i = 0; i < c.N; ++i) {
    X[2 * i] = static_cast<double>(i + 1) * c.l * std::sin(kAngle0);
    X[2 * i + 1] = -static_cast<double>(i + 1) * c.l * std::cos(kAngle0);
    V[2 * i] = V[2 * i + 1] = 0.0;
  }
}

inline Chain Make(long N) {
  Chain c;
  c.N = N;
  c.l = kLtot / static_cast<double>(N);
  std::vector<double> x(2 * N), v(2 * N);
  InitialState(c, x.data(), v.data());
  c.e0 = Energy(N, x.data(), v.data());
  return c;
}

// The error and drift on (x, x'), user data a Chain.
inline double ErrXV(double, const double* x, const double* v, void* u) {
  const Chain* c = static_cast<const Chain*>(u);
  return std::fabs(Energy(c->N, x, v) - c->e0);
}
inline double DriftXV(double, const double* x, const double*, void* u) {
  return Drift(static_cast<const Chain*>(u), x);
}

// The description of the chain (KLU saddle matrix unless dense).
inline wp::Problem Problem(Chain* c, double tend, bool dense) {
  wp::Problem p;
  p.n = static_cast<int>(2 * c->N), p.user = c, p.tend = tend;
  p.Lift<Gravity>();
  p.x0.resize(p.n), p.v0.resize(p.n);
  InitialState(*c, p.x0.data(), p.v0.data());
  p.err = ErrXV, p.drift = DriftXV;
  p.nc = static_cast<int>(c->N), p.phi = Phi, p.G = G;
  p.saddle_nnz = dense ? 0 : SaddleNnz(c->N);
  return p;
}

}  // namespace chain

#endif  // CEODE_BENCH_CHAIN_MODEL_H_
