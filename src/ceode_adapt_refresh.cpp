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

// Coefficients of the Newton basis w_j(s) = prod_{i<j} (s - delta_i), delta_i = t_{n-i} - t_n,
// in powers of s = t - t_n: w[i][j] is the coefficient of s^i in w_j (j, i < p; by power, so
// that the sums over j below run along rows).
void NewtonBasis(const AdaptMem& am, int p, sunrealtype (*w)[kMaxDegree]) {
  for (int i = 0; i < kMaxDegree; ++i) std::fill(w[i], w[i] + kMaxDegree, SUN_RCONST(0.0));
  w[0][0] = 1;
  for (int j = 1; j < p; ++j) {
    const sunrealtype delta = am.tnode[j - 1] - am.tnode[0];
    for (int i = j; i > 0; --i) w[i][j] = w[i - 1][j - 1] - delta * w[i][j - 1];
    w[0][j] = 0 - delta * w[0][j - 1];  // 0 - x: the sign of a zero as in the rows above
  }
}

// i! / (i - m)!, m <= i < kMaxDegree: the weights of the derivatives' Horner sums, products of
// integers (exact), formed once instead of in every sum.
struct FallingFactorials {
  sunrealtype f[kMaxDegree][kMaxDegree] = {};
  constexpr FallingFactorials() {
    for (int i = 0; i < kMaxDegree; ++i) {
      for (int m = 0; m <= i; ++m) {
        sunrealtype v = 1;
        for (int q = i - m + 1; q <= i; ++q) v *= q;
        f[i][m] = v;
      }
    }
  }
};
constexpr FallingFactorials kFalling;

// Weights over the divided differences of the consistent D_k at t_n + s for the step h:
// sum_l gamma_kl h^l y^(k+l)(t_n + s), y^(m) = the interpolant's (m-2)-th derivative.
void ConsistentWeights(const AdaptMem& am, const sunrealtype (*w)[kMaxDegree], int k, sunrealtype h,
                       sunrealtype s, sunrealtype* c) {
  const int p = am.order;
  for (int j = 0; j < p; ++j) c[j] = 0;
  sunrealtype hl = 1;
  for (int l = 0; k + l - 2 <= p - 1 && l < kGammaTerms; ++l, hl *= h) {
    const sunrealtype g = am.gamma[k][l] * hl;
    if (g == 0) continue;
    // the m-th derivatives of the w_j at s: Horner in s over i!/(i-m)! w[i][j], at s = 0 its
    // one term m! w[m][j] (the same value, up to the sign of a zero)
    const int m = k + l - 2;
    if (s == 0) {
      const sunrealtype f = kFalling.f[m][m];
      for (int j = 0; j < p; ++j) c[j] += g * (f * w[m][j]);
      continue;
    }
    sunrealtype r[kMaxDegree] = {};
    for (int i = p - 1; i >= m; --i) {
      const sunrealtype f = kFalling.f[i][m];
      for (int j = 0; j < p; ++j) r[j] = r[j] * s + f * w[i][j];
    }
    for (int j = 0; j < p; ++j) c[j] += g * r[j];
  }
}

// std::pow(x, e) for x > 0, the value of an earlier call when it is at hand.
sunrealtype PowOf(AdaptMem* am, sunrealtype x, int e) {
  for (int i = 0; i < AdaptMem::kPowMemo; ++i) {
    if (am->pow_e[i] == e && am->pow_x[i] == x && x > 0) return am->pow_r[i];
  }
  const sunrealtype r = std::pow(x, e);
  am->pow_x[am->pow_next] = x;
  am->pow_e[am->pow_next] = e;
  am->pow_r[am->pow_next] = r;
  am->pow_next = (am->pow_next + 1) % AdaptMem::kPowMemo;
  return r;
}

}  // namespace

bool RefreshHistory(CEodeMemRec* ce, AdaptMem* am, sunrealtype h) {
  const int d = ce->degree;
  const int p = am->order;
  if (!am->refresh || am->ndata < p || p < 2) return false;  // the table is not full yet
  // The top difference is the accepted estimate ele = cerr hlast^(p+1) (p-1)! a[t_n .. t_{n-p+1}].
  const sunrealtype scale = am->cerr * std::pow(am->hlast, p + 1) * am->pfac;
  if (scale == 0 || !std::isfinite(scale)) return false;
  N_Vector X[kMaxDegree + 1];
  X[0] = ce->D[2];  // a(t_n), the table's first entry
  for (int j = 1; j < p - 1; ++j) X[j] = am->dd[am->cur][j];
  X[p - 1] = am->ele;
  sunrealtype w[kMaxDegree][kMaxDegree];
  NewtonBasis(*am, p, w);
  for (auto& wi : w) wi[p - 1] /= scale;
  // D_1 keeps its value (the velocity is no parasitic component) and moves its h-dependent part
  // from hmap to h with the remap's own terms, from the history before it is rebuilt.
  for (int i = 0; i < am->nremap; ++i) {
    const RemapTerm& r = am->remap[i];
    if (r.k != 1) continue;
    const sunrealtype g = r.gamma * (PowOf(am, h, r.j) - PowOf(am, am->hmap, r.j));
    am->kernels.Axpy(g, 1 + r.j == d ? am->yd : ce->D[1 + r.j], ce->D[1]);
  }
  // The top derivative one step of h back, for the position's blend: yd = (z_n - z(t_n - h)) / h.
  // D_3 .. D_{d-1} and yd (the last row of c), in one call.
  sunrealtype c[kMaxDegree][kMaxDegree];  // rows < nout, columns < p: all written below
  N_Vector out[kMaxDegree];
  int nout = 0;
  sunrealtype cz[kMaxDegree];
  ConsistentWeights(*am, w, d - 1, h, -h, cz);
  for (int k = 3; k < d; ++k) {
    ConsistentWeights(*am, w, k, h, 0, c[nout]);
    out[nout++] = ce->D[k];
    if (k == d - 1) {
      for (int j = 0; j < p; ++j) cz[j] = (c[nout - 1][j] - cz[j]) / h;
    }
  }
  std::copy(cz, cz + p, c[nout]);
  out[nout++] = am->yd;
  am->kernels.LinMany(nout, p, c, X, out);
  am->hmap = am->hprev = h;
  return true;
}

}  // namespace ceode
