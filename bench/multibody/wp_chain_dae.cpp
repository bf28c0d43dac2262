// -----------------------------------------------------------------------------
// wp_chain_dae: the planar chain of N = 8 pendulums (chain_model.h, n = 16, nc = 8), t in
// [0, 2] s: it falls, swings through the bottom and whips; its fastest transverse mode stiffens
// with the link tension. The N-body version of wp_pendulum_dae.
// Solvers: CEODE G3_CD, G4_A34, G5_ONES (index 3, consistent start) at h = 6e-3 ... 2e-5 (1e-5
// with --full; G5_ONES stops with CE_CONV_FAILURE at 1e-2), the CSR saddle matrix factored by
// KLU, G5_ONES also dense; ARKODE RK3 on the index-1 form (the saddle system solved at every
// stage by KLU or dense), with and without a projection after every step; ERKStep adaptive,
// rtol = atol = 1e-4 ... 1e-12; IDA on the GGL form (48 unknowns), 1e-4 ... 1e-10 (at 1e-11 it
// fails in its first steps); CEODE error control (config "<set> adaptive KLU", h_or_tol the
// tolerance) with G4_A34 and G5_O4, rtol = atol = 1e-5 ... 1e-13, IDA's first step (CEODE's own,
// from x and v alone, is a tenth of the interval from rest: too long for the constrained start).
// Prints every curve's best per side and CEODE adaptive against every other curve at equal error
// (f evaluations and time).
// Checks (exit code): every run succeeds; every CEODE and RK3+proj run has drift <= 1e-10 l^2;
// every fixed-step RK3 run takes 3 f per step. --quick: h = 6e-3 ... 1e-3, tolerances to 1e-6
// (CEODE adaptive 1e-5 ... 1e-7).
// -----------------------------------------------------------------------------
#include "chain_model.h"

