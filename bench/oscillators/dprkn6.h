// -----------------------------------------------------------------------------
// dprkn6.h: DPRKN6, the Dormand-Prince Runge-Kutta-Nystrom pair of orders 6 and 4 for
// x'' = g(t, x) (no velocity dependence), 6 stages with the last one evaluated at the new
// position (first same as last: 5 new g evaluations per accepted step), as a reference
// adaptive Nystrom integrator of the work-precision scenes.
//
// Source of the tableau: J. R. Dormand and P. J. Prince, "Runge-Kutta-Nystrom triples",
// Computers & Mathematics with Applications 13 (1987) 937-949 (the 6(4) pair with a free
// interpolant, exact coefficients in R = sqrt(8581)), the pair OrdinaryDiffEq.jl ships as
// DPRKN6; the family goes back to Dormand and Prince, "New Runge-Kutta algorithms for numerical
// simulation in dynamical astronomy", Celestial Mechanics 18 (1978) 223-232, and E. Hairer,
// S. P. Norsett and G. Wanner, "Solving Ordinary Differential Equations I", section II.14, set
// out the Nystrom order conditions these weights satisfy.
//
// Step (h, stages k_i = g(t + c_i h, X_i)):
//   X_i     = x + c_i h v + h^2 sum_j a_ij k_j
//   x_new   = x + h v + h^2 sum_j b_j k_j       (= X_6: row 6 of a is b)
//   v_new   = v + h sum_j bp_j k_j
//   err_x   = h^2 sum_j e_j k_j, err_v = h sum_j ep_j k_j   (e = b - b_hat, ep = bp - bp_hat)
// Control: the error's RMS norm over (x, v) with scale atol + rtol max(|y_old|, |y_new|), the
// step factor safety * err^(-1/5) (the embedded pair is of order 4) clamped to
// [fac_min, fac_max], no growth right after a rejection; the starting step of Hairer, Norsett
// and Wanner I, section II.4 (one extra g evaluation) unless Options::h0 is given.
// -----------------------------------------------------------------------------
#ifndef CEODE_BENCH_DPRKN6_H_
#define CEODE_BENCH_DPRKN6_H_

#include <algorithm>
#include <cmath>
#include <vector>

namespace dprkn6 {

constexpr int kStages = 6;

struct Tableau {
  double c[kStages];
  double a[kStages][kStages];
  double b[kStages], bp[kStages];  // position and velocity weights of the 6th-order solution
  double e[kStages], ep[kStages];  // their differences to the 4th-order embedded weights
};

inline Tableau MakeTableau() {
  const double R = std::sqrt(8581.0);
  Tableau t = {};
  const double c[kStages] = {0.0, (209 - R) / 900, (209 - R) / 450, (209 + R) / 450, 0.9, 1.0};
  std::copy(c, c + kStages, t.c);
  t.a[1][0] = (26131 - 209 * R) / 810000;
  t.a[2][0] = (26131 - 209 * R) / 607500;
  t.a[2][1] = (26131 - 209 * R) / 303750;
  t.a[3][0] = (980403512254 + 7781688431 * R) / 11694469921875;
  t.a[3][1] = -(1262884486208 + 15385481287 * R) / 11694469921875;
  t.a[3][2] = (7166233891441 + 78694563299 * R) / 46777879687500;
  t.a[4][0] = -9 * (329260 + 3181 * R) / 27040000;
  t.a[4][1] = 27 * (35129 + 3331 * R) / 13520000;
  t.a[4][2] = -27 * (554358343 + 31040327 * R) / 464060480000;
  t.a[4][3] = 153 * (8555257 - 67973 * R) / 2745920000;
  t.a[5][0] = 329.0 / 4212;
  t.a[5][1] = 0;
  t.a[5][2] = (84119543 + 366727 * R) / 409622616;
  t.a[5][3] = (84119543 - 366727 * R) / 409622616;
  t.a[5][4] = 200.0 / 17901;
  for (int j = 0; j < kStages; ++j) t.b[j] = t.a[5][j];
  const double bp[kStages] = {329.0 / 4212,
                              0,
                              (389225579 + 96856 * R) / 1024056540,
                              (389225579 - 96856 * R) / 1024056540,
                              2000.0 / 17901,
                              1.0 / 20};
  std::copy(bp, bp + kStages, t.bp);
  // The embedded position weights use stages 1-3 only, so e_4 = b_4, e_5 = b_5, e_6 = 0.
  t.e[0] = 329.0 / 4212 - (2701 + 23 * R) / 4563;
  t.e[1] = (9829 + 131 * R) / 9126;
  t.e[2] = t.b[2] - 5 * (1798 + 17 * R) / 9126;
  t.e[3] = t.b[3];
  t.e[4] = t.b[4];
  t.e[5] = 0;
  t.ep[0] = 329.0 / 4212 - 115.0 / 2106;
  t.ep[1] = 0;
  t.ep[2] = t.bp[2] - (84119543 + 366727 * R) / 256014135;
  t.ep[3] = t.bp[3] - (84119543 - 366727 * R) / 256014135;
  t.ep[4] = 2000.0 / 17901 - 6950.0 / 17901;
  t.ep[5] = 1.0 / 20 + 1.0 / 10;
  return t;
}

// Computed once (the coefficients involve sqrt, which is not constexpr).
inline const Tableau& Coefficients() {
  static const Tableau t = MakeTableau();
  return t;
}

struct Options {
  double rtol = 1e-6, atol = 1e-6;
  double h0 = 0;  // first trial step; 0: the starting-step rule of the header comment
  double safety = 0.9, fac_min = 0.2, fac_max = 5.0;
  long max_steps = 100000000L;
};

struct Stats {
  long steps = 0, rejected = 0, evals = 0;
};

// The working vectors of one integration: stages, trial state and error estimate.
class Stepper {
 public:
  explicit Stepper(int n) : n_(n), k_(kStages * n), xs_(n), xn_(n), vn_(n), ex_(n), ev_(n) {}

