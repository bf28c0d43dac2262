// Amplification matrices of the classic methods the paper compares with (its
// Figures 4, 7 and 9), applied to the same test equation as CEODE's analysis:
// x'' + 2 xi omega x' + omega^2 x = 0 with step h, Omega = omega h. Each matrix is
// built from the method's own update rule, one unit state at a time, so no
// stability polynomial is typed in by hand.
#ifndef CEODE_TOOLS_CLASSIC_METHODS_HPP_
#define CEODE_TOOLS_CLASSIC_METHODS_HPP_

#include <Eigen/Dense>
#include <string>
#include <vector>

namespace ceode_tools {

// The first-order system y' = J y, y = (x, x'), with h = 1 so that J carries Omega.
inline Eigen::Matrix2d TestJacobian(double Omega, double xi) {
  Eigen::Matrix2d J;
  J << 0, 1, -Omega * Omega, -2 * xi * Omega;
  return J;
}

// One step of an explicit Runge-Kutta method (Butcher tableau a, b) on y' = J y.
inline Eigen::Matrix2d RungeKuttaMatrix(const std::vector<std::vector<double>>& a,
                                        const std::vector<double>& b, double Omega, double xi) {
  const Eigen::Matrix2d J = TestJacobian(Omega, xi);
  Eigen::Matrix2d A;
  for (int col = 0; col < 2; ++col) {
    const Eigen::Vector2d y0 = Eigen::Vector2d::Unit(col);
    std::vector<Eigen::Vector2d> k(b.size());
    Eigen::Vector2d y1 = y0;
    for (size_t i = 0; i < b.size(); ++i) {
      Eigen::Vector2d yi = y0;
      for (size_t j = 0; j < i; ++j) yi += a[i][j] * k[j];
      k[i] = J * yi;
      y1 += b[i] * k[i];
    }
    A.col(col) = y1;
  }
  return A;
}

// Kutta's three-stage method, the RK3 of the paper (c = 0, 1/2, 1).
inline Eigen::MatrixXd Rk3Matrix(double Omega, double xi) {
  return RungeKuttaMatrix({{}, {0.5}, {-1, 2}}, {1.0 / 6, 2.0 / 3, 1.0 / 6}, Omega, xi);
}

// The classic four-stage RK4.
inline Eigen::MatrixXd Rk4Matrix(double Omega, double xi) {
  return RungeKuttaMatrix({{}, {0.5}, {0, 0.5}, {0, 0, 1}}, {1.0 / 6, 1.0 / 3, 1.0 / 3, 1.0 / 6},
                          Omega, xi);
}

// k-step Adams-Bashforth on y' = J y: state (y_n, y_{n-1}, ..., y_{n-k+1}).
inline Eigen::MatrixXd AdamsBashforthMatrix(int k, double Omega, double xi) {
  std::vector<double> beta;
  if (k == 4) {
    beta = {55.0 / 24, -59.0 / 24, 37.0 / 24, -9.0 / 24};
  } else {  // k == 5
    beta = {1901.0 / 720, -2774.0 / 720, 2616.0 / 720, -1274.0 / 720, 251.0 / 720};
  }
  const Eigen::Matrix2d J = TestJacobian(Omega, xi);
  const int n = 2 * k;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
  for (int col = 0; col < n; ++col) {
    const Eigen::VectorXd s = Eigen::VectorXd::Unit(n, col);
    Eigen::Vector2d y1 = s.segment<2>(0);
    for (int j = 0; j < k; ++j) y1 += beta[j] * (J * s.segment<2>(2 * j));
    A.block(0, col, 2, 1) = y1;
    A.block(2, col, n - 2, 1) = s.segment(0, n - 2);  // shift the history
  }
  return A;
}

// HHT-alpha (Hilber, Hughes, Taylor 1977), alpha in [-1/3, 0], with Newmark
// beta = (1 - alpha)^2 / 4, gamma = 1/2 - alpha; state (x, x', x'') and h = 1:
//   a1 + (1 + alpha)(2 xi Omega v1 + Omega^2 x1) - alpha (2 xi Omega v0 + Omega^2 x0) = 0
//   x1 = x0 + v0 + (1/2 - beta) a0 + beta a1,   v1 = v0 + (1 - gamma) a0 + gamma a1
inline Eigen::MatrixXd HhtMatrix(double alpha, double Omega, double xi) {
  const double beta = 0.25 * (1 - alpha) * (1 - alpha);
  const double gamma = 0.5 - alpha;
  const double k = Omega * Omega;
  const double c = 2 * xi * Omega;
  Eigen::Matrix3d L;  // unknowns (x1, v1, a1)
  L << 1, 0, -beta, 0, 1, -gamma, (1 + alpha) * k, (1 + alpha) * c, 1;
  Eigen::Matrix3d R;  // knowns (x0, v0, a0)
  R << 1, 1, 0.5 - beta, 0, 1, 1 - gamma, alpha * k, alpha * c, 0;
  return L.partialPivLu().solve(R);
}

// The comparison methods by name: RK3, RK4, AB4, AB5, HHT (alpha = -0.05) or
// HHT:<alpha>. Returns false for an unknown name.
inline bool ClassicMatrix(const std::string& name, double Omega, double xi, Eigen::MatrixXd* A) {
  if (name == "RK3") {
    *A = Rk3Matrix(Omega, xi);
  } else if (name == "RK4") {
    *A = Rk4Matrix(Omega, xi);
  } else if (name == "AB4") {
    *A = AdamsBashforthMatrix(4, Omega, xi);
  } else if (name == "AB5") {
    *A = AdamsBashforthMatrix(5, Omega, xi);
  } else if (name == "HHT") {
    *A = HhtMatrix(-0.05, Omega, xi);
  } else if (name.rfind("HHT:", 0) == 0) {
    *A = HhtMatrix(std::stod(name.substr(4)), Omega, xi);
  } else {
    return false;
  }
  return true;
}

// f evaluations per step, for the cost-normalised comparison (Omega per evaluation).
inline int ClassicRhsEvals(const std::string& name) {
  if (name == "RK3") return 3;
  if (name == "RK4") return 4;
  return 1;  // AB: one new f per step; HHT: one (linear) solve per step
}

}  // namespace ceode_tools

#endif  // CEODE_TOOLS_CLASSIC_METHODS_HPP_
