// Order conditions of the degree-d step (docs/theory.md section 9.4).
//
// The step is a linear recurrence in the sequences x_n, D_1,n ... D_{d-1},n once
// the acceleration a_n is given. Insert the exponential solution of x'' = s^2 x
// with h = 1, x_n = e^{sn}, a_n = s^2 e^{sn}, D_k,n = delta_k e^{sn}: relations (a)
// and (c) of theory.md section 2.2 become a homogeneous linear system in
// (delta_0, delta_1, delta_3, ..., delta_{d-1}) whose entries are power series in s.
// Its determinant is, up to a unit factor e^{js}, the linear multistep form
// rho(e^s) - s^2 sigma(e^s) of the method, so the method is exact on polynomial
// solutions of degree q exactly when the coefficients of s^0 .. s^{q+1} vanish:
// order p in x <=> ord(det) = p + 2. The velocity is judged the same way from
// relations (a) alone (Cramer's rule for delta_1 against the exact delta_1 = s).
// The same expansion is the local error of the principal root: rho + Omega^2 sigma
// is the characteristic polynomial of the amplification matrix (s = i Omega).
// All parameters enter one column of the system, so the coefficients are affine in
// the parameters: the order conditions are linear (used by the set finder).
#include <ceode/ceode.h>
#include <ceode/ceode_stability.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "ceode_impl.hpp"

namespace ceode {

namespace {

// Truncated power series in s; long double keeps the cancellations of the
// high-order coefficients (parameters up to ~1e5 at d = 8) far below 1e-12.
constexpr int kLen = 2 * kMaxDegree + 4;
using Series = std::array<long double, kLen>;

Series Mul(const Series& a, const Series& b) {
  Series r{};
  for (int i = 0; i < kLen; ++i) {
    if (a[i] == 0) continue;
    for (int j = 0; i + j < kLen; ++j) r[i + j] += a[i] * b[j];
  }
  return r;
}

Series Exp(long double sign) {
  Series r{};
  long double c = 1;
  for (int m = 0; m < kLen; ++m) {
    r[m] = c;
    c *= sign / (m + 1);
  }
  return r;
}

long double Fact(int n) {
  long double r = 1;
  for (int i = 2; i <= n; ++i) r *= i;
  return r;
}

// Square matrix of series, with its entries' absolute values alongside: the
// magnitude of the terms that cancel in a coefficient decides "zero".
struct SeriesMatrix {
  int n = 0;
  Series a[kMaxDegree][kMaxDegree] = {};
};

// det by expansion over column subsets (n <= 7: 128 subsets).
void Det(const SeriesMatrix& m, Series* det, Series* mag) {
  const int n = m.n;
  std::vector<Series> f(1u << n), g(1u << n);
  f[0] = Series{};
  f[0][0] = 1;
  g[0] = f[0];
  for (unsigned mask = 0; mask < (1u << n); ++mask) {
    const int row = __builtin_popcount(mask);
    if (row >= n) continue;
    for (int j = 0; j < n; ++j) {
      if (mask & (1u << j)) continue;
      const int above = __builtin_popcount(mask >> (j + 1));
      const long double sign = (above % 2 == 0) ? 1 : -1;
      Series abs_e = m.a[row][j];
      for (long double& c : abs_e) c = std::fabs(c);
      const Series p = Mul(f[mask], m.a[row][j]);
      const Series q = Mul(g[mask], abs_e);
      Series& fo = f[mask | (1u << j)];
      Series& go = g[mask | (1u << j)];
      for (int k = 0; k < kLen; ++k) {
        fo[k] += sign * p[k];
        go[k] += q[k];
      }
    }
  }
  *det = f[(1u << n) - 1];
  *mag = g[(1u << n) - 1];
}

// The system of the exponential solution. Columns: 0 = delta_0 (delta_2 =
// s^2 delta_0 folds into it), then delta_1, delta_3, ..., delta_{d-1}. Rows:
// relations (a) for k = 1 .. d-2, then the position relation (c).
class ExpSystem {
 public:
  ExpSystem(int d, const sunrealtype* p) : d_(d) {
    const Series em = Exp(-1);
    for (int k = 1; k <= d - 2; ++k) {
      Add(k - 1, k, One());
      for (int i = 0; i <= d - 2 - k; ++i) Add(k - 1, k + i, Scale(em, -1 / Fact(i)));
      Add(k - 1, d - 1, Scale(Blend(em, p[k]), -1 / Fact(d - 1 - k)));
    }
    const int r = d - 2;
    Series ep = Exp(1);
    ep[0] -= 1;
    Add(r, 0, ep);
    for (int i = 1; i <= d - 2; ++i) Add(r, i, Scale(One(), -1 / Fact(i)));
    Add(r, d - 1, Scale(Blend(em, p[0]), -1 / Fact(d - 1)));
  }

  // The full (d-1) x (d-1) system: its determinant is the x residual.
  SeriesMatrix Full() const {
    SeriesMatrix m;
    m.n = d_ - 1;
    for (int r = 0; r < m.n; ++r) {
      for (int c = 0; c < m.n; ++c) m.a[r][c] = a_[r][c];
    }
    return m;
  }