  double* K(int i) { return k_.data() + static_cast<size_t>(i) * n_; }
  const double* XNew() const { return xn_.data(); }
  const double* VNew() const { return vn_.data(); }
  const double* ErrX() const { return ex_.data(); }
  const double* ErrV() const { return ev_.data(); }

  // One trial step from (t, x, v) with K(0) = g(t, x) given: fills XNew, VNew, ErrX, ErrV and
  // K(5) = g(t + h, XNew) (the next step's K(0) when the step is accepted). Returns acc's flag.
  template <class Acc>
  int Trial(Acc& acc, double t, const double* x, const double* v, double h, Stats* st) {
    const Tableau& tb = Coefficients();
    const double h2 = h * h;
    for (int i = 1; i < kStages; ++i) {
      double* X = i + 1 < kStages ? xs_.data() : xn_.data();
      for (int m = 0; m < n_; ++m) {
        double s = 0;
        for (int j = 0; j < i; ++j) s += tb.a[i][j] * K(j)[m];
        X[m] = x[m] + tb.c[i] * h * v[m] + h2 * s;
      }
      ++st->evals;
      const int flag = acc(t + tb.c[i] * h, X, K(i));
      if (flag != 0) return flag;
    }
    for (int m = 0; m < n_; ++m) {
      double sv = 0, se = 0, sep = 0;
      for (int j = 0; j < kStages; ++j) {
        const double kj = K(j)[m];
        sv += tb.bp[j] * kj;
        se += tb.e[j] * kj;
        sep += tb.ep[j] * kj;
      }
      vn_[m] = v[m] + h * sv;
      ex_[m] = h2 * se;
      ev_[m] = h * sep;
    }
    return 0;
  }

  // The RMS norm of the error estimate over (x, v), scaled by atol + rtol max(|old|, |new|).
  double ErrorNorm(const double* x, const double* v, const Options& o) const {
    double s = 0;
    for (int m = 0; m < n_; ++m) {
      const double sx = o.atol + o.rtol * std::max(std::fabs(x[m]), std::fabs(xn_[m]));
      const double sv = o.atol + o.rtol * std::max(std::fabs(v[m]), std::fabs(vn_[m]));
      s += (ex_[m] / sx) * (ex_[m] / sx) + (ev_[m] / sv) * (ev_[m] / sv);
    }
    return std::sqrt(s / (2 * n_));
  }

  // Moves the accepted trial state into (x, v) and K(5) into K(0).
  void Accept(double* x, double* v) {
    std::copy(xn_.begin(), xn_.end(), x);
    std::copy(vn_.begin(), vn_.end(), v);
    std::copy(K(kStages - 1), K(kStages - 1) + n_, K(0));
  }

