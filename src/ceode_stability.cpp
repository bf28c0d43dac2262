// Linear stability from the integrator's own step map (docs/theory.md section 9).
// The runtime guard that uses it is in ceode_guard.cpp.
#include <ceode/ceode_stability.h>
#include <nvector/nvector_serial.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <memory>
#include <vector>

#include "ceode_kernels.hpp"

namespace ceode {

namespace {

// The step of the method on the test equation x'' = -Omega^2 x - 2 xi Omega x' with h = 1 (so
// that omega h = Omega), applied to the d unit states (x(t), D_1..D_{d-1}(t - h)) at once: entry k
// of every vector below belongs to unit state k. The coefficients come from ComputeStepCoeffs
// and the update is the integrator's own plan (BuildUpdatePlan, UpdateReference); no CEODE
// instance is involved.
class StepMap {
 public:
  StepMap(int degree, const sunrealtype* params, sunrealtype xi) : d_(degree), xi_(xi) {
    ComputeStepCoeffs(degree, params, 1, &co_);
    ok_ = sun::ContextCreate(&ctx_) == 0;
    for (N_Vector* v : Vectors()) {
      if (ok_) *v = N_VNew_Serial(degree, ctx_);
      ok_ = ok_ && *v != nullptr;
    }
    if (ok_) BuildUpdatePlan(d_, co_, D_, Dn_, xnext_, xnew_, &plan_);
  }
  ~StepMap() {
    for (N_Vector* v : Vectors()) {
      if (*v != nullptr) N_VDestroy(*v);
    }
    if (ctx_ != nullptr) SUNContext_Free(&ctx_);
  }
  StepMap(const StepMap&) = delete;
  StepMap& operator=(const StepMap&) = delete;

  bool ok() const { return ok_; }

  // Column k of A: the step applied to the k-th unit state.
  bool Build(sunrealtype Omega, Eigen::MatrixXd* A) {
    for (int k = 0; k < d_; ++k) {
      N_VGetArrayPointer(xnext_)[k] = k == 0 ? 1 : 0;
      for (int j = 1; j < d_; ++j) N_VGetArrayPointer(D_[j])[k] = k == j ? 1 : 0;
    }
    N_Vector a = Dn_[2];
    if (xi_ == 0) {  // explicit path: f sees the last velocity D_1(t - h)
      N_VLinearSum(-Omega * Omega, xnext_, -2 * xi_ * Omega, D_[1], a);
    } else {  // implicit path: a = f(x, V0 + kappa a), linear in a, solved exactly
      VelocityOffset(d_, co_, D_, V0_);
      N_VLinearSum(-Omega * Omega, xnext_, -2 * xi_ * Omega, V0_, a);
      N_VScale(1 / (1 + 2 * xi_ * Omega * co_.kappa), a, a);
    }
    UpdateReference(plan_, Compensation{});
    A->resize(d_, d_);
    for (int k = 0; k < d_; ++k) {
      (*A)(0, k) = N_VGetArrayPointer(xnew_)[k];
      for (int j = 1; j < d_; ++j) (*A)(j, k) = N_VGetArrayPointer(Dn_[j])[k];
    }
    return IsFinite(xnew_);
  }

 private:
  std::vector<N_Vector*> Vectors() {
    std::vector<N_Vector*> all = {&xnext_, &xnew_, &V0_};
    for (int j = 1; j < d_; ++j) {
      all.push_back(&D_[j]);
      all.push_back(&Dn_[j]);
    }
    return all;
  }

  int d_;
  sunrealtype xi_;
  StepCoeffs co_;
  UpdatePlan plan_;
  SUNContext ctx_ = nullptr;
  N_Vector D_[kMaxDegree] = {};
  N_Vector Dn_[kMaxDegree] = {};
  N_Vector xnext_ = nullptr;
  N_Vector xnew_ = nullptr;
  N_Vector V0_ = nullptr;
  bool ok_ = false;
};

int CheckArgs(int degree, const sunrealtype* params, sunrealtype xi) {
  if (degree < kMinDegree || degree > kMaxDegree || params == nullptr || !(xi >= 0) ||
      !std::isfinite(xi)) {
    return CE_ILL_INPUT;
  }
  // The same check as CEodeSetMethod's, so the analysis and the integrator accept the same sets.
  return ValidateMethodParams(degree, params, nullptr, 0);
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

// The amplification matrix at one Omega, after the checks of the single-point functions.
static int AmplificationAt(int degree, const sunrealtype* params, sunrealtype Omega, sunrealtype xi,
                           const void* out, Eigen::MatrixXd* M) {
  if (ceode::CheckArgs(degree, params, xi) != CE_SUCCESS || out == nullptr || !(Omega >= 0) ||
      !std::isfinite(Omega)) {
    return CE_ILL_INPUT;
  }
  ceode::StepMap map(degree, params, xi);
  return map.ok() && map.Build(Omega, M) ? CE_SUCCESS : CE_ILL_INPUT;
}

static int CEodeAmplificationMatrixImpl(int degree, const sunrealtype* params, sunrealtype Omega,
                                        sunrealtype xi, sunrealtype* A) {
  Eigen::MatrixXd M;
  const int flag = AmplificationAt(degree, params, Omega, xi, A, &M);
  if (flag != CE_SUCCESS) return flag;
  for (int i = 0; i < degree; ++i) {
    for (int j = 0; j < degree; ++j) A[i * degree + j] = M(i, j);
  }
  return CE_SUCCESS;
}

static int CEodeSpectralRadiusImpl(int degree, const sunrealtype* params, sunrealtype Omega,
                                   sunrealtype xi, sunrealtype* rho) {
  Eigen::MatrixXd M;
  const int flag = AmplificationAt(degree, params, Omega, xi, rho, &M);
  if (flag != CE_SUCCESS) return flag;
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
