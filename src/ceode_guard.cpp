// The runtime stability guard (docs/theory.md, linear stability): an upper
// estimate of the top frequency omega_max of M x'' = f(t, x, x'), compared with
// the method's stability limit Omega_max. The guard has its own scratch vectors,
// its own copy and factorisation of M and its own counters, so the integration
// (its state, its solver's factorisation, nfe/nsetups/nje) is the same with the
// guard on or off.
#include <ceode/ceode_stability.h>
#include <sunmatrix/sunmatrix_band.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "ceode_saddle.hpp"

namespace ceode {

namespace {

// Lanczos on the symmetric pencil (K, M), K = -df/dx, in the M inner product.
constexpr int kMaxLanczos = 150;
constexpr int kMinLanczos = 5;
// The Ritz values are looked at after every step up to kEveryStepChecks steps (a check costs
// O(k^3) on the k x k tridiagonal, next to f's O(n)), then every kCheckEvery steps.
constexpr int kEveryStepChecks = 20;
constexpr int kCheckEvery = 5;
// Stop once the top Ritz pair's residual is below this fraction of its value: the estimate
// theta + residual is then at most 0.2 % above theta <= omega_max^2, and its square root, the
// frequency, at most 0.1 % above sqrt(theta). The step caps carry their own margin (0.99 and
// 0.9 of the limit); 0.1 % of the step costs 0.1 % more steps.
constexpr sunrealtype kLanczosTol = 2e-3;
// Is the pencil symmetric? In exact arithmetic <q_{j-1}, K q_j> = beta_{j-1} for a symmetric one.
// Two things move the computed coefficient c off beta_{j-1} when it is symmetric: the rounding of
// the difference quotients (eps |f| / sig per entry, bounded per step with kDqNoise), and the
// local loss of orthogonality it causes, which grows like amax / beta_{j-1} as beta falls (near
// breakdown the next vector is mostly that rounding). Measured over the test suite and the
// examples, |c - beta| / (amax + beta) <= 5e-8 on the symmetric problems but for those two cases
// (the spinning top just after beta = 6e-9 amax; pendulums at rest, K at rounding level), and
// >= 0.5 at j = 1 on the non-symmetric ones (the MRI fast part, triangular and scaled-chain K).
// kSymmetryTol sits between (docs/theory.md, the runtime guard).
constexpr sunrealtype kSymmetryTol = 1e-4;
constexpr sunrealtype kDqNoise = 10;  // safety factor on the Cauchy-Schwarz bound of the rounding
// Arnoldi (non-symmetric K): the residual and the change of theta that end it (the residual
// bounds nothing there), and the basis vectors per cycle before an explicit restart.
constexpr sunrealtype kArnoldiTol = 1e-3;
constexpr int kArnoldiDim = 20;
// Recommended steps and CEodeGetStableStep's default: this fraction of the limit,
// so that a step at the recommendation stays stable even at a Jordan-block edge.
constexpr sunrealtype kRecommendSafety = 0.99;
// The warm start (WarmStart): the Lanczos vectors are kept while their entries fit in this many
// (32 MiB at double precision, allocated as the iteration reaches them), the pseudo-random start
// enters with the M-norm of the last top Ritz vector beside it, and every kColdEvery-th estimate
// starts cold.
constexpr sunindextype kWarmEntries = sunindextype{1} << 22;
constexpr int kColdEvery = 8;

struct GuardWork {
  N_Vector q_prev = nullptr;  // Lanczos vectors q_{j-1}, q_j, and the next one
  N_Vector q = nullptr;
  N_Vector w = nullptr;
  N_Vector mw = nullptr;  // M w, also the mass solve's solution
  N_Vector xp = nullptr;  // perturbed position
  N_Vector f0 = nullptr;  // f at the guard's point
  SUNMatrix M = nullptr;  // the guard's own M(t, x) and its factorisation
  // M itself for the M products when the solver factors in place (dense, band): without it the
  // products would use the LU factors
  SUNMatrix M_prod = nullptr;
  SUNLinearSolver LS = nullptr;
  SUNMatrix M_source = nullptr;  // the user's matrix M was cloned from
  CEodeMassFn mfn_source = nullptr;
  N_Vector wts = nullptr;   // CEodeSetGuardMass: f returns M^{-1} force with this diagonal M
  bool mass_ready = false;  // M evaluated and factored (constant M: once per run)
  std::vector<sunrealtype> alpha, beta;
  sunrealtype f0_norm = 0;  // ||f(x)||_2: the scale of the difference quotients' rounding
  sunrealtype sig = 0;      // the last difference quotient's step
  // Arnoldi, for a non-symmetric K: its M-orthonormal basis (cloned when first needed), where
  // Lanczos also keeps its vectors for the warm vector while they fit in kWarmEntries entries,
  // and Hessenberg matrix; which estimator the last estimate came from (for the warning)
  std::vector<N_Vector> basis;
  Eigen::MatrixXd H;
  bool arnoldi = false;
  // The last estimate's top Ritz vector (M-normalised), the next estimate's start (WarmStart).
  N_Vector warm = nullptr;
  bool warm_ok = false;
  int warm_runs = 0;  // estimates started from it since the last cold start
};

GuardWork* Work(CEodeMemRec* ce) { return static_cast<GuardWork*>(ce->guard.work); }

int AllocWork(CEodeMemRec* ce, const char* func) {
  if (ce->guard.work != nullptr) return CE_SUCCESS;
  auto* g = new GuardWork;
  ce->guard.work = g;
  for (N_Vector* v : {&g->q_prev, &g->q, &g->w, &g->mw, &g->xp, &g->f0}) {
    *v = CloneVector(ce->xcur);
    if (*v == nullptr) return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory (guard).");
  }
  g->alpha.reserve(kMaxLanczos);
  g->beta.reserve(kMaxLanczos);
  return CE_SUCCESS;
}

// A solver for the guard's copy of M, of the kind the matrix type allows.
SUNLinearSolver MassSolver(CEodeMemRec* ce, GuardWork* g) {
  return DirectSolverFor(g->M, g->q, ce->sunctx);
}

void FreeMass(GuardWork* g) {
  if (g->LS != nullptr) SUNLinSolFree(g->LS);
  if (g->M != nullptr) SUNMatDestroy(g->M);
  if (g->M_prod != nullptr) SUNMatDestroy(g->M_prod);
  g->LS = nullptr;
  g->M = nullptr;
  g->M_prod = nullptr;
  g->M_source = nullptr;
  g->mass_ready = false;
}

// M(t, x) into the guard's own matrix and factored there; the solver's M and A
// are not touched. Returns CE_SUCCESS with *usable = false for matrix types the
// guard has no solver for.
int GuardMass(CEodeMemRec* ce, GuardWork* g, const char* func, bool* usable) {
  *usable = true;
  if (g->M_source != ce->ls.M || g->mfn_source != ce->ls.mfn) FreeMass(g);
  if (ce->ls.M == nullptr) return CE_SUCCESS;
  if (g->mass_ready && ce->ls.mass_constant) return CE_SUCCESS;
  if (g->M == nullptr) {
    g->M_source = ce->ls.M;
    g->mfn_source = ce->ls.mfn;
    g->M = SUNMatClone(ce->ls.M);
    const SUNMatrix_ID id = SUNMatGetID(ce->ls.M);
    if (id == SUNMATRIX_DENSE || id == SUNMATRIX_BAND) g->M_prod = SUNMatClone(ce->ls.M);
    if (g->M == nullptr ||
        ((id == SUNMATRIX_DENSE || id == SUNMATRIX_BAND) && g->M_prod == nullptr))
      return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory (guard).");
    g->LS = MassSolver(ce, g);
    if (g->LS == nullptr || SUNLinSolInitialize(g->LS) != 0) {
      *usable = false;
      return CE_SUCCESS;
    }
  }
  if (g->LS == nullptr) {
    *usable = false;
    return CE_SUCCESS;
  }
  SUNMatZero(g->M);
  int rv = ce->ls.mfn(ce->tcur, ce->xcur, g->M, ce->user_data, g->w, g->mw, g->xp);
  ++ce->guard.nme;
  if (rv != 0) {
    return ProcessError(ce, CE_MASSFUNC_FAIL, func,
                        "The mass matrix function failed (returned %d) in the stability guard at "
                        "t = %.17g.",
                        rv, static_cast<double>(ce->tcur));
  }
  if (g->M_prod != nullptr && SUNMatCopy(g->M, g->M_prod) != 0) {
    return ProcessError(ce, CE_MEM_FAIL, func, "The stability guard could not copy M.");
  }
  rv = SUNLinSolSetup(g->LS, g->M);
  ++ce->guard.nsetups;
  if (rv != 0) {
    return ProcessError(ce, CE_LSETUP_FAIL, func,
                        "The stability guard could not factor M (returned %d): M is singular.", rv);
  }
  g->mass_ready = true;
  return CE_SUCCESS;
}

// A pseudo-random start: a uniform chain's top mode is orthogonal to the ones
// vector. Vectors spread over several processes start from ones (the same on
// every rank count).
void StartVector(N_Vector q) {
  N_VConst(1, q);
  sunrealtype* d = N_VGetArrayPointer(q);
  const N_Vector_ID id = N_VGetVectorID(q);
  if (d == nullptr ||
      (id != SUNDIALS_NVEC_SERIAL && id != SUNDIALS_NVEC_OPENMP && id != SUNDIALS_NVEC_PTHREADS)) {
    return;
  }
  std::uint64_t seed = 12345;
  for (sunindextype i = 0; i < N_VGetLength(q); ++i) {
    seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
    d[i] = 0.5 + static_cast<sunrealtype>(seed >> 33) / 4294967296.0;
  }
}

// out = M in: the mass matrix, else CEodeSetGuardMass's diagonal, else M = I.
void MassTimes(const GuardWork* g, N_Vector in, N_Vector out) {
  const SUNMatrix M = g->M_prod != nullptr ? g->M_prod : g->M;
  if (M != nullptr && SUNMatMatvec(M, in, out) == 0) return;
  if (g->M == nullptr && g->wts != nullptr) {
    N_VProd(g->wts, in, out);
    return;
  }
  N_VScale(1, in, out);
}

// u = K q = -(f(x + sig q) - f(x)) / sig, into g->w.
int StiffnessTimes(CEodeMemRec* ce, GuardWork* g, const char* func) {
  const sunrealtype qmax = N_VMaxNorm(g->q);
  const sunrealtype sig = std::sqrt(SUN_UNIT_ROUNDOFF) * (1 + N_VMaxNorm(ce->xcur)) / qmax;
  g->sig = sig;
  N_VLinearSum(1, ce->xcur, sig, g->q, g->xp);
  const int rv = CallRhs(ce, ce->tcur, g->xp, ce->D[1], g->w);
  ++ce->guard.nfe;
  if (rv != 0) {
    return ProcessError(ce, CE_RHSFUNC_FAIL, func,
                        "f failed (returned %d) in the stability guard at t = %.17g.", rv,
                        static_cast<double>(ce->tcur));
  }
  N_VLinearSum(-1 / sig, g->w, 1 / sig, g->f0, g->w);
  return CE_SUCCESS;
}

// Top eigenvalue theta of the Lanczos tridiagonal and its residual norm
// beta_k |e_k^T z| (z the unit Ritz vector).
void TopRitz(const GuardWork* g, sunrealtype beta_k, sunrealtype* theta, sunrealtype* res,
             Eigen::VectorXd* z = nullptr) {
  const int k = static_cast<int>(g->alpha.size());
  const Eigen::VectorXd diag = Eigen::Map<const Eigen::VectorXd>(g->alpha.data(), k);
  const Eigen::VectorXd sub = Eigen::Map<const Eigen::VectorXd>(g->beta.data(), k - 1);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es;
  es.computeFromTridiagonal(diag, sub, Eigen::ComputeEigenvectors);
  *theta = es.eigenvalues()(k - 1);
  *res = std::fabs(beta_k * es.eigenvectors()(k - 1, k - 1));
  if (z != nullptr) *z = es.eigenvectors().col(k - 1);
}

// The symmetry test's two numbers at step j: c = <q_{j-1}, A q_j>_M and a bound on the part of it
// that is the difference quotient's rounding, |q_{j-1}|_2 eps (|f(x)| + |f(x + sig q)|) / sig
// (Cauchy-Schwarz; with lumped masses |W q_{j-1}|_2, as the product is then weighted).
struct Coupling {
  sunrealtype c = 0;
  sunrealtype noise = 0;
};

// One Lanczos step on q: alpha_j, the next vector in w, its M-norm beta_j, and the coupling.
int LanczosStep(CEodeMemRec* ce, GuardWork* g, bool mass, sunrealtype beta_prev, const char* func,
                sunrealtype* beta, Coupling* cp) {
  int flag = StiffnessTimes(ce, g, func);
  if (flag != CE_SUCCESS) return flag;
  const sunrealtype rounding = kDqNoise * 2 * SUN_UNIT_ROUNDOFF * g->f0_norm / g->sig;
  if (!mass && g->wts != nullptr) {
    // w = M^{-1} K q already (f divides by the lumped mass): <q, w>_M, in which it is symmetric.
    MassTimes(g, g->w, g->mw);
    g->alpha.push_back(N_VDotProd(g->q, g->mw));
    cp->c = N_VDotProd(g->q_prev, g->mw);
    cp->noise = rounding * N_VWL2Norm(g->q_prev, g->wts);
  } else {
    g->alpha.push_back(N_VDotProd(g->q, g->w));  // q^T K q = <q, M^{-1} K q>_M
    cp->c = N_VDotProd(g->q_prev, g->w);
    cp->noise = rounding * std::sqrt(N_VDotProd(g->q_prev, g->q_prev));
  }
  if (mass) {
    N_VConst(0, g->mw);
    if (SUNLinSolSolve(g->LS, g->M, g->mw, g->w, 0) != 0) {
      return ProcessError(ce, CE_LSOLVE_FAIL, func, "The stability guard's mass solve failed.");
    }
    std::swap(g->w, g->mw);
  }
  N_VLinearSum(1, g->w, -g->alpha.back(), g->q, g->w);
  N_VLinearSum(1, g->w, -beta_prev, g->q_prev, g->w);
  MassTimes(g, g->w, g->mw);
  *beta = std::sqrt(std::max(N_VDotProd(g->w, g->mw), SUN_RCONST(0.0)));
  return CE_SUCCESS;
}

// A q = M^{-1} K q into g->w.
int OperatorTimes(CEodeMemRec* ce, GuardWork* g, bool mass, const char* func) {
  const int flag = StiffnessTimes(ce, g, func);
  if (flag != CE_SUCCESS || !mass) return flag;  // without M, f's K (or M^{-1} K) is A already
  N_VConst(0, g->mw);
  if (SUNLinSolSolve(g->LS, g->M, g->mw, g->w, 0) != 0) {
    return ProcessError(ce, CE_LSOLVE_FAIL, func, "The stability guard's mass solve failed.");
  }
  std::swap(g->w, g->mw);
  return CE_SUCCESS;
}

// g->w minus its M-projection on basis[0..k-1], the coefficients added to column col of H:
// classical Gram-Schmidt twice (one M product per pass; "twice is enough" for orthogonality
// to round-off). Returns the M-norm of what is left.
sunrealtype Orthogonalise(GuardWork* g, int k, int col) {
  for (int pass = 0; pass < 2; ++pass) {
    MassTimes(g, g->w, g->mw);
    for (int i = 0; i < k; ++i) {
      const sunrealtype h = N_VDotProd(g->basis[i], g->mw);
      g->H(i, col) += h;
      N_VLinearSum(1, g->w, -h, g->basis[i], g->w);
    }
  }
  MassTimes(g, g->w, g->mw);
  return std::sqrt(std::max(N_VDotProd(g->w, g->mw), SUN_RCONST(0.0)));
}

// Arnoldi vectors are cloned when first needed: a symmetric f never allocates them.
int EnsureBasis(CEodeMemRec* ce, GuardWork* g, int k, const char* func) {
  while (static_cast<int>(g->basis.size()) < k) {
    N_Vector v = CloneVector(ce->xcur);
    if (v == nullptr) return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory (guard).");
    g->basis.push_back(v);
  }
  return CE_SUCCESS;
}

struct ArnoldiRitz {
  bool found = false;  // a Ritz value with a positive real part
  sunrealtype theta = 0;
  sunrealtype res = 0;
  Eigen::VectorXcd y;
};

// Among the Ritz values of H_k with a positive real part (the oscillations a step must resolve;
// the others grow or decay whatever h is), the one of largest modulus, its unit eigenvector y and
// residual norm beta |e_k^T y|.
ArnoldiRitz TopArnoldiRitz(const GuardWork* g, int k, sunrealtype beta) {
  ArnoldiRitz r;
  Eigen::EigenSolver<Eigen::MatrixXd> es(g->H.topLeftCorner(k, k));
  if (es.info() != Eigen::Success) {
    r.theta = NAN;
    return r;
  }
  int best = -1;
  for (int i = 0; i < k; ++i) {
    const std::complex<double> lam = es.eigenvalues()(i);
    if (lam.real() > 0 && (best < 0 || std::abs(lam) > r.theta)) {
      best = i;
      r.theta = std::abs(lam);
    }
  }
  if (best < 0) return r;
  r.found = true;
  r.y = es.eigenvectors().col(best);
  r.res = std::fabs(beta) * std::abs(r.y(k - 1));
  return r;
}

// Explicit restart: basis[0] = the real Ritz vector of y (y turned so that its largest entry is
// real, whose real part therefore does not vanish), M-normalised.
void RestartFrom(GuardWork* g, int k, const Eigen::VectorXcd& y) {
  Eigen::Index m = 0;
  y.cwiseAbs().maxCoeff(&m);
  const std::complex<double> turn = std::conj(y(m)) / std::abs(y(m));
  N_VConst(0, g->q);
  for (int i = 0; i < k; ++i) N_VLinearSum(1, g->q, (y(i) * turn).real(), g->basis[i], g->q);
  MassTimes(g, g->q, g->mw);
  N_VScale(1 / std::sqrt(N_VDotProd(g->q, g->mw)), g->q, g->basis[0]);
  g->H.setZero();
}

// Column k of H from A basis[k]; the next residual is left in g->w, its M-norm in *beta.
int ArnoldiColumn(CEodeMemRec* ce, GuardWork* g, bool mass, int k, const char* func,
                  sunrealtype* beta) {
  N_VScale(1, g->basis[k], g->q);
  const int flag = OperatorTimes(ce, g, mass, func);
  if (flag != CE_SUCCESS) return flag;
  *beta = Orthogonalise(g, k + 1, k);
  g->H(k + 1, k) = *beta;
  return CE_SUCCESS;
}

// Arnoldi from k basis vectors whose k columns of H are done (residual in g->w, M-norm beta):
// lam_hat = theta + r for the top Ritz value theta (TopArnoldiRitz), restarted from its Ritz
// vector every kArnoldiDim steps, at most budget products of A. Without symmetry a small residual
// does not put an eigenvalue near theta (the error can be the eigenvector condition number times
// r: a scaled chain of cond 1e3 stopped at -5 % on r alone), so theta must also have stopped
// moving; an invariant subspace (beta ~ 0) makes theta exact.
int ArnoldiTop(CEodeMemRec* ce, GuardWork* g, bool mass, int k, sunrealtype beta, int budget,
               const char* func, sunrealtype* lam_hat) {
  sunrealtype theta_prev = -1;
  for (;;) {
    const ArnoldiRitz r = TopArnoldiRitz(g, k, beta);
    const sunrealtype scale = g->H.topLeftCorner(k + 1, k).cwiseAbs().maxCoeff();
    const bool breakdown = !(beta > 1e-9 * (scale + SUN_UNIT_ROUNDOFF));
    const bool settled = r.found && r.res <= kArnoldiTol * r.theta &&
                         std::fabs(r.theta - theta_prev) <= kArnoldiTol * r.theta;
    *lam_hat = r.theta + r.res;
    if (!std::isfinite(*lam_hat) || breakdown || budget == 0 || settled) return CE_SUCCESS;
    theta_prev = r.theta;
    int flag = CE_SUCCESS;
    if (k == kArnoldiDim) {
      RestartFrom(g, k, r.found ? r.y : Eigen::VectorXcd::Ones(k).eval());
      k = 0;
    } else {
      if ((flag = EnsureBasis(ce, g, k + 1, func)) != CE_SUCCESS) return flag;
      N_VScale(1 / beta, g->w, g->basis[k]);
    }
    if ((flag = ArnoldiColumn(ce, g, mass, k, func, &beta)) != CE_SUCCESS) return flag;
    ++k;
    --budget;
  }
}

// The symmetry test (kSymmetryTol): a mismatch |c - beta_{j-1}| beyond what the rounding and the
// loss of orthogonality it causes explain.
bool NotSymmetric(const Coupling& cp, sunrealtype beta_prev, sunrealtype amax) {
  const sunrealtype amplification = 1 + amax / beta_prev;
  return std::fabs(cp.c - beta_prev) >
         (kSymmetryTol * (amax + beta_prev) + cp.noise) * amplification;
}

// K is not symmetric at step j: continue by Arnoldi (docs/theory.md, the runtime guard). At j = 1
// no product is lost: q_0 and q_1 = (A q_0 - alpha_0 q_0) / beta_0 are Arnoldi's first two vectors
// too, and A q_1 differs from Lanczos's only in its coefficient on q_0 (c, not beta_0). Later the
// earlier Lanczos vectors are gone (and not orthogonal to q_j), so Arnoldi starts from q_j.
int SwitchToArnoldi(CEodeMemRec* ce, GuardWork* g, bool mass, int j, sunrealtype beta_prev,
                    sunrealtype c, const char* func, sunrealtype* lam_hat) {
  g->arnoldi = true;
  g->H.setZero(kArnoldiDim + 1, kArnoldiDim);
  int flag = EnsureBasis(ce, g, 2, func);
  if (flag != CE_SUCCESS) return flag;
  const int budget = kMaxLanczos - (j + 1);
  sunrealtype beta = 0;
  if (j == 1) {
    N_VScale(1, g->q_prev, g->basis[0]);
    N_VScale(1, g->q, g->basis[1]);
    g->H(0, 0) = g->alpha[0];
    g->H(1, 0) = beta_prev;
    g->H(0, 1) = c;
    g->H(1, 1) = g->alpha[1];
    N_VLinearSum(1, g->w, beta_prev - c, g->q_prev, g->w);  // w = A q_1 - c q_0 - alpha_1 q_1
    beta = Orthogonalise(g, 2, 1);
    g->H(2, 1) = beta;
    return ArnoldiTop(ce, g, mass, 2, beta, budget, func, lam_hat);
  }
  N_VScale(1, g->q, g->basis[0]);
  if ((flag = ArnoldiColumn(ce, g, mass, 0, func, &beta)) != CE_SUCCESS) return flag;
  return ArnoldiTop(ce, g, mass, 1, beta, budget - 1, func, lam_hat);
}

// The start vector into g->q: the pseudo-random one (StartVector), with the last estimate's top
// Ritz vector before it when there is one. Near the top mode the iteration then stops after a few
// products where a cold start takes dozens; the random part, and a cold start every kColdEvery-th
// estimate, keep a mode that rose past the old top within reach (docs/theory.md, the runtime
// guard).
void WarmStart(GuardWork* g) {
  StartVector(g->q);
  const bool warm = g->warm_ok && g->warm_runs + 1 < kColdEvery;
  g->warm_ok = false;
  if (!warm) {
    g->warm_runs = 0;
    return;
  }
  ++g->warm_runs;
  MassTimes(g, g->q, g->mw);
  const sunrealtype rnorm = std::sqrt(N_VDotProd(g->q, g->mw));
  N_VLinearSum(1, g->warm, 1 / rnorm, g->q, g->q);
}

// The top Ritz vector sum_i z_i basis[i] (M-normalised: z is a unit vector, the basis
// M-orthonormal) as the next estimate's warm start.
void KeepWarm(GuardWork* g, Eigen::VectorXd* z) {
  if (g->warm == nullptr) g->warm = CloneVector(g->q);
  if (g->warm == nullptr) return;  // no warm start: the next estimate starts cold
  const int k = static_cast<int>(z->size());
  g->warm_ok = N_VLinearCombination(k, z->data(), g->basis.data(), g->warm) == 0;
}

// The iteration's start: q_0 from WarmStart, M-normalised, and q_{-1} = 0; returns how many of
// its vectors are kept for the next warm start.
int LanczosStart(GuardWork* g) {
  g->alpha.clear();
  g->beta.clear();
  WarmStart(g);
  MassTimes(g, g->q, g->mw);
  N_VScale(1 / std::sqrt(N_VDotProd(g->q, g->mw)), g->q, g->q);
  N_VConst(0, g->q_prev);
  const sunindextype n = std::max<sunindextype>(1, N_VGetLength(g->q));
  return static_cast<int>(std::min<sunindextype>(kMaxLanczos, kWarmEntries / n));
}

// q_j into basis[j], for the top Ritz vector at the end.
int KeepVector(CEodeMemRec* ce, GuardWork* g, int j, const char* func) {
  const int flag = EnsureBasis(ce, g, j + 1, func);
  if (flag == CE_SUCCESS) N_VScale(1, g->q, g->basis[j]);
  return flag;
}

// At a check: the top Ritz pair (theta, its residual res), whether both it and beta are finite,
// and whether it has converged (an invariant space, or res below kLanczosTol of theta); then, with
// the basis kept, its vector becomes the next warm start.
bool RitzConverged(GuardWork* g, sunrealtype beta, bool breakdown, bool kept, sunrealtype* theta,
                   sunrealtype* res, bool* finite) {
  Eigen::VectorXd z;
  TopRitz(g, beta, theta, res, kept ? &z : nullptr);
  *finite = std::isfinite(*theta) && std::isfinite(beta);
  if (!*finite || !(breakdown || *res <= kLanczosTol * (std::fabs(*theta) + SUN_UNIT_ROUNDOFF))) {
    return false;
  }
  if (kept) KeepWarm(g, &z);
  return true;
}

// lam_hat >= omega_max^2: the top Ritz value plus its residual norm once that is
// below kLanczosTol of it (for a symmetric pencil an eigenvalue lies within the
// residual of theta); at the iteration cap theta + beta_k, the safer Lanczos bound.
int LanczosTop(CEodeMemRec* ce, GuardWork* g, bool mass, const char* func, sunrealtype* lam_hat) {
  const int keep = LanczosStart(g);
  sunrealtype beta_prev = 0;
  sunrealtype theta = 0;
  sunrealtype res = 0;
  sunrealtype beta = 0;
  sunrealtype amax = 0;  // scale of the operator seen so far
  Coupling cp;
  for (int j = 0; j < kMaxLanczos; ++j) {
    int flag = j < keep ? KeepVector(ce, g, j, func) : CE_SUCCESS;
    if (flag == CE_SUCCESS) flag = LanczosStep(ce, g, mass, beta_prev, func, &beta, &cp);
    if (flag != CE_SUCCESS) return flag;
    amax = std::max(amax, std::fabs(g->alpha.back()));
    if (j >= 1 && NotSymmetric(cp, beta_prev, amax)) {
      return SwitchToArnoldi(ce, g, mass, j, beta_prev, cp.c, func, lam_hat);
    }
    // beta ~ 0: the Krylov space is invariant (e.g. n is small), theta is exact.
    const bool breakdown = !(beta > 1e-9 * (amax + SUN_UNIT_ROUNDOFF));
    const bool check =
        j + 1 >= kMinLanczos && (j + 1 <= kEveryStepChecks || (j + 1) % kCheckEvery == 0);
    if (breakdown || j + 1 == kMaxLanczos || check) {
      bool finite = true;
      const bool converged = RitzConverged(g, beta, breakdown, j < keep, &theta, &res, &finite);
      if (!finite) break;
      if (converged) {
        *lam_hat = theta + res;
        return CE_SUCCESS;
      }
    }
    g->beta.push_back(beta);
    std::swap(g->q_prev, g->q);  // q_prev <- q_j, q <- w / beta (w is free again)
    std::swap(g->q, g->w);
    N_VScale(1 / beta, g->q, g->q);
    beta_prev = beta;
  }
  *lam_hat = theta + beta;
  return CE_SUCCESS;
}

// f(tcur, xcur, D_1) into g->f0: the start's D_2 when it is that (just after a start without a
// mass matrix, where D_2 = M^{-1} f = f), else one evaluation.
int BaseForce(CEodeMemRec* ce, GuardWork* g, const char* func) {
  const bool start_accel = ce->guard.accel && ce->started && ce->nst == ce->guard.accel_nst &&
                           ce->ls.M == nullptr && ce->ls.mfn == nullptr;
  if (start_accel) {
    N_VScale(1, ce->D[2], g->f0);
    return CE_SUCCESS;
  }
  const int rv = CallRhs(ce, ce->tcur, ce->xcur, ce->D[1], g->f0);
  ++ce->guard.nfe;
  if (rv != 0) {
    return ProcessError(ce, CE_RHSFUNC_FAIL, func,
                        "f failed (returned %d) in the stability guard at t = %.17g.", rv,
                        static_cast<double>(ce->tcur));
  }
  return CE_SUCCESS;
}

// The guard's estimate of omega_max at (tcur, xcur, D_1): the user's value when
// given, else Lanczos; 0 when there is nothing to estimate (constraints, a mass
// matrix type without a guard solver, f independent of x).
int Estimate(CEodeMemRec* ce, const char* func, sunrealtype* omega) {
  if (ce->guard.omega_user > 0) {
    *omega = ce->guard.omega_user;
    return CE_SUCCESS;
  }
  if (ce->guard.carried) {  // CEodeSetGuardReuse: the last run's estimate, once
    ce->guard.carried = false;
    *omega = ce->guard.omega_est;
    return CE_SUCCESS;
  }
  *omega = 0;
  if (HasConstraints(ce)) return CE_SUCCESS;  // constrained frequencies need the user's value
  // The mass matrix may be of another size than a CEodeInit made the problem since.
  int flag = ValidateMassMatrix(ce, func, ce->ls.M);
  if (flag == CE_SUCCESS) flag = AllocWork(ce, func);
  GuardWork* g = Work(ce);
  bool usable = true;
  if (flag == CE_SUCCESS) flag = GuardMass(ce, g, func, &usable);
  if (flag != CE_SUCCESS || !usable) return flag;
  if ((flag = BaseForce(ce, g, func)) != CE_SUCCESS) return flag;
  g->f0_norm = std::sqrt(N_VDotProd(g->f0, g->f0));
  g->arnoldi = false;
  sunrealtype lam = 0;
  flag = LanczosTop(ce, g, ce->ls.M != nullptr, func, &lam);
  if (flag == CE_SUCCESS && lam > 0 && std::isfinite(lam)) *omega = std::sqrt(lam);
  return flag;
}

// The method's limit, once per method: a named set's from the table, other parameters
// computed: -1 when unstable for every step.
sunrealtype Limit(CEodeMemRec* ce) {
  if (ce->guard.omega_limit == 0) {
    sunrealtype lim = 0;
    if (const MethodSet* m = NamedSetWithParams(ce->degree, ce->params)) {
      lim = m->omega_max;
    } else if (MethodStabilityLimit(ce->degree, ce->params, &lim) != CE_SUCCESS) {
      return 0;
    }
    ce->guard.omega_limit = lim > 0 ? lim : -1;
  }
  return ce->guard.omega_limit;
}

// Named sets stable at Omega (with the recommendation's margin), into out.
std::string StableSets(sunrealtype Omega) {
  std::string out;
  for (int i = 0; i < NumMethodSets(); ++i) {
    const MethodSet& m = MethodSetAt(i);
    if (kRecommendSafety * m.omega_max < Omega) continue;
    out += out.empty() ? "" : ", ";
    out += m.name;
  }
  return out.empty() ? "none" : out;
}

// Weakly unstable for every h: what matters is the growth over the run, to the
// stop time when one is set, else over a horizon of kHorizonSteps steps.
sunrealtype RunSteps(const CEodeMemRec* ce) {
  constexpr sunrealtype kHorizonSteps = 1e6;
  return ce->tstop_set ? std::max((ce->tstop - ce->tcur) / ce->h, SUN_RCONST(1.0)) : kHorizonSteps;
}

// "grows by rho per step, doubling every N steps (T time units)", from rho at the run's Omega.
std::string GrowthText(const CEodeMemRec* ce, sunrealtype rho) {
  char buf[320];
  const sunrealtype lr = std::log(rho);
  if (!(lr > 4 * SUN_UNIT_ROUNDOFF)) {
    return "the fastest mode's amplification matrix has spectral radius 1 here (the edge of the "
           "limit): errors grow polynomially, not exponentially";
  }
  const sunrealtype doubling = std::log(2.0) / lr;
  // Round-off (unit roundoff relative to the state) in that mode reaches the
  // state's own size after about this many steps.
  const sunrealtype to_size = -std::log(SUN_UNIT_ROUNDOFF) / lr;
  int len = std::snprintf(buf, sizeof buf,
                          "errors in the fastest mode grow by rho = %.9g per step (doubling every "
                          "%.3g steps = %.3g time units; round-off there reaches the size of the "
                          "solution after about %.3g steps",
                          static_cast<double>(rho), static_cast<double>(doubling),
                          static_cast<double>(doubling * ce->h), static_cast<double>(to_size));
  if (ce->tstop_set && len > 0 && len < static_cast<int>(sizeof buf)) {
    len += std::snprintf(buf + len, sizeof buf - len, "; the %.3g steps to the stop time: 10^%.3g",
                         static_cast<double>(RunSteps(ce)),
                         static_cast<double>(RunSteps(ce) * lr / std::log(10.0)));
  }
  if (len > 0 && len < static_cast<int>(sizeof buf) - 1)
    std::snprintf(buf + len, sizeof buf - len, ")");
  return buf;
}

// Which named sets the user can switch to, and what they conserve over long runs: the measured
// long-run table (LongRunAdvice, src/ceode_long_run.cpp; docs/stability.md) decides.
std::string SetAdvice(const CEodeMemRec* ce, sunrealtype Omega) {
  constexpr sunrealtype kCdLimit = 2;  // G3_CD: Omega_max = 2
  std::string out = "Named sets stable at this h: " + StableSets(Omega);
  if (kRecommendSafety * kCdLimit >= Omega) {
    char advice[512];
    LongRunAdvice(ce->method_name.c_str(), Omega, advice, sizeof advice);
    // Between LongRunAdvice's margin (0.9) and the guard's (0.99) its "reduce h" would
    // contradict the list above; G3_CD is still stable there.
    if (advice[0] != '\0' && std::strncmp(advice, "no named set", 12) != 0)
      out += "; " + std::string(advice);
    return out;
  }
  char buf[200];
  std::snprintf(buf, sizeof buf,
                "; G3_CD, the named set whose energy error stays bounded over long runs, needs "
                "h <= %.6g",
                static_cast<double>(kRecommendSafety * kCdLimit / ce->guard.omega_est));
  return out + buf;
}

void Report(CEodeMemRec* ce, const char* func, sunrealtype Omega, sunrealtype rho, bool refuse) {
  const int flag = refuse ? CE_UNSTABLE : CE_WARNING;
  const GuardWork* g = Work(ce);
  const char* source = ce->guard.omega_user > 0 ? "given by CEodeSetMaxFrequency"
                       : g != nullptr && g->arnoldi
                           ? "estimated by Arnoldi, as df/dx is not symmetric: the square root of "
                             "the spectral radius of M^{-1} df/dx, not a bound"
                           : "an upper estimate by Lanczos";
  const char* tail = refuse ? "" : " (CE_GUARD_REFUSE stops instead of warning)";
  const std::string growth = GrowthText(ce, rho);
  if (ce->guard.omega_limit < 0) {
    ProcessError(ce, flag, func,
                 "At t = %.9g (step %ld): %s is unstable for every step size. With omega_max = %g "
                 "(%s) and h = %g, Omega = %g: %s. %s%s.",
                 static_cast<double>(ce->tcur), ce->nst, ce->method_name.c_str(),
                 static_cast<double>(ce->guard.omega_est), source, static_cast<double>(ce->h),
                 static_cast<double>(Omega), growth.c_str(), SetAdvice(ce, Omega).c_str(), tail);
    return;
  }
  ProcessError(ce, flag, func,
               "At t = %.9g (step %ld): h * omega_max = %g * %g = %.6g exceeds the stability limit "
               "Omega_max = %.6g of %s (omega_max %s): %s. h <= %.6g (%g Omega_max / omega_max) is "
               "stable%s.",
               static_cast<double>(ce->tcur), ce->nst, static_cast<double>(ce->h),
               static_cast<double>(ce->guard.omega_est), static_cast<double>(Omega),
               static_cast<double>(ce->guard.omega_limit), ce->method_name.c_str(), source,
               growth.c_str(),
               static_cast<double>(kRecommendSafety * ce->guard.omega_limit / ce->guard.omega_est),
               static_cast<double>(kRecommendSafety), tail);
}

// CEodeSetGuardMass's vector: the length of x, every entry positive and finite.
int CheckGuardMass(CEodeMemRec* ce, const char* func, N_Vector mass) {
  if (N_VGetLength(mass) != N_VGetLength(ce->xcur)) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "mass has %ld entries but x has %ld: give one lumped mass per entry of x.",
                        static_cast<long>(N_VGetLength(mass)),
                        static_cast<long>(N_VGetLength(ce->xcur)));
  }
  // min > 0 and a finite sum: no zero, negative, NaN (which propagates through the sum) or Inf.
  const sunrealtype mn = N_VMin(mass);
  if (!(mn > 0) || !std::isfinite(N_VL1Norm(mass))) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "mass has an entry that is not positive and finite (min %g): every lumped "
                        "mass must be.",
                        static_cast<double>(mn));
  }
  return CE_SUCCESS;
}

}  // namespace

