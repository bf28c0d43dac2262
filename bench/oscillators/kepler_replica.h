// A reference driver of CEODE's explicit fixed step on the Kepler problem in an extended
// floating-point type R (long double): the update of docs/theory.md section 2 with the library's
// coefficients and its sums in the library's order, started either as the library starts
// (central differences / Picard sweeps of the acceleration, src/ceode_start.cpp) or from the
// exact derivatives of the orbit (its Taylor series). Its round-off is 2048 times smaller than a
// double run's, so its error against the exact orbit is the method's truncation, and the double
// run's distance from it is round-off; rounding one chosen quantity to double (Rounded) shows
// which operation of the double run injects it (wp_kepler_long).
#ifndef CEODE_BENCH_OSCILLATORS_KEPLER_REPLICA_H_
#define CEODE_BENCH_OSCILLATORS_KEPLER_REPLICA_H_

#include <algorithm>
#include <cmath>

#include "kepler_model.h"

namespace kepler {

constexpr int kMaxD = 8;

template <class R>
inline R Sqrt(R x) {
  using std::sqrt;
  return sqrt(x);
}

// a = -x / |x|^3 with kepler::Acc's operations.
template <class R>
inline void AccR(const R* x, R* a) {
  const R r2 = x[0] * x[0] + x[1] * x[1];
  const R ir3 = R(1) / (r2 * Sqrt(r2));
  a[0] = -x[0] * ir3;
  a[1] = -x[1] * ir3;
}

// The derivatives D_k = x^(k)(0), k < m, of the orbit from the pericentre: its Taylor series by
// the recurrences of u = |x|^2, w = u^(-3/2) and x'' = -x w.
template <class R>
void ExactDerivatives(int m, R (*D)[2]) {
  R xc[2][kMaxD + 2], u[kMaxD + 2], w[kMaxD + 2];
  xc[0][0] = R(1 - kEcc);  // the initial state as the double program holds it
  xc[1][0] = 0;
  xc[0][1] = 0;
  xc[1][1] = R(std::sqrt((1 + kEcc) / (1 - kEcc)));
  for (int k = 0; k + 2 < m; ++k) {
    u[k] = 0;
    for (int i = 0; i <= k; ++i) u[k] += xc[0][i] * xc[0][k - i] + xc[1][i] * xc[1][k - i];
    if (k == 0) {
      w[0] = R(1) / (u[0] * Sqrt(u[0]));
    } else {
      R s = 0;  // k u0 w_k = sum_j ((alpha + 1) j - k) u_j w_(k-j), alpha = -3/2
      for (int j = 1; j <= k; ++j) s += (R(-0.5) * j - k) * u[j] * w[k - j];
      w[k] = s / (k * u[0]);
    }
    for (int c = 0; c < 2; ++c) {
      R a = 0;
      for (int i = 0; i <= k; ++i) a -= xc[c][i] * w[k - i];
      xc[c][k + 2] = a / R((k + 1) * (k + 2));
    }
  }
  R fact = 1;
  for (int k = 0; k < m; ++k) {
    if (k > 0) fact *= k;
    D[k][0] = xc[0][k] * fact;
    D[k][1] = xc[1][k] * fact;
  }
}

// The exact position at time t on the orbit through the initial state the double programs hold,
// x0 = 1 - e and v0 = sqrt((1 + e) / (1 - e)) rounded to double (its energy differs from -1/2 by
// 1.4e-16, which moves x(2000 pi) by 5e-12 from x0), in long double from its elements.
inline void ExactAt(long double t, long double* x) {
  const long double x0 = 1 - kEcc, v0 = std::sqrt((1 + kEcc) / (1 - kEcc));
  const long double energy = v0 * v0 / 2 - 1 / x0;
  const long double a = -1 / (2 * energy), e = 1 - x0 / a;
  const long double n = 1 / (a * std::sqrt(a));  // mean motion
  const long double two_pi = 6.283185307179586476925286766559005768L;
  const long double M = n * t;
  const long double k = std::floor(M / two_pi + 0.5L);
  const long double tau = M - k * two_pi;
  long double E = tau;
  for (int i = 0; i < 80; ++i) E -= (E - e * std::sin(E) - tau) / (1 - e * std::cos(E));
  x[0] = a * (std::cos(E) - e);
  x[1] = a * std::sqrt(1 - e * e) * std::sin(E);
}

// Which quantities an extended-precision run rounds to double (Replica::rounded): one at a time
// they tell which operation of the double run injects the round-off that matters.
enum Rounded : unsigned {
  kFInput = 1,         // f reads x rounded to double
  kFOutput = 2,        // the acceleration f returns
  kTop = 4,            // the recovered top derivative z
  kPosition = 8,       // x(t + h) as stored (no compensation)
  kVelocity = 16,      // D_1 as stored (no compensation)
  kHigher = 32,        // D_3 .. D_{d-2} as stored (no compensation)
  kCoefficients = 64,  // the step's weights
  kPositionSum = 128,  // the position increment: products and partial sums in double
  kVelocitySum = 256,  // the velocity increment: products and partial sums in double
};

template <class R>
inline R ToDouble(R v) {
  return R(static_cast<double>(v));
}

template <class R>
class Replica {
 public:
  // The method (degree d, parameters p as the library holds them, in double), step h (double).
  Replica(int d, const double* p, double h, unsigned rounded = 0) : d_(d), rounded_(rounded) {
    h_ = R(h);
    R tw[kMaxD + 1] = {};
    R fact = 1;
    for (int i = 0; i <= d; ++i) {  // h^i / i!
      if (i > 1) fact *= i;
      R pw = 1;
      for (int j = 0; j < i; ++j) pw *= h_;
      tw[i] = i == 0 ? R(1) : (i == 1 ? h_ : pw / fact);
    }
    for (int k = 1; k <= d - 2; ++k) {
      for (int i = 0; i <= d - 2 - k; ++i) T_[k][k + i] = tw[i];
      const R top = tw[d - 1 - k];
      T_[k][d - 1] += top * (R(1) - R(p[k]));
      c_[k] = top * R(p[k]);
    }
    if (d == 3) c_[2] = 1;
    for (int i = 1; i <= d - 2; ++i) w_[i] = tw[i];
    wz_old_ = tw[d - 1] * (R(1) - R(p[0]));
    wz_new_ = tw[d - 1] * R(p[0]);
    std::copy(tw, tw + d, twc_);
    if (rounded_ & kCoefficients) RoundCoefficients();
  }

