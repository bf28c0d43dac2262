// The step of CEODE's method written out by hand on raw doubles, the floor of the per-step cost
// that bench_step and the scenes compare CEODE with: the step's coefficients for any degree and
// the degree-8 update (G8_O8) in the arithmetic of CEODE's update plan.
#ifndef CEODE_BENCH_HAND_STEP_H_
#define CEODE_BENCH_HAND_STEP_H_

#include <cmath>

namespace hand {

constexpr int kMaxD = 8;

// The coefficients of a degree-d set with the parameters p at the step h (docs/theory.md
// section 2.2): D_k(t) = sum_j T[k][j] D_j(t-h) + c[k] z, z from a = D_2(t),
// x(t+h) = x(t) + sum_i w[i] D_i(t) + wz_old z(t-h) + wz_new z.
struct Coeffs {
  double T[kMaxD][kMaxD] = {};
  double c[kMaxD] = {};
  double w[kMaxD] = {};
  double wz_old = 0, wz_new = 0, inv_c2 = 1;
};

inline double Fact(int n) { return n < 2 ? 1.0 : n * Fact(n - 1); }

inline Coeffs MakeCoeffs(int d, const double* p, double h) {
  Coeffs co;
  for (int k = 1; k <= d - 2; ++k) {
    for (int i = 0; i <= d - 2 - k; ++i) co.T[k][k + i] = std::pow(h, i) / Fact(i);
    const double top = std::pow(h, d - 1 - k) / Fact(d - 1 - k);
    co.T[k][d - 1] += top * (1 - p[k]);
    co.c[k] = top * p[k];
  }
  co.c[d - 1] = 1;
  if (d > 3) co.inv_c2 = 1 / co.c[2];
  for (int i = 1; i <= d - 2; ++i) co.w[i] = std::pow(h, i) / Fact(i);
  const double top = std::pow(h, d - 1) / Fact(d - 1);
  co.wz_old = top * (1 - p[0]);
  co.wz_new = top * p[0];
  return co;
}

// The G8_O8 step written out by hand in the arithmetic of CEODE's update plan (docs/theory.md
// section 2.2, src/ceode_method.cpp BuildUpdatePlan): z(t) = (a - B_2) / c_2 as one sum with the
// weights 1/c_2 and -T[2][j]/c_2, each lower derivative D_k(t) = sum_j T[k][j] D_j(t - h) + c_k z
// + D_k(t - h) (the old value added last), and x(t + h) = sum_i w_i D_i(t) + wz_old z(t - h) +
// wz_new z + x(t). f is its own pass; every history vector is updated in place, z
// over D_7 (its old value read first) and a swapped in as D_2. The same products and sums in the
// same order as CEODE's step, so that CEODE's numbers are expected to round-off.
struct D8Weights {
  double z[7];     // a, D_2 .. D_7
  double l[7][8];  // level k: D_{k+1} .. D_7, then z (k = 1, 3 .. 6)
  double x[8];     // D_1 .. D_6 (new), z(t - h), z
};

inline D8Weights MakeD8Weights(const Coeffs& co) {
  D8Weights w{};
  const double c2 = co.c[2];
  w.z[0] = 1 / c2;
  for (int j = 2; j < 8; ++j) w.z[j - 1] = -co.T[2][j] / c2;
  for (int k : {1, 3, 4, 5, 6}) {
    int m = 0;
    for (int j = k + 1; j < 8; ++j) w.l[k][m++] = co.T[k][j];
    w.l[k][m] = co.c[k];
  }
  for (int i = 1; i <= 6; ++i) w.x[i - 1] = co.w[i];
  w.x[6] = co.wz_old;
  w.x[7] = co.wz_new;
  return w;
}

__attribute__((noinline)) inline void D8Update(const D8Weights& w, const double* __restrict a,
                                               double* __restrict d1, const double* __restrict d2,
                                               double* __restrict d3, double* __restrict d4,
                                               double* __restrict d5, double* __restrict d6,
                                               double* __restrict d7, double* __restrict x,
                                               long n) {
  for (long i = 0; i < n; ++i) {
    const double o2 = d2[i], o3 = d3[i], o4 = d4[i], o5 = d5[i], o6 = d6[i], o7 = d7[i];
    const double z = w.z[0] * a[i] + w.z[1] * o2 + w.z[2] * o3 + w.z[3] * o4 + w.z[4] * o5 +
                     w.z[5] * o6 + w.z[6] * o7;
    const double n1 = w.l[1][0] * o2 + w.l[1][1] * o3 + w.l[1][2] * o4 + w.l[1][3] * o5 +
                      w.l[1][4] * o6 + w.l[1][5] * o7 + w.l[1][6] * z + d1[i];
    const double n3 =
        w.l[3][0] * o4 + w.l[3][1] * o5 + w.l[3][2] * o6 + w.l[3][3] * o7 + w.l[3][4] * z + o3;
    const double n4 = w.l[4][0] * o5 + w.l[4][1] * o6 + w.l[4][2] * o7 + w.l[4][3] * z + o4;
    const double n5 = w.l[5][0] * o6 + w.l[5][1] * o7 + w.l[5][2] * z + o5;
    const double n6 = w.l[6][0] * o7 + w.l[6][1] * z + o6;
    x[i] = w.x[0] * n1 + w.x[1] * a[i] + w.x[2] * n3 + w.x[3] * n4 + w.x[4] * n5 + w.x[5] * n6 +
           w.x[6] * o7 + w.x[7] * z + x[i];
    d1[i] = n1;
    d3[i] = n3;
    d4[i] = n4;
    d5[i] = n5;
    d6[i] = n6;
    d7[i] = z;
  }
}

}  // namespace hand

#endif  // CEODE_BENCH_HAND_STEP_H_