void GuardFree(CEodeMemRec* ce) {
  ce->guard.omega_est = 0;  // a new problem (or none): nothing to carry over
  ce->guard.carried = false;
  GuardWork* g = Work(ce);
  if (g == nullptr) return;
  for (N_Vector v : {g->q_prev, g->q, g->w, g->mw, g->xp, g->f0, g->wts, g->warm}) {
    if (v != nullptr) N_VDestroy(v);
  }
  for (N_Vector v : g->basis) N_VDestroy(v);
  FreeMass(g);
  delete g;
  ce->guard.work = nullptr;
}

void GuardReset(CEodeMemRec* ce, bool counters) {
  GuardMem& g = ce->guard;
  if (g.work != nullptr) {
    Work(ce)->mass_ready = false;
    Work(ce)->warm_ok = false;  // each run's first estimate starts cold
  }
  g.accel = false;
  // The user's frequency, when set, is not an estimate to carry.
  g.carried = g.reuse && !(g.omega_user > 0) && g.omega_est > 0 && std::isfinite(g.omega_est);
  if (!counters) return;
  g.warned = false;
  g.nfe = g.nme = g.nsetups = 0;
}

void GuardMethodChanged(CEodeMemRec* ce) { ce->guard.omega_limit = 0; }

void GuardRequestCheck(CEodeMemRec* ce) {
  ce->guard.pending = true;
  StepOptionsChanged(ce);  // the one-step fast path leaves the check to CEodeEvolve's general path
}