 private:
  int n_;
  std::vector<double> k_, xs_, xn_, vn_, ex_, ev_;
};

// The starting step (Hairer, Norsett, Wanner I, II.4) for the first-order form y = (x, v),
// y' = (v, g), order 6; uses K(0) = g(t0, x) and one more g evaluation.
template <class Acc>
double StartingStep(Acc& acc, int n, double t0, const double* x, const double* v, const double* a0,
                    const Options& o, Stats* st, int* flag) {
  double d0 = 0, d1 = 0;
  for (int m = 0; m < n; ++m) {
    const double sx = o.atol + o.rtol * std::fabs(x[m]);
    const double sv = o.atol + o.rtol * std::fabs(v[m]);
    d0 += (x[m] / sx) * (x[m] / sx) + (v[m] / sv) * (v[m] / sv);
    d1 += (v[m] / sx) * (v[m] / sx) + (a0[m] / sv) * (a0[m] / sv);
  }
  d0 = std::sqrt(d0 / (2 * n));
  d1 = std::sqrt(d1 / (2 * n));
  const double h0 = d0 < 1e-5 || d1 < 1e-5 ? 1e-6 : 0.01 * d0 / d1;
  std::vector<double> x1(n), v1(n), a1(n);
  for (int m = 0; m < n; ++m) {
    x1[m] = x[m] + h0 * v[m];
    v1[m] = v[m] + h0 * a0[m];
  }
  ++st->evals;
  *flag = acc(t0 + h0, x1.data(), a1.data());
  double d2 = 0;
  for (int m = 0; m < n; ++m) {
    const double sx = o.atol + o.rtol * std::fabs(x[m]);
    const double sv = o.atol + o.rtol * std::fabs(v[m]);
    const double dx = (v1[m] - v[m]) / sx, dv = (a1[m] - a0[m]) / sv;
    d2 += dx * dx + dv * dv;
  }
  d2 = std::sqrt(d2 / (2 * n)) / h0;
  const double dm = std::max(d1, d2);
  const double h1 = dm <= 1e-15 ? std::max(1e-6, 1e-3 * h0) : std::pow(0.01 / dm, 1.0 / 6);
  return std::min(100 * h0, h1);
}

// Adaptive integration of x'' = acc(t, x) from t0 to tend (the last step lands on tend);
// x, v hold the start and receive the end. acc(t, x, a) returns 0 on success;
// observe(t, x, v) is called after every accepted step. Returns 0 on success, 1 when acc
// failed, the step underflowed or max_steps was reached.
template <class Acc, class Obs>
int Integrate(int n, Acc&& acc, double t0, double tend, double* x, double* v, const Options& o,
              Obs&& observe, Stats* st) {
  Stepper s(n);
  ++st->evals;
  if (acc(t0, x, s.K(0)) != 0) return 1;
  int flag = 0;
  double h = o.h0 > 0 ? o.h0 : StartingStep(acc, n, t0, x, v, s.K(0), o, st, &flag);
  if (flag != 0) return 1;
  double t = t0;
  bool rejected_last = false;
  while (t < tend) {
    if (st->steps >= o.max_steps) return 1;
    const bool last = t + h * (1 + 1e-10) >= tend;  // no sliver of a last step
    if (last) h = tend - t;
    if (!(h > 1e-14 * std::max(1.0, std::fabs(t)))) return 1;  // step underflow
    if (s.Trial(acc, t, x, v, h, st) != 0) return 1;
    const double err = s.ErrorNorm(x, v, o);
    const double fac = std::isfinite(err) ? o.safety * std::pow(std::max(err, 1e-12), -0.2) : 0;
    if (err <= 1) {
      t = last ? tend : t + h;
      s.Accept(x, v);
      ++st->steps;
      observe(t, x, v);
      h *= std::min(rejected_last ? 1.0 : o.fac_max, std::max(o.fac_min, fac));
      rejected_last = false;
    } else {
      ++st->rejected;
      h *= std::min(1.0, std::max(o.fac_min, fac));
      rejected_last = true;
    }
  }
  return 0;
}

// `steps` fixed steps of h from t0 (the order check); observe(t, x, v) after every step.
template <class Acc, class Obs>
int IntegrateFixed(int n, Acc&& acc, double t0, double h, long steps, double* x, double* v,
                   Obs&& observe, Stats* st) {
  Stepper s(n);
  ++st->evals;
  if (acc(t0, x, s.K(0)) != 0) return 1;
  for (long i = 0; i < steps; ++i) {
    const double t = t0 + static_cast<double>(i) * h;
    if (s.Trial(acc, t, x, v, h, st) != 0) return 1;
    s.Accept(x, v);
    ++st->steps;
    observe(t0 + static_cast<double>(i + 1) * h, x, v);
  }
  return 0;
}

}  // namespace dprkn6

#endif  // CEODE_BENCH_DPRKN6_H_