namespace {

using chain::Chain;
using chain::kGrav;
constexpr long kN = 8;
constexpr double kTend = 2.0;

// The saddle-point system [[I, G^T], [G, 0]] of the index-1 form and its
// solver (CSR + KLU or dense), owned by one ARKODE run, its user data.
struct Index1 {
  Chain c;
  bool sparse = true;
  SUNMatrix A = nullptr;
  SUNLinearSolver LS = nullptr;
  N_Vector rhs = nullptr, sol = nullptr;  // length n + nc
  Index1(SUNContext ctx, bool sparse_) : c(chain::Make(kN)), sparse(sparse_) {
    const long m = 3 * kN;
    rhs = N_VNew_Serial(m, ctx);
    sol = N_VNew_Serial(m, ctx);
    A = sparse ? SUNSparseMatrix(m, m, chain::SaddleNnz(kN), CSR_MAT, ctx)
               : SUNDenseMatrix(m, m, ctx);
    if (rhs == nullptr || sol == nullptr || A == nullptr) return;
    LS = sparse ? SUNLinSol_KLU(rhs, A, ctx) : SUNLinSol_Dense(rhs, A, ctx);
    if (LS != nullptr && SUNLinSolInitialize(LS) != 0) {
      SUNLinSolFree(LS);
      LS = nullptr;
    }
  }
  ~Index1() {
    if (LS != nullptr) SUNLinSolFree(LS);
    if (A != nullptr) SUNMatDestroy(A);
    if (rhs != nullptr) N_VDestroy(rhs);
    if (sol != nullptr) N_VDestroy(sol);
  }
  Index1(const Index1&) = delete;
  Index1& operator=(const Index1&) = delete;
};

// CSR rows, columns in increasing order: row 2j+k (coordinate k of p_j): its
// diagonal, then constraints j and j+1; row n+i: p_{i-1} (if i > 0), then p_i.
void FillSparse(Index1* s, const double* X) {
  const long N = s->c.N, n = 2 * N;
  sunindextype* ptr = SUNSparseMatrix_IndexPointers(s->A);
  sunindextype* idx = SUNSparseMatrix_IndexValues(s->A);
  double* d = SUNSparseMatrix_Data(s->A);
  double gx[kN + 1][2];  // gradient of Phi_i with respect to p_i
  double xp = 0.0, yp = 0.0;
  for (long i = 0; i < N; ++i) {
    gx[i][0] = 2.0 * (X[2 * i] - xp);
    gx[i][1] = 2.0 * (X[2 * i + 1] - yp);
    xp = X[2 * i];
    yp = X[2 * i + 1];
  }
  sunindextype k = 0;
  for (long j = 0; j < N; ++j) {
    for (long c = 0; c < 2; ++c) {
      ptr[2 * j + c] = k;
      idx[k] = 2 * j + c, d[k++] = 1.0;
      idx[k] = n + j, d[k++] = gx[j][c];
      if (j + 1 < N) idx[k] = n + j + 1, d[k++] = -gx[j + 1][c];
    }
  }
  for (long i = 0; i < N; ++i) {
    ptr[n + i] = k;
    if (i > 0) {
      idx[k] = 2 * i - 2, d[k++] = -gx[i][0];
      idx[k] = 2 * i - 1, d[k++] = -gx[i][1];
    }
    idx[k] = 2 * i, d[k++] = gx[i][0];
    idx[k] = 2 * i + 1, d[k++] = gx[i][1];
  }
  ptr[n + N] = k;
}

void FillDense(Index1* s, const double* X) {
  const long N = s->c.N, n = 2 * N;
  SUNMatZero(s->A);
  for (long i = 0; i < n; ++i) SM_ELEMENT_D(s->A, i, i) = 1.0;
  double xp = 0.0, yp = 0.0;
  for (long i = 0; i < N; ++i) {
    const double dx = X[2 * i] - xp, dy = X[2 * i + 1] - yp;
    if (i > 0) {
      SM_ELEMENT_D(s->A, n + i, 2 * i - 2) = SM_ELEMENT_D(s->A, 2 * i - 2, n + i) = -2.0 * dx;
      SM_ELEMENT_D(s->A, n + i, 2 * i - 1) = SM_ELEMENT_D(s->A, 2 * i - 1, n + i) = -2.0 * dy;
    }
    SM_ELEMENT_D(s->A, n + i, 2 * i) = SM_ELEMENT_D(s->A, 2 * i, n + i) = 2.0 * dx;
    SM_ELEMENT_D(s->A, n + i, 2 * i + 1) = SM_ELEMENT_D(s->A, 2 * i + 1, n + i) = 2.0 * dy;
    xp = X[2 * i];
    yp = X[2 * i + 1];
  }
}

// Fills [[I, G(X)^T], [G(X), 0]] and factors it; 0 on success.
int SaddleSetup(Index1* s, const double* X) {
  if (s->sparse) {
    FillSparse(s, X);
  } else {
    FillDense(s, X);
  }
  return SUNLinSolSetup(s->LS, s->A) == 0 ? 0 : 1;
}

// Index-1 accelerations (and multipliers): right-hand side (f, -(dG/dt) v).
int Index1Accel(Index1* s, const double* X, const double* V, double* acc, double* lam) {
  const long N = s->c.N, n = 2 * N;
  double* B = N_VGetArrayPointer(s->rhs);
  const double* Z = N_VGetArrayPointer(s->sol);
  if (SaddleSetup(s, X) != 0) return 1;
  double up = 0.0, wp = 0.0;
  for (long i = 0; i < N; ++i) {
    const double du = V[2 * i] - up, dw = V[2 * i + 1] - wp;
    B[2 * i] = 0.0;
    B[2 * i + 1] = -kGrav;
    B[n + i] = -2.0 * (du * du + dw * dw);
    up = V[2 * i];
    wp = V[2 * i + 1];
  }
  if (SUNLinSolSolve(s->LS, s->A, s->sol, s->rhs, 0.0) != 0) return 1;
  for (long i = 0; i < n; ++i) acc[i] = Z[i];
  if (lam != nullptr) {
    for (long i = 0; i < N; ++i) lam[i] = Z[n + i];
  }
  return 0;
}

// Minimum-norm Newton projection of the positions onto Phi = 0 (ARKODE's
// step postprocessing function): the saddle system with right-hand side
// (0, Phi) gives dx = G^T (G G^T)^-1 Phi; x -= dx, repeated to round-off.
int ProjectPositions(sunrealtype, N_Vector y, void* data) {
  Index1* s = static_cast<Index1*>(data);
  double* X = N_VGetArrayPointer(y);
  const long N = s->c.N, n = 2 * N;
  double* B = N_VGetArrayPointer(s->rhs);
  const double* Z = N_VGetArrayPointer(s->sol);
  for (int it = 0; it < 10; ++it) {
    double xp = 0.0, yp = 0.0, dn = 0.0, pn = 0.0;
    for (long i = 0; i < N; ++i) {
      const double dx = X[2 * i] - xp, dy = X[2 * i + 1] - yp;
      B[2 * i] = B[2 * i + 1] = 0.0;
      B[n + i] = dx * dx + dy * dy - s->c.l * s->c.l;
      pn = std::max(pn, std::fabs(B[n + i]));
      xp = X[2 * i];
      yp = X[2 * i + 1];
    }
    if (pn <= 1e-16 * s->c.l * s->c.l) return 0;  // at round-off already
    if (SaddleSetup(s, X) != 0) return 1;
    if (SUNLinSolSolve(s->LS, s->A, s->sol, s->rhs, 0.0) != 0) return 1;
    for (long i = 0; i < n; ++i) {
      X[i] -= Z[i];
      dn = std::max(dn, std::fabs(Z[i]));
    }
    if (dn <= 1e-15 * chain::kLtot) return 0;
  }
  return 0;  // stagnated at round-off: as good as it gets
}

// The index-1 acceleration a(x, v), lifted by the harness to ARKODE's first-order form.
int Index1Acc(double, const double* x, const double* v, double* a, void* data) {
  return Index1Accel(static_cast<Index1*>(data), x, v, a, nullptr) != 0 ? 1 : 0;
}

double ArkErr(double t, const double* x, const double* v, void* u) {
  return chain::ErrXV(t, x, v, &static_cast<Index1*>(u)->c);
}
double ArkDrift(double, const double* x, const double*, void* u) {
  return chain::Drift(&static_cast<Index1*>(u)->c, x);
}

// GGL residual, y = (q[n], v[n], lambda[nc], mu[nc]), rows in the same order.
int IdaRes(sunrealtype, N_Vector yy, N_Vector yp, N_Vector rr, void* data) {
  const Chain* c = static_cast<const Chain*>(data);
  const double* Y = N_VGetArrayPointer(yy);
  const double* P = N_VGetArrayPointer(yp);
  double* R = N_VGetArrayPointer(rr);
  const long N = c->N, n = 2 * N;
  const double *Q = Y, *V = Y + n, *L = Y + 2 * n, *U = Y + 2 * n + N;
  for (long i = 0; i < n; ++i) {
    R[i] = P[i] - V[i];                                /* q' - v (- G^T mu below) */
    R[n + i] = P[n + i] - ((i & 1) != 0 ? -kGrav : 0); /* v' - f (+ G^T lambda below) */
  }
  double xp = 0.0, yq = 0.0, up = 0.0, wp = 0.0;
  for (long i = 0; i < N; ++i) {
    const double dx = Q[2 * i] - xp, dy = Q[2 * i + 1] - yq;
    const double du = V[2 * i] - up, dw = V[2 * i + 1] - wp;
    R[2 * i] -= 2.0 * dx * U[i];
    R[2 * i + 1] -= 2.0 * dy * U[i];
    R[n + 2 * i] += 2.0 * dx * L[i];
    R[n + 2 * i + 1] += 2.0 * dy * L[i];
    if (i > 0) {
      R[2 * i - 2] += 2.0 * dx * U[i];
      R[2 * i - 1] += 2.0 * dy * U[i];
      R[n + 2 * i - 2] -= 2.0 * dx * L[i];
      R[n + 2 * i - 1] -= 2.0 * dy * L[i];
    }
    R[2 * n + i] = dx * dx + dy * dy - c->l * c->l; /* Phi(q) */
    R[2 * n + N + i] = 2.0 * (dx * du + dy * dw);   /* G(q) v */
    xp = Q[2 * i];
    yq = Q[2 * i + 1];
    up = V[2 * i];
    wp = V[2 * i + 1];
  }
  return 0;
}

// Analytic iteration matrix dF/dy + cj dF/dy' of the GGL residual. With H_i
// the Hessian of Phi_i (2 on the diagonal blocks of p_{i-1} and p_i, -2 on
// the blocks between them): dRq/dq = cj I - sum mu_i H_i, dRq/dv = -I,
// dRq/dmu = -G^T; dRv/dq = sum lambda_i H_i, dRv/dv = cj I, dRv/dlambda = G^T;
// dPhi/dq = G; d(G v)/dq = G on the velocity differences, d(G v)/dv = G.
void JacLink(SUNMatrix J, long n, long N, long i, const double* g, const double* gv, double mu,
             double lam) {
  const long rl = 2 * n + i, rg = 2 * n + N + i;
  for (long k = 0; k < 2; ++k) {
    const long a = 2 * i + k;  // coordinate k of p_i
    SM_ELEMENT_D(J, a, a) -= 2.0 * mu;
    SM_ELEMENT_D(J, n + a, a) += 2.0 * lam;
    SM_ELEMENT_D(J, a, rg) = -g[k];
    SM_ELEMENT_D(J, n + a, rl) = g[k];
    SM_ELEMENT_D(J, rl, a) = g[k];
    SM_ELEMENT_D(J, rg, a) = gv[k];
    SM_ELEMENT_D(J, rg, n + a) = g[k];
    if (i == 0) continue;
    const long p = 2 * (i - 1) + k;  // coordinate k of p_{i-1}
    SM_ELEMENT_D(J, p, p) -= 2.0 * mu;
    SM_ELEMENT_D(J, a, p) += 2.0 * mu;
    SM_ELEMENT_D(J, p, a) += 2.0 * mu;
    SM_ELEMENT_D(J, n + p, p) += 2.0 * lam;
    SM_ELEMENT_D(J, n + a, p) -= 2.0 * lam;
    SM_ELEMENT_D(J, n + p, a) -= 2.0 * lam;
    SM_ELEMENT_D(J, p, rg) = g[k];
    SM_ELEMENT_D(J, n + p, rl) = -g[k];
    SM_ELEMENT_D(J, rl, p) = -g[k];
    SM_ELEMENT_D(J, rg, p) = -gv[k];
    SM_ELEMENT_D(J, rg, n + p) = -g[k];
  }
}

int IdaJac(sunrealtype, sunrealtype cj, N_Vector yy, N_Vector, N_Vector, SUNMatrix J, void* data,
           N_Vector, N_Vector, N_Vector) {
  const Chain* c = static_cast<const Chain*>(data);
  const double* Y = N_VGetArrayPointer(yy);
  const long N = c->N, n = 2 * N;
  const double *Q = Y, *V = Y + n, *L = Y + 2 * n, *U = Y + 2 * n + N;
  if (SUNMatZero(J) != 0) return -1;
  for (long i = 0; i < n; ++i) {
    SM_ELEMENT_D(J, i, i) = cj;
    SM_ELEMENT_D(J, i, n + i) = -1.0;
    SM_ELEMENT_D(J, n + i, n + i) = cj;
  }
  double xp = 0.0, yq = 0.0, up = 0.0, wp = 0.0;
  for (long i = 0; i < N; ++i) {
    const double g[2] = {2.0 * (Q[2 * i] - xp), 2.0 * (Q[2 * i + 1] - yq)};
    const double gv[2] = {2.0 * (V[2 * i] - up), 2.0 * (V[2 * i + 1] - wp)};
    JacLink(J, n, N, i, g, gv, U[i], L[i]);
    xp = Q[2 * i];
    yq = Q[2 * i + 1];
    up = V[2 * i];
    wp = V[2 * i + 1];
  }
  return 0;
}

}  // namespace

