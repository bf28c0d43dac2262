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
// in powers of s = t - t_n: w[j][i] is the coefficient of s^i (j, i < p).
void NewtonBasis(const AdaptMem& am, int p, sunrealtype (*w)[kMaxDegree]) {
  for (int j = 0; j < p; ++j) std::fill(w[j], w[j] + kMaxDegree, SUN_RCONST(0.0));
  w[0][0] = 1;
  for (int j = 1; j < p; ++j) {
    const sunrealtype delta = am.tnode[j - 1] - am.tnode[0];
    for (int i = j; i >= 0; --i) {
      w[j][i] = (i > 0 ? w[j - 1][i - 1] : 0) - delta * w[j - 1][i];
    }
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

// The m-th derivative of w_j at s; at s = 0 the one term m! w[j][m] (the Horner sum's value, up
// to the sign of a zero).
sunrealtype BasisDerivative(const sunrealtype (*w)[kMaxDegree], int p, int j, int m,
                            sunrealtype s) {
  if (s == 0) return m < p ? kFalling.f[m][m] * w[j][m] : 0;
  sunrealtype r = 0;
  for (int i = p - 1; i >= m; --i) r = r * s + kFalling.f[i][m] * w[j][i];  // Horner in s
  return r;
}

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
    const int m = k + l - 2;
    if (s == 0) {  // BasisDerivative at 0, the loop over j without its tests
      for (int j = 0; j < p; ++j) c[j] += g * (kFalling.f[m][m] * w[j][m]);
      continue;
    }
    for (int j = 0; j < p; ++j) c[j] += g * BasisDerivative(w, p, j, m, s);
  }
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
  for (sunrealtype& wi : w[p - 1]) wi /= scale;
  sunrealtype c[kMaxDegree + 1];
  // D_1 keeps its value (the velocity is no parasitic component) and moves its h-dependent part
  // from hmap to h with the remap's own terms, from the history before it is rebuilt.
  for (int i = 0; i < am->nremap; ++i) {
    const RemapTerm& r = am->remap[i];
    if (r.k != 1) continue;
    const sunrealtype g = r.gamma * (std::pow(h, r.j) - std::pow(am->hmap, r.j));
    am->kernels.Axpy(g, 1 + r.j == d ? am->yd : ce->D[1 + r.j], ce->D[1]);
  }
  // The top derivative one step of h back, for the position's blend: yd = (z_n - z(t_n - h)) / h.
  sunrealtype cz[kMaxDegree];
  ConsistentWeights(*am, w, d - 1, h, -h, cz);
  for (int k = 3; k < d; ++k) {
    ConsistentWeights(*am, w, k, h, 0, c);
    am->kernels.Lin(p, c, X, ce->D[k]);
    if (k == d - 1) {
      for (int j = 0; j < p; ++j) cz[j] = (c[j] - cz[j]) / h;
    }
  }
  am->kernels.Lin(p, cz, X, am->yd);
  am->hmap = am->hprev = h;
  return true;
}

}  // namespace ceode