void GuardStartAccel(CEodeMemRec* ce) {
  ce->guard.accel = true;
  ce->guard.accel_nst = ce->nst;
}

sunrealtype GuardStableStep(CEodeMemRec* ce, sunrealtype safety) {
  const sunrealtype omega = ce->guard.omega_est;
  if (!GuardOn(ce) || !(omega > 0) || !std::isfinite(omega)) return SUN_BIG_REAL;
  const sunrealtype lim = Limit(ce);
  return lim > 0 ? safety * lim / omega : SUN_BIG_REAL;
}

int GuardCheckPending(CEodeMemRec* ce, const char* func) {
  if (!ce->guard.pending) return CE_SUCCESS;
  ce->guard.pending = false;
  return GuardCheck(ce, func);
}

}  // namespace ceode

namespace ceode {

int GuardCheck(CEodeMemRec* ce, const char* func) {
  if (ce->guard.mode == CE_GUARD_OFF) return CE_SUCCESS;
  const int flag = Estimate(ce, func, &ce->guard.omega_est);
  if (flag != CE_SUCCESS) return flag;
  // No oscillation to resolve (f independent of x), or no estimate possible.
  if (!(ce->guard.omega_est > 0) || !std::isfinite(ce->guard.omega_est)) return CE_SUCCESS;
  // With error control the estimate caps the steps (GuardStableStep): nothing to warn about.
  if (AdaptOn(ce)) return CE_SUCCESS;
  const sunrealtype lim = Limit(ce);
  const sunrealtype Omega = ce->h * ce->guard.omega_est;
  // omega_est >= omega_max, so Omega <= lim keeps the true h * omega_max inside too.
  if (lim == 0 || (lim > 0 && Omega <= lim)) return CE_SUCCESS;
  sunrealtype rho = 1;
  if (CEodeSpectralRadius(ce->degree, ce->params, Omega, 0, &rho) != CE_SUCCESS) rho = 1;
  if (lim < 0 && !(RunSteps(ce) * std::log(rho) >= std::log(2.0))) return CE_SUCCESS;
  const bool refuse = ce->guard.mode == CE_GUARD_REFUSE;
  if (!refuse && ce->guard.warned) return CE_SUCCESS;  // warn once per run
  ce->guard.warned = true;
  Report(ce, func, Omega, rho, refuse);
  if (!refuse) return CE_SUCCESS;
  // The next CEodeEvolve restarts here and checks again, so a refused run cannot
  // be resumed by simply calling CEodeEvolve once more.
  Restart(ce);
  return CE_UNSTABLE;
}

}  // namespace ceode