namespace {

struct Config {
  enum Kind { kCeode, kCeodeAdaptive, kRk3, kRk3Proj, kErk, kIda } kind;
  const char* name;    // CSV config column
  const char* method;  // CEODE method name
  bool dense;          // dense saddle matrix instead of CSR + KLU
};

struct Scene {
  SUNContext ctx = nullptr;
  wp::Table* table = nullptr;
  ARKodeButcherTable rk3 = nullptr;
  wp::Problem ida;
  int bad = 0;
};

// One ARKODE run on the index-1 form, with its own saddle matrix and solver.
int ArkOnce(Scene* sc, const Config& c, double h, wp::Outcome* o) {
  Index1 s(sc->ctx, !c.dense);
  if (s.LS == nullptr) return 1;
  wp::Problem p = chain::Problem(&s.c, kTend, false);
  p.user = &s;
  p.f1 = wp::FirstOrderRhs<Index1Acc>;
  p.err = ArkErr, p.drift = ArkDrift;
  p.post_step = c.kind == Config::kRk3Proj ? ProjectPositions : nullptr;
  const wp::Sun kind = c.kind == Config::kErk ? wp::Sun::kErk : wp::Sun::kErkFixed;
  return wp::SundialsRun(sc->ctx, p, {kind, 0, sc->rk3}, h, o);
}

// ARKODE before 6.7.0 evaluates f once at the start of a non-FSAL table too; 6.7.0 and later
// do not (the FSAL fix), so the count per run differs by one between SUNDIALS 6.4 and 7.x.
#if SUNDIALS_VERSION_MAJOR > 6 || (SUNDIALS_VERSION_MAJOR == 6 && SUNDIALS_VERSION_MINOR >= 7)
constexpr long int kArkInitialEvals = 0;
#else
constexpr long int kArkInitialEvals = 1;
#endif

void RunPoint(Scene* sc, const Config& c, double h) {
  static Chain ce_chain = chain::Make(kN);
  const double l2 = ce_chain.l * ce_chain.l;
  wp::Outcome o;
  bool ok = false;
  if (c.kind == Config::kCeode) {
    const wp::Problem p = chain::Problem(&ce_chain, kTend, c.dense);
    ok = wp::MeasureCeode(sc->table, sc->ctx, p, c.method, h, false, c.name, &o);
    if (ok) wp::PrintMatrixReuse(c.name, h, o);
  } else if (c.kind == Config::kCeodeAdaptive) {
    // h is the tolerance. IDA's first step: CEODE's own, from x and v alone, is a tenth of the
    // interval from rest, too long for the constrained start.
    wp::Problem p = chain::Problem(&ce_chain, kTend, c.dense);
    p.init_step = sc->ida.init_step;
    const wp::TolCurve curve{c.name, wp::CeodeOpts(c.method), {h}};
    std::vector<wp::Outcome> got;
    if (wp::MeasureTolCurve(sc->table, sc->ctx, p, curve, &got) != 0) {
      ++sc->bad;
      return;
    }
    if (got.empty()) return;  // a flagged result: no row to check
    ok = true;
    o = got.back();
  } else if (c.kind == Config::kIda) {
    ok = wp::MeasureIda(sc->table, sc->ctx, sc->ida, h, c.name, &o);
  } else {
    ok = wp::Measure(
        sc->table, "ARKODE", c.name, h, [&](wp::Outcome* r) { return ArkOnce(sc, c, h, r); }, &o);
  }
  if (!ok) {
    ++sc->bad;
    return;
  }
  if ((c.kind == Config::kCeode || c.kind == Config::kCeodeAdaptive ||
       c.kind == Config::kRk3Proj) &&
      !(o.drift <= 1e-10 * l2)) {
    ++sc->bad;
    std::printf("  <-- %s %g: drift above 1e-10 l^2\n", c.name, h);
  }
  if ((c.kind == Config::kRk3 || c.kind == Config::kRk3Proj) &&
      o.rhs_evals != 3 * o.steps + kArkInitialEvals) {
    ++sc->bad;
    std::printf("  <-- %s %g: not 3 f evaluations per step\n", c.name, h);
  }
}

// The chain with its GGL residual form. IDA's consistent start: q' = v = 0, v' and lambda from
// the index-1 saddle system, mu = 0; lambda and mu algebraic.
int IdaProblem(SUNContext ctx, Chain* c, wp::Problem* p) {
  const long n = 2 * kN, neq = 6 * kN;
  *p = chain::Problem(c, kTend, false);
  p->ny = static_cast<int>(neq), p->res = IdaRes, p->res_jac = IdaJac, p->init_step = 1e-5;
  p->y0.assign(neq, 0.0), p->yp0.assign(neq, 0.0), p->id.assign(neq, 0.0);
  for (long i = 0; i < 2 * n; ++i) p->id[i] = 1.0;
  chain::InitialState(*c, p->y0.data(), p->y0.data() + n);
  Index1 s(ctx, true);
  return s.LS == nullptr ||
         Index1Accel(&s, p->y0.data(), p->y0.data() + n, p->yp0.data() + n, p->y0.data() + 2 * n);
}

}  // namespace

