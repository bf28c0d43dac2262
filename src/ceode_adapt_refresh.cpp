// The history refresh of the adaptive step (docs/theory.md section 12.5): when the step changes,
// the history beyond the acceleration is rebuilt from the interpolant of the last p
// accelerations as the consistent history of a fixed-step run with the new step, so that a
// rough step sequence cannot pump the parasitic modes of the derivative relations.
#include <algorithm>
#include <cmath>

#include "ceode_adapt.hpp"
#include "ceode_step.hpp"

namespace ceode {

namespace {

// i! / (i - m)!, m <= i < kMaxDegree: the weights of the derivatives of s^i, products of
// integers (exact).
sunrealtype Falling(int i, int m) {
  sunrealtype v = 1;
  for (int q = i - m + 1; q <= i; ++q) v *= q;
  return v;
}

// The row of D_k, k >= 3, at s = 0: gamma_kl h^l P^(m)(t_n), m = k + l - 2, reads m! times the
// interpolant's power coefficient m, with h^(m - (k - 2)).
void ConsistentRow(const AdaptMem& am, int k, sunrealtype* row) {
  for (int l = 0; k + l - 2 <= am.order - 1 && l < kGammaTerms; ++l) {
    const int m = k + l - 2;
    row[m] = am.gamma[k][l] * Falling(m, m);
  }
}

// The row of yd = (z(t_n) - z(t_n - h)) / h, z = D_{d-1}: the terms i = m of the two series
// cancel, the others give coefficient i the weight sum_m gamma_{d-1,l} i!/(i-m)! (-1)^(i-m+1)
// with h^(i - (d - 2)), free of the difference's cancellation.
void RateRow(const AdaptMem& am, int d, sunrealtype* row) {
  const int k = d - 1;
  for (int l = 0; k + l - 2 <= am.order - 1 && l < kGammaTerms; ++l) {
    const int m = k + l - 2;
    for (int i = m + 1; i < am.order; ++i) {
      const sunrealtype sign = (i - m) % 2 == 0 ? -1 : 1;
      row[i] += am.gamma[k][l] * Falling(i, m) * sign;
    }
  }
}

// The weights of the refreshed history over the differences, c[r][j] (r < refresh_rows,
// j < p). Row r weighs the interpolant's power coefficient i by k_ri h^(i - e_r); in
// sigma = s / h the Newton basis is w_j = h^j prod_{i<j} (sigma - rho_i), rho_i = delta_i / h,
// delta_i = t_{n-i} - t_n, so that c[r][j] = h^(j - e_r) L_r(u_j), u_j = prod_{i<j} (sigma -
// rho_i), L_r the row's constant functional on the power coefficients. With L_r^t the functional
// shifted by t, u_j = (sigma - rho_{j-1}) u_{j-1} gives L_r^t(u_j) = L_r^{t+1}(u_{j-1}) - rho_{j-1}
// L_r^t(u_{j-1}): all rows at once, from the table without forming the basis.
void RefreshWeights(const AdaptMem& am, sunrealtype h, sunrealtype scale,
                    sunrealtype (*c)[kMaxDegree]) {
  constexpr int R = AdaptMem::kRefreshRows;
  const int p = am.order;
  const sunrealtype hinv = 1 / h;
  // g[t][r] = L_r^t(u_j), t < p - j; col[j][r] = L_r(u_j) (fixed sizes: copies without calls)
  sunrealtype g[kMaxDegree][R];
  for (int t = 0; t < kMaxDegree; ++t) std::copy(am.refresh_k[t], am.refresh_k[t] + R, g[t]);
  sunrealtype col[kMaxDegree][R];
  std::copy(g[0], g[0] + R, col[0]);
  for (int j = 1; j < p; ++j) {
    const sunrealtype rho = (am.tnode[j - 1] - am.tnode[0]) * hinv;
    for (int t = 0; t + j < p; ++t) {
      for (int r = 0; r < R; ++r) g[t][r] = g[t + 1][r] - rho * g[t][r];
    }
    std::copy(g[0], g[0] + R, col[j]);
  }
  // c[r][j] = h^(j - e) col[j][r], j >= e; below e col is zero (no term of L_r reaches it)
  sunrealtype pw[kMaxDegree];
  pw[0] = 1;
  for (int k = 1; k < p; ++k) pw[k] = pw[k - 1] * h;
  for (int r = 0; r < am.refresh_rows; ++r) {
    const int e = am.refresh_e[r];
    std::fill(c[r], c[r] + kMaxDegree, SUN_RCONST(0.0));
    for (int j = e; j < p; ++j) c[r][j] = col[j][r] * pw[j - e];
    c[r][p - 1] /= scale;
  }
}

// The top difference's scale: the accepted estimate is ele = cerr hlast^(p+1) (p-1)! times it,
// the estimate's own factor when it was formed for hlast.
sunrealtype TopScale(const AdaptMem& am) {
  if (am.est_h == am.hlast) return am.est_scale;
  sunrealtype hp = 1;
  for (int i = 0; i <= am.order; ++i) hp *= am.hlast;
  return am.cerr * hp * am.pfac;
}

// D_1 keeps its value (the velocity is no parasitic component) and moves its h-dependent part
// from hmap to h with the remap's own terms, from the history before it is rebuilt.
void MoveVelocity(CEodeMemRec* ce, AdaptMem* am, sunrealtype h) {
  const int d = ce->degree;
  sunrealtype rc[kMaxDegree * kMaxDegree];
  RemapWeights(*am, d, h, rc);
  for (int i = 0; i < am->nremap; ++i) {
    const RemapTerm& r = am->remap[i];
    if (r.k == 1) am->kernels.Axpy(rc[i], 1 + r.j == d ? am->yd : ce->D[1 + r.j], ce->D[1]);
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
    am->refresh_e[r] = k < d ? k - 2 : d - 2;
    if (k < d) {
      ConsistentRow(*am, k, row);
    } else {
      RateRow(*am, d, row);
    }
    for (int i = 0; i < kMaxDegree; ++i) am->refresh_k[i][r] = row[i];
  }
}

bool RefreshHistory(CEodeMemRec* ce, AdaptMem* am, sunrealtype h) {
  const int p = am->order;
  if (!am->refresh || am->ndata < p || p < 2) return false;  // the table is not full yet
  const sunrealtype scale = TopScale(*am);
  if (scale == 0 || !std::isfinite(scale)) return false;
  N_Vector X[kMaxDegree + 1];
  X[0] = ce->D[2];  // a(t_n), the table's first entry
  for (int j = 1; j < p - 1; ++j) X[j] = am->dd[am->cur][j];
  X[p - 1] = am->ele;
  MoveVelocity(ce, am, h);
  // D_3 .. D_{d-1}, then yd, in one call.
  sunrealtype c[AdaptMem::kRefreshRows][kMaxDegree];
  RefreshWeights(*am, h, scale, c);
  N_Vector out[AdaptMem::kRefreshRows];
  for (int r = 0; r + 1 < am->refresh_rows; ++r) out[r] = ce->D[3 + r];
  out[am->refresh_rows - 1] = am->yd;
  am->kernels.LinMany(am->refresh_rows, p, c, X, out);
  am->hmap = am->hprev = h;
  return true;
}

}  // namespace ceode
