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
  if (!cs.on) {
    c[m] = 1;
    X[m++] = cb.old;
    Combine(m, c, X, cb.out);
    return;
  }
  if (ExactIncrement(cb.level) && CompensatedSumOnData(cb, cs)) return;
  // The higher derivatives, and vectors without host data: the rounded increment, compensated
  // when it is added.
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