  // exact: the derivatives of the orbit; otherwise the library's start (ceode_start.cpp).
  void Start(bool exact) {
    R E[kMaxD][2];
    ExactDerivatives<R>(d_, E);
    for (int c = 0; c < 2; ++c) {
      x_[c] = E[0][c];
      for (int k = 1; k < d_; ++k) D_[k][c] = exact || k <= 1 ? E[k][c] : R(0);
    }
    if (!exact) {
      AccR(x_, D_[2]);  // a0 from f, as the library
      if (d_ >= 6) {
        StartHigh();
      } else {
        StartLow();
      }
    }
    for (int c = 0; c < 2; ++c) {
      R inc = twc_[1] * D_[1][c];
      for (int i = 2; i < d_; ++i) inc += twc_[i] * D_[i][c];
      xn_[c] = x_[c] + inc;
    }
  }

  // One step: a = f(x(t + h)), the derivatives at t + h and x(t + 2h), the sums in the
  // library's order (BuildUpdatePlan).
  void Step() {
    R a[2];
    R xf[2] = {xn_[0], xn_[1]};
    if (rounded_ & kFInput) xf[0] = ToDouble(xf[0]), xf[1] = ToDouble(xf[1]);
    AccR(xf, a);
    if (rounded_ & kFOutput) a[0] = ToDouble(a[0]), a[1] = ToDouble(a[1]);
    const int d = d_;
    for (int c = 0; c < 2; ++c) {
      R z = a[c];
      if (d > 3) {
        z = (R(1) / c_[2]) * a[c];
        for (int j = 2; j < d; ++j) z += (-T_[2][j] / c_[2]) * D_[j][c];
      }
      if (rounded_ & kTop) z = ToDouble(z);
      R Dn[kMaxD];
      for (int k = 1; k <= d - 2; ++k) {
        if (k == 2) continue;
        Sum s(k == 1 && (rounded_ & kVelocitySum));
        for (int j = k + 1; j < d; ++j) s.Add(T_[k][j], D_[j][c]);
        s.Add(c_[k], z);
        Dn[k] = s.value + D_[k][c];
        if ((k == 1 && (rounded_ & kVelocity)) || (k > 2 && (rounded_ & kHigher))) {
          Dn[k] = ToDouble(Dn[k]);
        }
      }
      Sum s((rounded_ & kPositionSum) != 0);
      for (int i = 1; i <= d - 2; ++i) s.Add(w_[i], i == 2 ? a[c] : Dn[i]);
      s.Add(wz_old_, D_[d - 1][c]);
      s.Add(wz_new_, z);
      R xnew = s.value + xn_[c];
      if (rounded_ & kPosition) xnew = ToDouble(xnew);
      for (int k = 1; k <= d - 2; ++k) D_[k][c] = k == 2 ? a[c] : Dn[k];
      D_[d - 1][c] = z;
      x_[c] = xn_[c];
      xn_[c] = xnew;
    }
  }

  const R* X() const { return x_; }  // x(t)
  const R* V() const { return D_[1]; }

