// -----------------------------------------------------------------------------
// top_model.h: the heavy symmetric top with a fixed tip in ZXZ Euler angles q = (psi, theta,
// phi) (the equations in wp_spinning_top.cpp), its acceleration and energy, shared by
// wp_spinning_top and ../step_cost/bench_implicit_step.
// -----------------------------------------------------------------------------
#ifndef CEODE_BENCH_TOP_MODEL_H_
#define CEODE_BENCH_TOP_MODEL_H_

#include <cmath>

namespace top {

struct Top {
  double I1 = 5e-5, I3 = 2e-4, m = 0.02, l = 0.05, g = 9.81;
  double e0 = 0;  // energy at t = 0
};

inline double Energy(const Top& p, const double* q, const double* w) {
  const double s = std::sin(q[1]), c = std::cos(q[1]);
  const double w3 = w[2] + w[0] * c;
  return 0.5 * p.I1 * (w[1] * w[1] + w[0] * w[0] * s * s) + 0.5 * p.I3 * w3 * w3 +
         p.m * p.g * p.l * c;
}

// Accelerations (psi'', theta'', phi'') from angles q and rates w.
inline int Accel(double, const double* q, const double* w, double* a, void* user) {
  const Top& p = *static_cast<Top*>(user);
  const double s = std::sin(q[1]), c = std::cos(q[1]);
  const double w3 = w[2] + w[0] * c;
  const double psi_dd = w[1] * (p.I3 * w3 - 2 * p.I1 * w[0] * c) / (p.I1 * s);
  a[1] = w[0] * w[0] * s * c - (p.I3 / p.I1) * w3 * w[0] * s + (p.m * p.g * p.l / p.I1) * s;
  a[0] = psi_dd;
  a[2] = -psi_dd * c + w[0] * w[1] * s;
  return 0;
}

}  // namespace top

#endif  // CEODE_BENCH_TOP_MODEL_H_
