// The step's update kernel: the reference on generic N_Vectors and the fused serial backend
// (the whole update in one sweep through memory, block by block, about 3x faster on serial
// vectors; docs/results/bench_step.txt).
#include "ceode_fused.hpp"

#include <algorithm>
#include <cmath>

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
  N_Vector y = cs.tmp;
  c[m] = -1;
  X[m++] = cs.comp[cb.level];
  Combine(m, c, X, y);  // y = increment - comp
  N_Vector comp_new = cs.compnew[cb.level];
  N_VLinearSum(1, cb.old, 1, y, cb.out);
  N_VLinearSum(1, cb.out, -1, cb.old, comp_new);
  N_VLinearSum(1, comp_new, -1, y, comp_new);
}

// N_VLinearSum's shortcuts: a = +-b is computed as a * (x +- y) unless a or b is +-1.
enum class TwoTerm { kSum, kDifference, kGeneral };
TwoTerm TwoTermForm(sunrealtype a, sunrealtype b) {
  const bool unit = a == 1 || b == 1 || a == -1 || b == -1;
  if (!unit && a == b) return TwoTerm::kSum;
  if (!unit && a == -b) return TwoTerm::kDifference;
  return TwoTerm::kGeneral;
}

// Tiny systems: plain scalar code, without the vector loops' set-up.
void CombineTiny(int m, const sunrealtype* c, sunrealtype* const* X, sunindextype off,
                 sunindextype len, sunrealtype* out) {
  const TwoTerm form = m == 2 ? TwoTermForm(c[0], c[1]) : TwoTerm::kGeneral;
  for (sunindextype i = 0; i < len; ++i) {
    const sunrealtype x0 = X[0][off + i];
    sunrealtype acc;
    if (form == TwoTerm::kSum) {
      acc = c[0] * (x0 + X[1][off + i]);
    } else if (form == TwoTerm::kDifference) {
      acc = c[0] * (x0 - X[1][off + i]);
    } else if (m == 2) {
      acc = c[0] * x0 + c[1] * X[1][off + i];
    } else {
      acc = c[0] * x0;
      for (int j = 1; j < m; ++j) acc += c[j] * X[j][off + i];
    }
    out[i] = acc;
  }
}

void CombineTwo(const sunrealtype* c, const sunrealtype* x0, const sunrealtype* y, sunindextype len,
                sunrealtype* out) {
  const sunrealtype a = c[0];
  const sunrealtype b = c[1];
  switch (TwoTermForm(a, b)) {
    case TwoTerm::kSum:
      for (sunindextype i = 0; i < len; ++i) out[i] = a * (x0[i] + y[i]);
      break;
    case TwoTerm::kDifference:
      for (sunindextype i = 0; i < len; ++i) out[i] = a * (x0[i] - y[i]);
      break;
    case TwoTerm::kGeneral:
      for (sunindextype i = 0; i < len; ++i) out[i] = a * x0[i] + b * y[i];
      break;
  }
}

// out[0..len) = sum_j c[j] X[j][off..off+len) with the rounding of Combine: a two-term sum
// follows N_VLinearSum's shortcuts; longer sums add term by term in order, as
// N_VLinearCombination. The branch is taken once per block, so the inner loops vectorise.
void CombineBlock(int m, const sunrealtype* c, sunrealtype* const* X, sunindextype off,
                  sunindextype len, sunrealtype* out) {
  if (m == 0) {
    std::fill(out, out + len, SUN_RCONST(0.0));
    return;
  }
  if (len <= 4) {
    CombineTiny(m, c, X, off, len, out);
    return;
  }
  const sunrealtype* x0 = X[0] + off;
  if (m == 2) {
    CombineTwo(c, x0, X[1] + off, len, out);
    return;
  }
  for (sunindextype i = 0; i < len; ++i) out[i] = c[0] * x0[i];
  for (int j = 1; j < m; ++j) {
    const sunrealtype cj = c[j];
    const sunrealtype* xj = X[j] + off;
    for (sunindextype i = 0; i < len; ++i) out[i] += cj * xj[i];
  }
}

// One combination of the plan on one block; y is scratch of the block's length.
void RunTermsBlock(const FusedTerms& tk, sunindextype off, sunindextype len, sunrealtype* y) {
  if (tk.old == nullptr) {
    CombineBlock(tk.m, tk.c, tk.X, off, len, tk.out + off);
    return;
  }
  CombineBlock(tk.m, tk.c, tk.X, off, len, y);  // y = increment - comp
  const sunrealtype* o = tk.old + off;
  sunrealtype* nw = tk.out + off;
  sunrealtype* cn = tk.compnew + off;
  for (sunindextype i = 0; i < len; ++i) {
    nw[i] = o[i] + y[i];
    cn[i] = (nw[i] - o[i]) - y[i];
  }
}

}  // namespace

void UpdateReference(const UpdatePlan& plan, const Compensation& cs) {
  for (int k = 0; k < plan.n; ++k) RunCombo(plan.combos[k], cs);
}

// Each block stays in cache while every combination of the plan runs on it, instead of one
// pass over the vectors per term.
sunrealtype UpdateSerial(const FusedPlan& fp, sunindextype n) {
  constexpr sunindextype kBlock = 256;
  sunrealtype y[kBlock];
  const sunrealtype* xout = fp.terms[fp.n - 1].out;  // the position comes last
  sunrealtype sum = 0;
  for (sunindextype off = 0; off < n; off += kBlock) {
    const sunindextype len = std::min(kBlock, n - off);
    for (int k = 0; k < fp.n; ++k) RunTermsBlock(fp.terms[k], off, len, y);
    for (sunindextype i = 0; i < len; ++i) sum += std::fabs(xout[off + i]);
  }
  return sum;
}

// Each combination with its accumulated term (or, compensated, minus its compensation)
// appended, exactly as RunCombo hands it to Combine.
void BuildFusedPlan(const UpdatePlan& plan, const Compensation& cs, FusedPlan* fp) {
  fp->n = plan.n;
  for (int k = 0; k < plan.n; ++k) {
    const Combo& cb = plan.combos[k];
    FusedTerms& tk = fp->terms[k];
    tk.m = cb.m;
    for (int j = 0; j < cb.m; ++j) {
      tk.c[j] = cb.c[j];
      tk.X[j] = N_VGetArrayPointer(cb.X[j]);
    }
    tk.old = nullptr;
    tk.compnew = nullptr;
    if (cb.old != nullptr && !cs.on) {
      tk.c[tk.m] = 1;
      tk.X[tk.m++] = N_VGetArrayPointer(cb.old);
    } else if (cb.old != nullptr) {
      tk.c[tk.m] = -1;
      tk.X[tk.m++] = N_VGetArrayPointer(cs.comp[cb.level]);
      tk.old = N_VGetArrayPointer(cb.old);
      tk.compnew = N_VGetArrayPointer(cs.compnew[cb.level]);
    }
    tk.out = N_VGetArrayPointer(cb.out);
  }
}

}  // namespace ceode
