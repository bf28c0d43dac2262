// Linear stability from the integrator's own step map (method.md section 4).
// The runtime guard that uses it is in ceode_guard.cpp.
#include <ceode/ceode_stability.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <memory>

#include "ceode_impl.hpp"

namespace ceode {

namespace {

struct TestProblem {
  sunrealtype omega;
  sunrealtype xi;
};

// x'' = -Omega^2 x - 2 xi Omega x' with h = 1, so that omega h = Omega.
int TestRhs(sunrealtype /*t*/, N_Vector x, N_Vector v, N_Vector f, void* data) {
  const auto* p = static_cast<const TestProblem*>(data);
  N_VLinearSum(-p->omega * p->omega, x, -2 * p->xi * p->omega, v, f);
  return 0;
}

int TestJac(sunrealtype /*t*/, N_Vector /*x*/, N_Vector /*v*/, N_Vector /*f*/, SUNMatrix J,
            void* data, N_Vector, N_Vector, N_Vector) {
  const auto* p = static_cast<const TestProblem*>(data);
  SUNDenseMatrix_Data(J)[0] = -2 * p->xi * p->omega;
  return 0;
}

// Owns a one-degree-of-freedom CEODE run whose step is applied to unit states.
class StepMap {
 public:
  StepMap(int degree, const sunrealtype* params, sunrealtype xi) : prob_{0, xi} {
    SUNContext_Create(nullptr, &ctx_);
    x_ = N_VNew_Serial(1, ctx_);
    v_ = N_VNew_Serial(1, ctx_);
    N_VConst(0, x_);
    N_VConst(0, v_);
    mem_ = CEodeCreate(ctx_);
    CEodeSetErrFile(mem_, nullptr);
    ok_ = CEodeInit(mem_, TestRhs, 0, x_, v_) == CE_SUCCESS &&
          CEodeSetMethod(mem_, degree, params) == CE_SUCCESS &&
          CEodeSetFixedStep(mem_, 1) == CE_SUCCESS &&
          CEodeSetUserData(mem_, &prob_) == CE_SUCCESS &&
          CEodeSetStabilityGuard(mem_, CE_GUARD_OFF, 0) == CE_SUCCESS;
    if (ok_ && xi > 0) {
      A_ = SUNDenseMatrix(1, 1, ctx_);
      LS_ = SUNLinSol_Dense(x_, A_, ctx_);
      ok_ = CEodeSetVelocityDependence(mem_, SUNTRUE) == CE_SUCCESS &&
            CEodeSetLinearSolver(mem_, LS_, A_) == CE_SUCCESS &&
            CEodeSetVelJacFn(mem_, TestJac) == CE_SUCCESS &&
            CEodeSetNonlinTolerances(mem_, 1e-15, 0) == CE_SUCCESS;
    }
    sunrealtype t = 0;
    // One real step builds the solver objects and coefficients for h = 1.
    ok_ = ok_ && CEodeEvolve(mem_, 1, x_, v_, &t, CE_ONE_STEP) == CE_SUCCESS;
  }
  ~StepMap() {
    CEodeFree(&mem_);
    if (LS_ != nullptr) SUNLinSolFree(LS_);
    if (A_ != nullptr) SUNMatDestroy(A_);
    N_VDestroy(x_);
    N_VDestroy(v_);
    SUNContext_Free(&ctx_);
  }
  StepMap(const StepMap&) = delete;
  StepMap& operator=(const StepMap&) = delete;

  bool ok() const { return ok_; }

  // Column k of A: the step applied to the k-th unit state (x(t), D_1..D_{d-1}(t-h)).
  bool Build(sunrealtype Omega, Eigen::MatrixXd* A) {
    auto* ce = static_cast<CEodeMemRec*>(mem_);
    const int d = ce->degree;
    prob_.omega = Omega;
    A->resize(d, d);
    for (int k = 0; k < d; ++k) {
      N_VConst(0, ce->xnext);
      for (int j = 1; j < d; ++j) N_VConst(k == j ? 1 : 0, ce->D[j]);
      if (k == 0) N_VConst(1, ce->xnext);
      ce->jac_current = false;
      if (TakeStep(ce) != CE_SUCCESS) return false;
      (*A)(0, k) = N_VGetArrayPointer(ce->xnext)[0];
      for (int j = 1; j < d; ++j) (*A)(j, k) = N_VGetArrayPointer(ce->D[j])[0];
    }
    return true;
  }

