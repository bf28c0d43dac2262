// The reference backend: every combination one N_Vector operation per term (or per two), on any
// vector type. The serial backend (ceode_kernels_serial.cpp) reproduces its numbers bit for bit.
#include <algorithm>

#include "ceode_kernels.hpp"

namespace ceode {

void Combine(int m, const sunrealtype* c, N_Vector* X, N_Vector z) {
  if (m == 0) {
    N_VConst(0, z);
  } else if (m == 1) {
    N_VScale(c[0], X[0], z);
  } else if (m == 2) {
    N_VLinearSum(c[0], X[0], c[1], X[1], z);
  } else {
    N_VLinearCombination(m, const_cast<sunrealtype*>(c), X, z);
  }
}

namespace {

// The exact rounding error of the products p = a x (a scalar, x a vector) into out, by Dekker's
// product of the halves of a and x (bh, bl scratch): the operations ProductError makes on each
// entry, one N_Vector operation each, so that both give the same bits (the error is exact).
void ProductErrorByOps(sunrealtype a, N_Vector x, N_Vector p, N_Vector bh, N_Vector bl,
                       N_Vector out) {
  constexpr sunrealtype kSplit = 134217729.0;  // 2^27 + 1
  const sunrealtype ta = kSplit * a, ah = ta - (ta - a), al = a - ah;
  N_VScale(kSplit, x, bh);            // tb
  N_VLinearSum(1, bh, -1, x, bl);     // tb - x
  N_VLinearSum(1, bh, -1, bl, bh);    // bh = tb - (tb - x)
  N_VLinearSum(1, x, -1, bh, bl);     // bl = x - bh
  N_VLinearSum(ah, bh, -1, p, out);   // ah bh - p
  N_VLinearSum(1, out, ah, bl, out);  // + ah bl
  N_VLinearSum(1, out, al, bh, out);  // + al bh
  N_VLinearSum(1, out, al, bl, out);  // + al bl
}

// StoreCompensatedExact (ceode_kernels_serial.cpp) on vectors without host data: the increment
// sum_j c_j X_j - comp as s + e (Dot2), then out = old + s and compnew = ((out - old) - s) - e,
// one N_Vector operation per operation of the entry-wise form. False without scratch vectors.
bool CompensatedSumByOps(const Combo& cb, const Compensation& cs) {
  if (cs.work == nullptr || cs.work[kCompWork - 1] == nullptr) return false;
  N_Vector s = cs.work[0], t = cs.work[1], e = cs.work[2], p = cs.work[3], bb = cs.work[4];
  N_Vector bh = cs.work[5], bl = cs.work[6], q = cs.work[7], r = cs.work[8];
  N_VScale(cb.c[0], cb.X[0], s);
  ProductErrorByOps(cb.c[0], cb.X[0], s, bh, bl, e);
  for (int j = 1; j <= cb.m; ++j) {
    const sunrealtype c = j < cb.m ? cb.c[j] : -1;
    N_Vector x = j < cb.m ? cb.X[j] : cs.comp[cb.level];
    N_VScale(c, x, p);
    N_VLinearSum(1, s, 1, p, t);    // t = s + p
    N_VLinearSum(1, t, -1, s, bb);  // bb = t - s
    ProductErrorByOps(c, x, p, bh, bl, q);
    N_VLinearSum(1, t, -1, bb, r);   // t - bb
    N_VLinearSum(1, s, -1, r, r);    // s - (t - bb)
    N_VLinearSum(1, p, -1, bb, bb);  // p - bb
    N_VLinearSum(1, r, 1, bb, r);    // the sum's error
    N_VLinearSum(1, q, 1, r, q);     // the product's error and the sum's
    N_VLinearSum(1, e, 1, q, e);
    std::swap(s, t);
  }
  N_Vector comp_new = cs.compnew[cb.level];
  N_VLinearSum(1, cb.old, 1, s, cb.out);
  N_VLinearSum(1, cb.out, -1, cb.old, comp_new);
  N_VLinearSum(1, comp_new, -1, s, comp_new);
  N_VLinearSum(1, comp_new, -1, e, comp_new);
  return true;
}

// The increment is summed first and the large accumulated term last, so that
// quantity is rounded once per step; with compensated summation its rounding
// error is carried forward in comp -> compnew (Kahan).
void RunCombo(const Combo& cb, const Compensation& cs) {
  if (cb.old == nullptr) {
    Combine(cb.m, cb.c, const_cast<N_Vector*>(cb.X), cb.out);
    return;
  }
  sunrealtype c[kMaxDegree + 3];
  N_Vector X[kMaxDegree + 3];
  std::copy(cb.c, cb.c + cb.m, c);
  std::copy(cb.X, cb.X + cb.m, X);
  int m = cb.m;
  if (!cs.on && cb.lead_old) {
    c[0] = 1;
    X[0] = cb.old;
    std::copy(cb.c, cb.c + cb.m, c + 1);
    std::copy(cb.X, cb.X + cb.m, X + 1);
    Combine(m + 1, c, X, cb.out);
    return;
  }
  if (!cs.on) {
    c[m] = 1;
    X[m++] = cb.old;
    Combine(m, c, X, cb.out);
    return;
  }
  if (ExactIncrement(cb.level) && (CompensatedSumOnData(cb, cs) || CompensatedSumByOps(cb, cs))) {
    return;
  }
  // The higher derivatives: the rounded increment, compensated when it is added.
  N_Vector y = cs.tmp;
  c[m] = -1;
  X[m++] = cs.comp[cb.level];
  Combine(m, c, X, y);  // y = increment - comp
  N_Vector comp_new = cs.compnew[cb.level];
  N_VLinearSum(1, cb.old, 1, y, cb.out);
  N_VLinearSum(1, cb.out, -1, cb.old, comp_new);
  N_VLinearSum(1, comp_new, -1, y, comp_new);
}

}  // namespace

void UpdateReference(const UpdatePlan& plan, const Compensation& cs) {
  for (int k = 0; k < plan.n; ++k) RunCombo(plan.combos[k], cs);
}

}  // namespace ceode
