// -----------------------------------------------------------------------------
// fe_plate_modes.h: the lowest vibration modes of the FE plate (bench/fe_plate_model.h)
// and the closed-form modal response with Rayleigh damping, for the reference
// solutions of the plate scenes (bench/fe_plate/wp_fe_*.cpp).
//
// Modes: subspace iteration (block of 6, 60 sweeps) with a sparse LDL^T of K and
// Rayleigh-Ritz on (K, M), M the lumped masses; the residual ||K phi - w^2 M phi|| /
// ||K phi|| of each returned mode is reported so that the scene can check it.
// Damped response: C = a M + b K keeps the modes decoupled (phi^T C phi = a + b w^2
// for M-normalised phi), so each mode is a damped oscillator with zeta = a / (2 w) +
// b w / 2, solved in closed form.
// -----------------------------------------------------------------------------
#ifndef CEODE_BENCH_FE_PLATE_MODES_H_
#define CEODE_BENCH_FE_PLATE_MODES_H_

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <cmath>
#include <vector>

#include "fe_plate_model.h"

namespace fe {

struct Modes {
  std::vector<double> w;                 // circular frequencies, ascending
  std::vector<std::vector<double>> phi;  // mode shapes, scaled to max |.| = 1
  double residual = 0;                   // largest relative residual of the returned modes
};

inline Eigen::SparseMatrix<double> StiffnessSparse(const Plate& p) {
  std::vector<Eigen::Triplet<double>> tr;
  tr.reserve(p.val.size());
  for (int r = 0; r < p.n; ++r) {
    for (int k = p.rowptr[r]; k < p.rowptr[r + 1]; ++k) tr.emplace_back(r, p.col[k], p.val[k]);
  }
  Eigen::SparseMatrix<double> K(p.n, p.n);
  K.setFromTriplets(tr.begin(), tr.end());
  return K;
}

// The `count` (<= 6) lowest modes of K phi = w^2 M phi.
inline Modes LowestModes(const Plate& p, int count) {
  using SpMat = Eigen::SparseMatrix<double>;
  const SpMat K = StiffnessSparse(p);
  Eigen::SimplicialLDLT<SpMat> ldlt(K);
  const Eigen::Map<const Eigen::VectorXd> m(p.mass.data(), p.n);
  const int b = 6;
  Eigen::MatrixXd X = Eigen::MatrixXd::Random(p.n, b);
  Eigen::VectorXd lam;
  for (int it = 0; it < 60; ++it) {
    const Eigen::MatrixXd Y = ldlt.solve(m.asDiagonal() * X);
    const Eigen::MatrixXd Kr = Y.transpose() * (K * Y);
    const Eigen::MatrixXd Mr = Y.transpose() * m.asDiagonal() * Y;
    Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(Kr, Mr);
    X = Y * es.eigenvectors();
    lam = es.eigenvalues();
  }
  Modes md;
  for (int j = 0; j < count; ++j) {
    const Eigen::VectorXd kx = K * X.col(j);
    md.residual =
        std::max(md.residual, (kx - lam(j) * (m.asDiagonal() * X.col(j))).norm() / kx.norm());
    md.w.push_back(std::sqrt(lam(j)));
    std::vector<double> v(X.col(j).data(), X.col(j).data() + p.n);
    double mx = 0;
    for (double q : v) mx = std::max(mx, std::fabs(q));
    for (double& q : v) q /= mx;
    md.phi.push_back(v);
  }
  return md;
}

// q(t) / q(0) of one mode with damping ratio zeta < 1 that starts at rest.
inline double DampedModeResponse(double w, double zeta, double t) {
  const double wd = w * std::sqrt(1 - zeta * zeta);
  return std::exp(-zeta * w * t) * (std::cos(wd * t) + zeta * w / wd * std::sin(wd * t));
}

// Rayleigh damping ratio of a mode of circular frequency w.
inline double RayleighZeta(const Plate& p, double w) {
  return p.damp_m / (2 * w) + p.damp_k * w / 2;
}

}  // namespace fe

#endif  // CEODE_BENCH_FE_PLATE_MODES_H_