 private:
  TestProblem prob_;
  SUNContext ctx_ = nullptr;
  N_Vector x_ = nullptr;
  N_Vector v_ = nullptr;
  SUNMatrix A_ = nullptr;
  SUNLinearSolver LS_ = nullptr;
  void* mem_ = nullptr;
  bool ok_ = false;
};

int CheckArgs(int degree, const sunrealtype* params, sunrealtype xi) {
  if (degree < kMinDegree || degree > kMaxDegree || params == nullptr || !(xi >= 0) ||
      !std::isfinite(xi)) {
    return CE_ILL_INPUT;
  }
  for (int i = 0; i < degree - 1; ++i) {
    if (!std::isfinite(params[i])) return CE_ILL_INPUT;
  }
  // beta (and gamma for d >= 4) divide in the step: CEodeSetMethod refuses them too.
  if (params[1] == 0 || (degree >= 4 && params[2] == 0)) return CE_ILL_INPUT;
  return CE_SUCCESS;
}

// The eigen-analysis of one amplification matrix.
struct Spectrum {
  sunrealtype rho = 0;     // spectral radius
  sunrealtype excess = 0;  // max_i (|lambda_i| - 1 - tol_i): > 0 means unstable
};

// Smallest tolerance on |lambda| = 1, for well-conditioned eigenvalues.
constexpr sunrealtype kRhoTolFloor = 1e-13;
// Multiplier of the first-order eigenvalue error bound kappa_i * eps * ||A||.
constexpr sunrealtype kRhoTolFactor = 64;

// The undamped physical pair sits exactly on the unit circle, so rho = 1 must be
// recognised through rounding. A fixed tolerance cannot serve everywhere: near
// a collision of eigenvalues (at Omega -> 0, or where the pair meets a spurious
// root, as G4_A34 does at sqrt(3)) the computed |lambda| errs by 1e-11 and more,
// while G5_TOP's physical pair leaves the circle by only 1e-10 near Omega = 0.07.
// So each eigenvalue gets its own tolerance from its condition number
// kappa_i = |x_i| |y_i| / |y_i^H x_i| (right and left eigenvectors): the first-order
// error bound kappa_i * eps * ||A||, times a safety factor.
Spectrum Analyse(const Eigen::MatrixXd& A) {
  Spectrum s;
  Eigen::EigenSolver<Eigen::MatrixXd> es(A, true);
  if (es.info() != Eigen::Success) {
    s.rho = s.excess = std::numeric_limits<sunrealtype>::infinity();
    return s;
  }
  const Eigen::VectorXcd& lam = es.eigenvalues();
  const Eigen::MatrixXcd V = es.eigenvectors();
  Eigen::FullPivLU<Eigen::MatrixXcd> lu(V);
  const sunrealtype anorm = A.norm();
  const sunrealtype eps = std::numeric_limits<sunrealtype>::epsilon();
  Eigen::MatrixXcd W;  // rows: left eigenvectors with y_i^H x_i = 1
  const bool invertible = lu.isInvertible();
  if (invertible) W = lu.inverse();
  s.excess = -std::numeric_limits<sunrealtype>::infinity();
  for (int i = 0; i < lam.size(); ++i) {
    const sunrealtype mod = std::abs(lam(i));
    s.rho = std::max(s.rho, mod);
    // A defective matrix has no inverse: its eigenvalues are known to sqrt(eps) only.
    const sunrealtype kappa = invertible ? V.col(i).norm() * W.row(i).norm() : 1 / std::sqrt(eps);
    // Capped at sqrt(eps), the accuracy of an exactly defective eigenvalue, so that a
    // crossing through a Jordan block (G4_A34 at sqrt(3)) is not overshot.
    const sunrealtype tol =
        std::min(std::sqrt(eps), std::max(kRhoTolFloor, kRhoTolFactor * kappa * eps * anorm));
    s.excess = std::max(s.excess, mod - 1 - tol);
  }
  return s;
}

// The scan's grid: instability confined to an interval narrower than this (or
// below it, near Omega = 0) is below the resolution of the analysis.
constexpr sunrealtype kScanStep = 1e-3;
constexpr sunrealtype kScanMax = 20;

}  // namespace

// Eigen and the solver objects allocate: no exception may cross the C API.
template <typename Fn>
int NoThrow(Fn fn) {
  try {
    return fn();
  } catch (...) {
    return CE_MEM_FAIL;
  }
}

int MethodStabilityLimit(int degree, const sunrealtype* params, sunrealtype* Omega_max) {
  return CEodeStabilityLimit(degree, params, 0, Omega_max);
}

}  // namespace ceode