  // Relations (a) only, in the unknowns delta_1, delta_3, ...; with
  // replace_first, the delta_1 column is the right-hand side (Cramer).
  SeriesMatrix Velocity(bool replace_first) const {
    SeriesMatrix m;
    m.n = d_ - 2;
    for (int r = 0; r < m.n; ++r) {
      for (int c = 0; c < m.n; ++c) m.a[r][c] = a_[r][c + 1];
      if (replace_first) m.a[r][0] = Scale(a_[r][0], -1);
    }
    return m;
  }

 private:
  static Series One() {
    Series r{};
    r[0] = 1;
    return r;
  }
  static Series Scale(Series s, long double c) {
    for (long double& v : s) v *= c;
    return s;
  }
  // (1 - p) e^{-s} + p: the blend of the top derivative at the two ends.
  static Series Blend(const Series& em, sunrealtype p) {
    Series r = Scale(em, 1 - static_cast<long double>(p));
    r[0] += p;
    return r;
  }
  // var: the index k of delta_k; delta_2 = s^2 delta_0.
  void Add(int row, int var, const Series& s) {
    if (var == 0 || var == 2) {
      const int shift = var == 2 ? 2 : 0;
      for (int m = 0; m + shift < kLen; ++m) a_[row][0][m + shift] += s[m];
      return;
    }
    const int col = var == 1 ? 1 : var - 1;
    for (int m = 0; m < kLen; ++m) a_[row][col][m] += s[m];
  }

  int d_;
  Series a_[kMaxDegree][kMaxDegree] = {};
};

// Relative size below which a coefficient counts as zero: the terms it is made
// of are rounded at ~1e-19 (long double), parameters given as decimals at 1e-16.
constexpr long double kZeroTol = 1e-11L;

// Lowest s-power with a non-zero coefficient (kLen when all vanish).
int Valuation(const Series& c, const Series& mag) {
  for (int m = 0; m < kLen; ++m) {
    if (std::fabs(c[m]) > kZeroTol * mag[m]) return m;
  }
  return kLen;
}

}  // namespace

// x and x' residual series, normalised so that the leading coefficient is the
// error constant of the multistep form (1/12 for central differences).
void OrderSeries(int d, const sunrealtype* p, long double* cx, long double* mx, long double* cv,
                 long double* mv) {
  const ExpSystem sys(d, p);
  Series dx, mgx, da, mga, d1, mg1;
  Det(sys.Full(), &dx, &mgx);
  Det(sys.Velocity(false), &da, &mga);
  Det(sys.Velocity(true), &d1, &mg1);
  const long double norm = da[1];  // parameter free: the scaled system is unit triangular at 0
  for (int m = 0; m < kLen; ++m) {
    const long double sda = m > 0 ? da[m - 1] : 0;
    const long double smg = m > 0 ? mga[m - 1] : 0;
    cx[m] = dx[m] / norm;
    mx[m] = mgx[m] / std::fabs(norm);
    cv[m] = (d1[m] - sda) / norm;
    mv[m] = (mg1[m] + smg) / std::fabs(norm);
  }
}

int MethodOrders(int d, const sunrealtype* p, int* order_x, int* order_v, long double* const_x,
                 long double* const_v) {
  Series cx, mx, cv, mv;
  OrderSeries(d, p, cx.data(), mx.data(), cv.data(), mv.data());
  const int vx = Valuation(cx, mx);
  const int vv = Valuation(cv, mv);
  *order_x = vx - 2;
  *order_v = vv - 2;
  if (const_x != nullptr) *const_x = vx < kLen ? cx[vx] : 0;
  if (const_v != nullptr) *const_v = vv < kLen ? cv[vv] : 0;
  return CE_SUCCESS;
}

}  // namespace ceode

extern "C" {

int CEodeMethodOrder(int degree, const sunrealtype* params, int* order_x, int* order_v) {
  if (degree < ceode::kMinDegree || degree > ceode::kMaxDegree || params == nullptr ||
      order_x == nullptr || order_v == nullptr) {
    return CE_ILL_INPUT;
  }
  for (int i = 0; i < degree - 1; ++i) {
    if (!std::isfinite(params[i])) return CE_ILL_INPUT;
  }
  try {
    return ceode::MethodOrders(degree, params, order_x, order_v, nullptr, nullptr);
  } catch (...) {
    return CE_MEM_FAIL;
  }
}

int CEodeMethodErrorCoeffs(int degree, const sunrealtype* params, int n, sunrealtype* coef_x,
                           sunrealtype* coef_v) {
  if (degree < ceode::kMinDegree || degree > ceode::kMaxDegree || params == nullptr || n < 0 ||
      n > ceode::kLen || (n > 0 && (coef_x == nullptr || coef_v == nullptr))) {
    return CE_ILL_INPUT;
  }
  for (int i = 0; i < degree - 1; ++i) {
    if (!std::isfinite(params[i])) return CE_ILL_INPUT;
  }
  try {
    ceode::Series cx, mx, cv, mv;
    ceode::OrderSeries(degree, params, cx.data(), mx.data(), cv.data(), mv.data());
    bool finite = true;
    for (int m = 0; m < n; ++m) {
      coef_x[m] = static_cast<sunrealtype>(cx[m]);
      coef_v[m] = static_cast<sunrealtype>(cv[m]);
      finite = finite && std::isfinite(coef_x[m]) && std::isfinite(coef_v[m]);
    }
    // Parameters near the floating-point range overflow the series (as CEodeMethodErrorConstant).
    return finite ? CE_SUCCESS : CE_ILL_INPUT;
  } catch (...) {
    return CE_MEM_FAIL;
  }
}

}  // extern "C"