extern "C" {

int CEodeGetStableStep(void* mem, sunrealtype safety, sunrealtype* hmax) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce, true);
  if (flag != CE_SUCCESS) return flag;
  if (hmax == nullptr) return ceode::ProcessError(ce, CE_ILL_INPUT, __func__, "hmax = NULL.");
  if (safety == 0) safety = ceode::kRecommendSafety;
  if (!(safety > 0 && safety <= 1)) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "safety = %g: pass a factor in (0, 1], or 0 for the default %g.",
                               static_cast<double>(safety),
                               static_cast<double>(ceode::kRecommendSafety));
  }
  if (ceode::HasConstraints(ce) && !(ce->guard.omega_user > 0)) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "With constraints the guard cannot estimate omega_max: give it "
                               "with CEodeSetMaxFrequency.");
  }
  flag = ceode::Estimate(ce, __func__, &ce->guard.omega_est);
  if (flag != CE_SUCCESS) return flag;
  const sunrealtype lim = ceode::Limit(ce);
  if (lim == 0) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "The stability limit of %s could not be computed.",
                               ce->method_name.c_str());
  }
  const sunrealtype w = ce->guard.omega_est;
  if (!std::isfinite(w)) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "The frequency estimate is %g: f or the mass matrix gives no "
                               "finite Rayleigh quotient at the current state.",
                               static_cast<double>(w));
  }
  if (lim < 0) {
    *hmax = 0;  // unstable for every step
  } else {
    // A frequency so small that the quotient overflows bounds the step no more than none does.
    const sunrealtype h = w > 0 ? safety * lim / w : SUN_BIG_REAL;
    *hmax = std::isfinite(h) ? h : SUN_BIG_REAL;
  }
  return CE_SUCCESS;
}