extern "C" {

static int CEodeAmplificationMatrixImpl(int degree, const sunrealtype* params, sunrealtype Omega,
                                        sunrealtype xi, sunrealtype* A) {
  if (ceode::CheckArgs(degree, params, xi) != CE_SUCCESS || A == nullptr || !(Omega >= 0) ||
      !std::isfinite(Omega)) {
    return CE_ILL_INPUT;
  }
  ceode::StepMap map(degree, params, xi);
  Eigen::MatrixXd M;
  if (!map.ok() || !map.Build(Omega, &M)) return CE_ILL_INPUT;
  for (int i = 0; i < degree; ++i) {
    for (int j = 0; j < degree; ++j) A[i * degree + j] = M(i, j);
  }
  return CE_SUCCESS;
}

static int CEodeSpectralRadiusImpl(int degree, const sunrealtype* params, sunrealtype Omega,
                                   sunrealtype xi, sunrealtype* rho) {
  if (ceode::CheckArgs(degree, params, xi) != CE_SUCCESS || rho == nullptr || !(Omega >= 0) ||
      !std::isfinite(Omega)) {
    return CE_ILL_INPUT;
  }
  ceode::StepMap map(degree, params, xi);
  Eigen::MatrixXd M;
  if (!map.ok() || !map.Build(Omega, &M)) return CE_ILL_INPUT;
  *rho = ceode::Analyse(M).rho;
  return CE_SUCCESS;
}

static int CEodeStabilityLimitImpl(int degree, const sunrealtype* params, sunrealtype xi,
                                   sunrealtype* Omega_max) {
  if (ceode::CheckArgs(degree, params, xi) != CE_SUCCESS || Omega_max == nullptr) {
    return CE_ILL_INPUT;
  }
  ceode::StepMap map(degree, params, xi);
  if (!map.ok()) return CE_ILL_INPUT;
  Eigen::MatrixXd M;
  bool failed = false;
  auto stable = [&](sunrealtype Om) {
    if (!map.Build(Om, &M)) {
      failed = true;
      return false;
    }
    return ceode::Analyse(M).excess <= 0;
  };
  using ceode::kScanMax;
  using ceode::kScanStep;
  // Growth that only shows below the grid (rho - 1 ~ Omega^2 for G4_A54, or a
  // damped spurious root ~ xi Omega) still makes every h unstable.
  for (sunrealtype Om : {1e-5, 1e-4}) {
    if (!stable(Om)) {
      *Omega_max = 0;
      return failed ? CE_ILL_INPUT : CE_SUCCESS;
    }
  }
  const int kmax = static_cast<int>(std::lround(kScanMax / kScanStep));
  int k = 1;
  while (k <= kmax && stable(k * kScanStep)) ++k;
  if (failed) return CE_ILL_INPUT;
  if (k == 1) {
    *Omega_max = 0;
    return CE_SUCCESS;
  }
  if (k > kmax) {
    *Omega_max = kScanMax;  // stable on the whole scanned range
    return CE_SUCCESS;
  }
  sunrealtype lo = (k - 1) * kScanStep;
  sunrealtype hi = k * kScanStep;
  while (hi - lo > 4 * std::numeric_limits<sunrealtype>::epsilon() * hi) {
    const sunrealtype mid = 0.5 * (lo + hi);
    if (mid <= lo || mid >= hi) break;
    (stable(mid) ? lo : hi) = mid;
  }
  if (failed) return CE_ILL_INPUT;
  *Omega_max = lo;
  return CE_SUCCESS;
}

static int CEodeSpectralRadiiImpl(int degree, const sunrealtype* params, sunrealtype xi, int n,
                                  const sunrealtype* Omega, sunrealtype* rho) {
  if (ceode::CheckArgs(degree, params, xi) != CE_SUCCESS || n < 0 || (n > 0 && Omega == nullptr) ||
      (n > 0 && rho == nullptr)) {
    return CE_ILL_INPUT;
  }
  for (int i = 0; i < n; ++i) {
    if (!(Omega[i] >= 0) || !std::isfinite(Omega[i])) return CE_ILL_INPUT;
  }
  if (n == 0) return CE_SUCCESS;
  ceode::StepMap map(degree, params, xi);
  if (!map.ok()) return CE_ILL_INPUT;
  Eigen::MatrixXd M;
  for (int i = 0; i < n; ++i) {
    if (!map.Build(Omega[i], &M)) return CE_ILL_INPUT;
    rho[i] = ceode::Analyse(M).rho;
  }
  return CE_SUCCESS;
}

int CEodeAmplificationMatrix(int degree, const sunrealtype* params, sunrealtype Omega,
                             sunrealtype xi, sunrealtype* A) {
  return ceode::NoThrow([&] { return CEodeAmplificationMatrixImpl(degree, params, Omega, xi, A); });
}

int CEodeSpectralRadius(int degree, const sunrealtype* params, sunrealtype Omega, sunrealtype xi,
                        sunrealtype* rho) {
  return ceode::NoThrow([&] { return CEodeSpectralRadiusImpl(degree, params, Omega, xi, rho); });
}

int CEodeStabilityLimit(int degree, const sunrealtype* params, sunrealtype xi,
                        sunrealtype* Omega_max) {
  return ceode::NoThrow([&] { return CEodeStabilityLimitImpl(degree, params, xi, Omega_max); });
}

int CEodeSpectralRadii(int degree, const sunrealtype* params, sunrealtype xi, int n,
                       const sunrealtype* Omega, sunrealtype* rho) {
  return ceode::NoThrow([&] { return CEodeSpectralRadiiImpl(degree, params, xi, n, Omega, rho); });
}

}  // extern "C"