int main(int argc, char** argv) {
  const wp::Args args = wp::ParseArgs(argc, argv);
  Scene sc;
  if (SUNContext_Create(SUN_COMM_NULL, &sc.ctx) != 0) return 1;
  Chain ida_chain = chain::Make(kN);
  if (IdaProblem(sc.ctx, &ida_chain, &sc.ida) != 0) return 1;
  sc.rk3 = wp::KuttaRk3();
  const Config configs[] = {
      {Config::kCeode, "G5_ONES KLU", "G5_ONES", false},
      {Config::kCeode, "G5_ONES dense", "G5_ONES", true},
      {Config::kCeode, "G4_A34 KLU", "G4_A34", false},
      {Config::kCeode, "G3_CD KLU", "G3_CD", false},
      {Config::kCeodeAdaptive, "G4_A34 adaptive KLU", "G4_A34", false},
      {Config::kCeodeAdaptive, "G5_O4 adaptive KLU", "G5_O4", false},
      {Config::kRk3, "RK3 index-1 KLU", nullptr, false},
      {Config::kRk3, "RK3 index-1 dense", nullptr, true},
      {Config::kRk3Proj, "RK3+proj index-1 KLU", nullptr, false},
      {Config::kErk, "ERK adaptive index-1 KLU", nullptr, false},
      {Config::kIda, "BDF-GGL", nullptr, false},
  };
  const double hs[] = {6e-3, 4e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5};
  const double tols[] = {1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13};
  // CEODE's energy error is 100 to 500 times its tolerance here (ERKStep's about 80 times).
  const double ce_tols[] = {1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13, 1e-14};
  std::printf(
      "Chain of N = %ld pendulums (n = %ld, nc = %ld), t in [0, %g] s, from rest at 60 deg\n", kN,
      2 * kN, kN, kTend);
  std::printf("error = max |E - E0|, drift = max |Phi_i| (l^2 = %.4g)\n\n",
              (chain::kLtot / kN) * (chain::kLtot / kN));
  wp::Table table("chain_dae_wp", args.csv);
  sc.table = &table;
  for (const Config& c : configs) {
    const bool adaptive =
        c.kind == Config::kErk || c.kind == Config::kIda || c.kind == Config::kCeodeAdaptive;
    int np = c.kind == Config::kIda ? 7 : args.full ? 10 : 9;
    if (args.quick) np = adaptive ? 3 : 4;
    const double* grid = c.kind == Config::kCeodeAdaptive ? ce_tols : adaptive ? tols : hs;
    for (int j = 0; j < np; ++j) RunPoint(&sc, c, grid[j]);
  }
  wp::PrintEqualError(table, {1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11});
  wp::PrintAdaptiveEqualError(table, {1e-4, 1e-6, 1e-8, 1e-10});
  ARKodeButcherTable_Free(sc.rk3);
  SUNContext_Free(&sc.ctx);
  std::printf("work-precision: %d runs failed or checks off\n", sc.bad);
  return sc.bad == 0 ? 0 : 1;
}