int CEodeSetGuardMass(void* mem, N_Vector mass) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce, true);
  if (flag != CE_SUCCESS) return flag;
  if ((flag = ceode::AllocWork(ce, __func__)) != CE_SUCCESS) return flag;
  ceode::GuardWork* g = ceode::Work(ce);
  if (mass == nullptr) {
    if (g->wts != nullptr) N_VDestroy(g->wts);
    g->wts = nullptr;
  } else if ((flag = ceode::CheckGuardMass(ce, __func__, mass)) != CE_SUCCESS) {
    return flag;
  } else {
    if (g->wts == nullptr) g->wts = ceode::CloneVector(ce->xcur);
    if (g->wts == nullptr) return ceode::ProcessError(ce, CE_MEM_FAIL, __func__, "Out of memory.");
    N_VScale(1, mass, g->wts);
  }
  ce->guard.warned = false;
  ce->guard.carried = false;     // other masses, other frequencies
  ceode::GuardRequestCheck(ce);  // checked again at the next CEodeEvolve
  return CE_SUCCESS;
}

int CEodeSetGuardReuse(void* mem, sunbooleantype reuse) {
  CEodeMemRec* ce = nullptr;
  const int flag = ceode::Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  ce->guard.reuse = reuse != SUNFALSE;
  if (!ce->guard.reuse) ce->guard.carried = false;
  return CE_SUCCESS;
}

