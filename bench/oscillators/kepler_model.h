// SUNDIALS' Kepler problem (examples/arkode/C_serial/ark_kepler.c), shared by the Kepler scenes
// (wp_kepler, wp_events): q'' = -q / |q|^3 in the plane, eccentricity e = 0.6, from the
// pericentre q = (1 - e, 0), q' = (0, sqrt((1 + e) / (1 - e))), period 2 pi.
#ifndef CEODE_BENCH_OSCILLATORS_KEPLER_MODEL_H_
#define CEODE_BENCH_OSCILLATORS_KEPLER_MODEL_H_

#include <cmath>

namespace kepler {

constexpr double kEcc = 0.6;

// The user data: counts every f evaluation, whoever asks for it.
struct Kepler {
  long evals = 0;
};

inline int Acc(double, const double* x, const double*, double* a, void* user) {
  ++static_cast<Kepler*>(user)->evals;
  const double r2 = x[0] * x[0] + x[1] * x[1];
  const double ir3 = 1 / (r2 * std::sqrt(r2));
  a[0] = -x[0] * ir3;
  a[1] = -x[1] * ir3;
  return 0;
}

inline double Energy(const double* x, const double* v) {
  return 0.5 * (v[0] * v[0] + v[1] * v[1]) - 1 / std::hypot(x[0], x[1]);
}

// The exact state at time t from the pericentre (Kepler's equation by Newton, mean motion 1).
inline void Exact(double t, double* x, double* v) {
  double E = t;
  for (int i = 0; i < 60; ++i) E -= (E - kEcc * std::sin(E) - t) / (1 - kEcc * std::cos(E));
  const double s = std::sqrt(1 - kEcc * kEcc), dE = 1 / (1 - kEcc * std::cos(E));
  x[0] = std::cos(E) - kEcc;
  x[1] = s * std::sin(E);
  v[0] = -std::sin(E) * dE;
  v[1] = s * std::cos(E) * dE;
}

}  // namespace kepler

#endif  // CEODE_BENCH_OSCILLATORS_KEPLER_MODEL_H_
