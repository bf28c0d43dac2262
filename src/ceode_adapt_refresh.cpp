// The history refresh of the adaptive step (docs/theory.md section 12.5): when the step changes,
// the history beyond the acceleration is rebuilt from the interpolant of the last p
// accelerations as the consistent history of a fixed-step run with the new step, so that a
// rough step sequence cannot pump the parasitic modes of the derivative relations.
#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include "ceode_adapt.hpp"
#include "ceode_lanes.hpp"
#include "ceode_step.hpp"

namespace ceode {

namespace {

// The refresh's rows side by side: pairs where SSE2 is, single values elsewhere (the same IEEE
// operations per row either way, ceode_lanes.hpp).
#if defined(__SSE2__) && defined(SUNDIALS_DOUBLE_PRECISION)
using Lanes = Pair;
#else
using Lanes = sunrealtype;
#endif

// i! / (i - m)!, m <= i < kMaxDegree: the weights of the derivatives of s^i, products of
// integers (exact).
sunrealtype Falling(int i, int m) {
  sunrealtype v = 1;
  for (int q = i - m + 1; q <= i; ++q) v *= q;
  return v;
}

// x^j - y^j, the powers by repeated multiplication from 1 (RemapWeights' values).
sunrealtype PowerDifference(sunrealtype x, sunrealtype y, int j) {
  sunrealtype u = 1;
  sunrealtype v = 1;
  for (int q = 0; q < j; ++q) {
    u *= x;
    v *= y;
  }
  return u - v;
}

// The row of D_k, k >= 3, at s = 0: gamma_kl h^l P^(m)(t_n), m = k + l - 2, reads m! times the
// interpolant's power coefficient m, with h^(m - (k - 2)).
void ConsistentRow(const AdaptMem& am, int k, sunrealtype* row) {
  for (int l = 0; k + l - 2 <= am.set.order - 1 && l < kGammaTerms; ++l) {
    const int m = k + l - 2;
    row[m] = am.set.gamma[k][l] * Falling(m, m);
  }
}

// The row of yd = (z(t_n) - z(t_n - h)) / h, z = D_{d-1}: the terms i = m of the two series
// cancel, the others give coefficient i the weight sum_m gamma_{d-1,l} i!/(i-m)! (-1)^(i-m+1)
// with h^(i - (d - 2)), free of the difference's cancellation.
void RateRow(const AdaptMem& am, int d, sunrealtype* row) {
  const int k = d - 1;
  for (int l = 0; k + l - 2 <= am.set.order - 1 && l < kGammaTerms; ++l) {
    const int m = k + l - 2;
    for (int i = m + 1; i < am.set.order; ++i) {
      const sunrealtype sign = (i - m) % 2 == 0 ? -1 : 1;
      row[i] += am.set.gamma[k][l] * Falling(i, m) * sign;
    }
  }
}

// The weights of the refreshed history over the differences by term, c[j][r] (j < p, r <
// refresh_rows: row r's weight of difference j). Row r weighs the interpolant's power coefficient
// i by k_ri h^(i - e_r); in sigma = s / h the Newton basis is w_j = h^j prod_{i<j} (sigma - rho_i),
// rho_i = delta_i / h, delta_i = t_{n-i} - t_n, so that c[j][r] = h^(j - e_r) L_r(u_j), u_j =
// prod_{i<j} (sigma - rho_i), L_r the row's constant functional on the power coefficients. With
// L_r^t the functional shifted by t, u_j = (sigma - rho_{j-1}) u_{j-1} gives L_r^t(u_j) =
// L_r^{t+1}(u_{j-1}) - rho_{j-1} L_r^t(u_{j-1}): all rows at once, from the table without forming
// the basis. The order P is a constant, so that the loops unroll and the rows run side by side.
template <int P>
void RefreshWeightsOf(const AdaptMem& am, sunrealtype h, sunrealtype scale,
                      sunrealtype (*c)[kMaxDegree]) {
  constexpr int L = sizeof(Lanes) / sizeof(sunrealtype);
  constexpr int W = AdaptMem::kRefreshRows / L;  // the rows in groups of L
  static_assert(W * L == AdaptMem::kRefreshRows, "the rows fill the groups");
  const Lanes tag{};
  const sunrealtype hinv = 1 / h;
  // Row r's lowest power is e_r = r + 1 (RefreshTables): lane r of term j weighs by h^(j - 1 - r),
  // at pw[P - j + r] with the powers in reverse (pw[P - 1 - k] = h^k), zero below h^0, where
  // L_r(u_j) is zero too (no term of L_r reaches it).
  sunrealtype pw[P + AdaptMem::kRefreshRows] = {};
  pw[P - 1] = 1;
  for (int k = 1; k < P; ++k) pw[P - 1 - k] = pw[P - k] * h;
  Lanes rho[P];
  for (int j = 1; j < P; ++j) rho[j] = Splat((am.tnode[j - 1] - am.tnode[0]) * hinv, tag);
  std::fill(c[0], c[0] + AdaptMem::kRefreshRows, SUN_RCONST(0.0));  // e_r >= 1: no row reaches it
  // Each group of rows on its own (the table of one group stays in registers): g[t] = L^t(u_j),
  // t < P - j; term j's weights are L(u_j) = g[0] times the powers. Below the group's lowest
  // power e = w L + 1 (t + j < e) the entries stay zero: each would be +0 - rho (+0) = +0.
#pragma GCC unroll 8
  for (int w = 0; w < W; ++w) {
    Lanes g[P];
    for (int t = 0; t < P; ++t) g[t] = Load(am.refresh_k[t] + w * L, tag);
#pragma GCC unroll 8
    for (int j = 1; j < P; ++j) {
#pragma GCC unroll 8
      for (int t = std::max(0, w * L + 1 - j); t + j < P; ++t) g[t] = g[t + 1] - rho[j] * g[t];
      Store(c[j] + w * L, g[0] * Load(pw + P - j + w * L, tag));
    }
  }
  const Lanes s = Splat(scale, tag);
  for (int w = 0; w < W; ++w) Store(c[P - 1] + w * L, Load(c[P - 1] + w * L, tag) / s);
}

using RefreshWeightsFn = void (*)(const AdaptMem&, sunrealtype, sunrealtype,
                                  sunrealtype (*)[kMaxDegree]);
template <std::size_t... I>
constexpr std::array<RefreshWeightsFn, sizeof...(I)> RefreshWeightsTable(
    std::index_sequence<I...> /*p*/) {
  return {&RefreshWeightsOf<static_cast<int>(I) + 2>...};
}
// By the order p = 2 .. kMaxDegree.
constexpr auto kRefreshWeightsFns = RefreshWeightsTable(std::make_index_sequence<kMaxDegree - 1>{});

// The top difference's scale: the accepted estimate is ele = cerr hlast^(p+1) (p-1)! times it,
// the estimate's own factor when it was formed for hlast.
sunrealtype TopScale(const AdaptMem& am) {
  if (am.est_h == am.hlast) return am.est_scale;
  sunrealtype hp = 1;
  for (int i = 0; i <= am.set.order; ++i) hp *= am.hlast;
  return am.set.cerr * hp * am.pfac;
}

// D_1 keeps its value (the velocity is no parasitic component) and moves its h-dependent part
// from hmap to h with the remap's own terms (RemapWeights' values), from the history before it
// is rebuilt. The terms come by k (ComputeSetCoefficients): those of D_1 first.
void MoveVelocity(CEodeMemRec* ce, AdaptMem* am, sunrealtype h) {
  const int d = ce->degree;
  for (int i = 0; i < am->set.nremap && am->set.remap[i].k == 1; ++i) {
    const RemapTerm& r = am->set.remap[i];
    const sunrealtype c = r.gamma * PowerDifference(h, am->hmap, r.j);
    am->kernels.Axpy(c, 1 + r.j == d ? am->yd : ce->D[1 + r.j], ce->D[1]);
  }
}

}  // namespace

void RefreshTables(AdaptMem* am, int d) {
  am->refresh_rows = 0;
  for (auto& row : am->refresh_k) std::fill(row, row + AdaptMem::kRefreshRows, SUN_RCONST(0.0));
  if (!am->refresh) return;
  for (int k = 3; k <= d; ++k) {  // D_3 .. D_{d-1}, then yd
    const int r = am->refresh_rows++;
    sunrealtype row[kMaxDegree] = {};
    if (k < d) {
      ConsistentRow(*am, k, row);
    } else {
      RateRow(*am, d, row);
    }
    for (int i = 0; i < kMaxDegree; ++i) am->refresh_k[i][r] = row[i];
  }
}

bool RefreshHistory(CEodeMemRec* ce, AdaptMem* am, sunrealtype h) {
  const int p = am->set.order;
  if (!am->refresh || am->ndata < p || p < 2) return false;  // the table is not full yet
  const sunrealtype scale = TopScale(*am);
  if (scale == 0 || !std::isfinite(scale)) return false;
  // The arrays of pointers by whole (constant-size copies: a few moves, no library call).
  N_Vector X[kMaxDegree];
  std::copy(am->dd[am->cur], am->dd[am->cur] + kMaxDegree, X);
  X[0] = ce->D[2];  // a(t_n), the table's first entry, then the differences
  X[p - 1] = am->ele;
  MoveVelocity(ce, am, h);
  // D_3 .. D_{d-1}, then yd, in one call.
  sunrealtype c[kMaxDegree][kMaxDegree];
  kRefreshWeightsFns[p - 2](*am, h, scale, c);
  N_Vector out[AdaptMem::kRefreshRows];
  std::copy(ce->D + 3, ce->D + 3 + AdaptMem::kRefreshRows - 1, out);
  out[am->refresh_rows - 1] = am->yd;
  am->kernels.LinMany(am->refresh_rows, p, c, X, out);
  am->hmap = am->hprev = h;
  return true;
}

}  // namespace ceode