int CEodeGetGuardStats(void* mem, long int* nfevals, long int* nmevals, long int* nlinsetups) {
  CEodeMemRec* ce = nullptr;
  const int flag = ceode::Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (nfevals == nullptr || nmevals == nullptr || nlinsetups == nullptr) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__, "An output pointer is NULL.");
  }
  *nfevals = ce->guard.nfe;
  *nmevals = ce->guard.nme;
  *nlinsetups = ce->guard.nsetups;
  return CE_SUCCESS;
}

int CEodeSetStabilityGuard(void* mem, int mode, long int every) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (mode != CE_GUARD_OFF && mode != CE_GUARD_WARN && mode != CE_GUARD_REFUSE) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "mode = %d: use CE_GUARD_OFF, CE_GUARD_WARN or CE_GUARD_REFUSE.",
                               mode);
  }
  if (every < 0) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "every = %ld: use 0 (check at start only) or a positive step count.",
                               every);
  }
  ce->guard.mode = mode;
  ce->guard.every = every;
  ce->guard.warned = false;
  ceode::GuardRequestCheck(ce);
  return CE_SUCCESS;
}

int CEodeSetMaxFrequency(void* mem, sunrealtype omega_max) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (!(omega_max >= 0) || !std::isfinite(omega_max)) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "omega_max = %g: pass a non-negative frequency (0: estimate it).",
                               static_cast<double>(omega_max));
  }
  ce->guard.omega_user = omega_max;
  ce->guard.warned = false;
  ceode::GuardRequestCheck(ce);  // a new estimate is checked at the next CEodeEvolve
  return CE_SUCCESS;
}

}  // extern "C"