 private:
  // A sum of products in R, or with every product and partial sum rounded to double.
  struct Sum {
    explicit Sum(bool in_double) : dbl(in_double) {}
    void Add(R c, R v) {
      if (c == R(0)) return;
      if (dbl) {
        const double cv = static_cast<double>(c) * static_cast<double>(v);
        value = R(first ? cv : static_cast<double>(value) + cv);
      } else {
        value = first ? c * v : value + c * v;
      }
      first = false;
    }
    bool dbl;
    bool first = true;
    R value = 0;
  };
  void RoundCoefficients() {
    for (int k = 0; k < kMaxD; ++k) {
      for (int j = 0; j < kMaxD; ++j) T_[k][j] = ToDouble(T_[k][j]);
      c_[k] = ToDouble(c_[k]);
      w_[k] = ToDouble(w_[k]);
    }
    wz_old_ = ToDouble(wz_old_);
    wz_new_ = ToDouble(wz_new_);
  }
  // Weights of the q-th derivative on nodes x (Fornberg), every order up to q.
  static void Fornberg(int q, int m, const R* x, R (*w)[2 * kMaxD + 1]) {
    R C[2 * kMaxD + 1][kMaxD] = {};
    C[0][0] = 1;
    R c1 = 1;
    for (int i = 1; i < m; ++i) {
      R c2 = 1;
      const int mn = std::min(i, q);
      for (int j = 0; j < i; ++j) {
        const R c3 = x[i] - x[j];
        c2 *= c3;
        for (int k = mn; k >= 0; --k) {
          if (j == i - 1) {
            C[i][k] = c1 / c2 * ((k > 0 ? k * C[i - 1][k - 1] : R(0)) - x[i - 1] * C[i - 1][k]);
          }
        }
        for (int k = mn; k >= 0; --k)
          C[j][k] = (x[i] * C[j][k] - (k > 0 ? k * C[j][k - 1] : R(0))) / c3;
      }
      c1 = c2;
    }
    for (int k = 0; k <= q; ++k) {
      for (int i = 0; i < m; ++i) w[k][i] = C[i][k];
    }
  }
  void StartLow() {
    for (int m = 2; m <= d_ - 2; ++m) {
      const int q = m - 1, r = (q + 1) / 2, npts = 2 * r + 1;
      R nodes[2 * kMaxD + 1], wts[kMaxD][2 * kMaxD + 1];
      for (int j = 0; j < npts; ++j) nodes[j] = R(j - r) * h_;
      Fornberg(q, npts, nodes, wts);
      R out[2] = {wts[q][r] * D_[2][0], wts[q][r] * D_[2][1]};
      for (int j = 0; j < npts; ++j) {
        if (j == r || wts[q][j] == R(0)) continue;
        R cx[kMaxD + 1];
        for (int i = 0; i <= m; ++i) {
          R pw = 1, f = 1;
          for (int l = 1; l <= i; ++l) pw *= nodes[j], f *= l;
          cx[i] = i == 0 ? R(1) : (i == 1 ? nodes[j] : pw / f);
        }
        R xs[2], as[2];
        for (int c = 0; c < 2; ++c) {
          xs[c] = cx[0] * x_[c];
          for (int i = 1; i <= m; ++i) xs[c] += cx[i] * D_[i][c];
        }
        AccR(xs, as);
        for (int c = 0; c < 2; ++c) out[c] = out[c] + wts[q][j] * as[c];
      }
      D_[m + 1][0] = out[0];
      D_[m + 1][1] = out[1];
    }
  }
  void StartHigh() {
    const int d = d_, Rh = d / 2, npts = 2 * Rh + 1;
    R nodes[2 * kMaxD + 1], wts[kMaxD][2 * kMaxD + 1];
    for (int j = 0; j < npts; ++j) nodes[j] = R(j - Rh) * h_;
    Fornberg(d - 3, npts, nodes, wts);
    for (int k = 3; k < d; ++k) D_[k][0] = D_[k][1] = 0;
    const int sweeps = std::min(d - 3, Rh);
    R sample[2 * kMaxD][2];
    for (int sw = 0; sw < sweeps; ++sw) {
      for (int j = 0; j < 2 * Rh; ++j) {
        const R s = nodes[j < Rh ? j : j + 1];
        R xs[2];
        for (int c = 0; c < 2; ++c) {
          R wgt = 1, acc = 0;
          for (int i = 0; i < d; ++i) {
            const R v = i == 0 ? x_[c] : D_[i][c];
            acc = i == 0 ? wgt * v : acc + wgt * v;
            wgt *= s / R(i + 1);
          }
          xs[c] = acc;
        }
        AccR(xs, sample[j]);
      }
      for (int k = 3; k < d; ++k) {
        for (int c = 0; c < 2; ++c) {
          R acc = wts[k - 2][Rh] * D_[2][c];
          for (int j = 0; j < npts; ++j) {
            if (j != Rh) acc += wts[k - 2][j] * sample[j < Rh ? j : j - 1][c];
          }
          D_[k][c] = acc;
        }
      }
    }
  }

  int d_;
  unsigned rounded_;
  R h_;
  R T_[kMaxD][kMaxD] = {};
  R c_[kMaxD] = {};
  R w_[kMaxD] = {};
  R wz_old_ = 0, wz_new_ = 0;
  R twc_[kMaxD + 1] = {};
  R x_[2] = {}, xn_[2] = {};
  R D_[kMaxD][2] = {};
};

}  // namespace kepler

#endif  // CEODE_BENCH_OSCILLATORS_KEPLER_REPLICA_H_
