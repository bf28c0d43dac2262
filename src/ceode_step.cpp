// The degree-generic conditionally explicit step (method.md section 2), its
// coefficients, the start of the method and the dense output. One code path
// serves every degree: the parameter sets are data in kMethodSets.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>

#include "ceode_impl.hpp"

namespace ceode {

namespace {

// Named parameter sets (method.md section 5): alpha, beta, gamma, zeta. Measured
// properties (orders, stability limits) are in docs/stability.md and the tests.
const MethodSet kMethodSets[] = {
    {"G3_CD", 3, {1.0, 0.5}},
    {"G3_A43", 3, {4.0 / 3.0, 0.5}},
    {"G3_A2", 3, {2.0, 0.5}},
    {"G4_A54", 4, {5.0 / 4.0, 1.0 / 3.0, 0.5}},
    {"G4_A14", 4, {1.0 / 4.0, 1.0 / 3.0, 0.5}},
    {"G4_A34", 4, {3.0 / 4.0, 1.0 / 3.0, 0.5}},
    {"G5", 5, {4.0 / 5.0, 1.0, 1.0, 1.0}},
    {"G5_TOP", 5, {1.62, 1.03522, 1.0291293, 1.016}},
    {"G5_ONES", 5, {1.0, 1.0, 1.0, 1.0}},
    // High-degree sets found by `ceode-stability find` (command in docs/stability.md).
    {"G6_O5",
     6,
     {7.8581049690442608, 3.2003060015391878, 2.306472520152492, 1.445972372099134,
      0.78920709629572905}},
    {"G6_O6",
     6,
     {2.438146987413893, 1.260773492352264, 1.0359340008566345, 0.84442784269433835,
      0.57681936136099354}},
    {"G7_O7",
     7,
     {19.362993681325158, 15.310841926671563, 8.7099568711498723, 3.9685609709725753,
      2.3539640770647496, 0.90130820250696653}},
    {"G8_O8",
     8,
     {399.99982239054896, 278.28678067794129, 134.15990720943549, 51.039413540261052,
      20.827940678986256, 6.8588048481939303, 2.805527440772015}},
};

sunrealtype Factorial(int n) {
  sunrealtype r = 1;
  for (int i = 2; i <= n; ++i) r *= i;
  return r;
}

// z = sum c_i X_i with exactly the rounding of N_VScale / N_VLinearSum /
// N_VLinearCombination, so the fused kernel below can reproduce it bit for bit.
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

// The increment is summed first and the large accumulated term last, so that
// quantity is rounded once per step; with compensated summation its rounding
// error is carried forward in comp -> compnew (Kahan).
void RunCombo(CEodeMemRec* ce, const Combo& cb) {
  if (cb.old == nullptr) {
    Combine(cb.m, cb.c, const_cast<N_Vector*>(cb.X), cb.out);
    return;
  }
  sunrealtype c[kMaxDegree + 3];
  N_Vector X[kMaxDegree + 3];
  std::copy(cb.c, cb.c + cb.m, c);
  std::copy(cb.X, cb.X + cb.m, X);
  int m = cb.m;
  if (!ce->compensated) {
    c[m] = 1;
    X[m++] = cb.old;
    Combine(m, c, X, cb.out);
    return;
  }
  N_Vector y = ce->tmp1;
  c[m] = -1;
  X[m++] = ce->comp[cb.level];
  Combine(m, c, X, y);  // y = increment - comp
  N_Vector comp_new = ce->compnew[cb.level];
  N_VLinearSum(1, cb.old, 1, y, cb.out);
  N_VLinearSum(1, cb.out, -1, cb.old, comp_new);
  N_VLinearSum(1, comp_new, -1, y, comp_new);
}

// out[0..len) = sum_j c[j] X[j][0..len) with the rounding of Combine: a
// two-term sum follows N_VLinearSum's shortcuts (a = +-b is computed as
// a * (x +- y)); longer sums add term by term in order, as N_VLinearCombination.
// The branch is taken once per block, so the inner loops vectorise.
void CombineBlock(int m, const sunrealtype* c, sunrealtype* const* X, sunindextype off,
                  sunindextype len, sunrealtype* out) {
  if (m == 0) {
    std::fill(out, out + len, SUN_RCONST(0.0));
    return;
  }
  const sunrealtype* x0 = X[0] + off;
  if (len <= 4) {  // tiny systems: plain scalar code, without the vector loops' set-up
    for (sunindextype i = 0; i < len; ++i) {
      sunrealtype acc;
      if (m == 2) {
        const sunrealtype a = c[0];
        const sunrealtype b = c[1];
        const sunrealtype y = X[1][off + i];
        const bool unit = a == 1 || b == 1 || a == -1 || b == -1;
        acc = (!unit && a == b)    ? a * (x0[i] + y)
              : (!unit && a == -b) ? a * (x0[i] - y)
                                   : a * x0[i] + b * y;
      } else {
        acc = c[0] * x0[i];
        for (int j = 1; j < m; ++j) acc += c[j] * X[j][off + i];
      }
      out[i] = acc;
    }
    return;
  }
  if (m == 2) {
    const sunrealtype a = c[0];
    const sunrealtype b = c[1];
    const sunrealtype* y = X[1] + off;
    const bool unit = a == 1 || b == 1 || a == -1 || b == -1;
    if (!unit && a == b) {
      for (sunindextype i = 0; i < len; ++i) out[i] = a * (x0[i] + y[i]);
    } else if (!unit && a == -b) {
      for (sunindextype i = 0; i < len; ++i) out[i] = a * (x0[i] - y[i]);
    } else {
      for (sunindextype i = 0; i < len; ++i) out[i] = a * x0[i] + b * y[i];
    }
    return;
  }
  for (sunindextype i = 0; i < len; ++i) out[i] = c[0] * x0[i];
  for (int j = 1; j < m; ++j) {
    const sunrealtype cj = c[j];
    const sunrealtype* xj = X[j] + off;
    for (sunindextype i = 0; i < len; ++i) out[i] += cj * xj[i];
  }
}

// Serial vectors: the whole update in one sweep through memory, block by block
// (each block stays in cache while every combination of the plan runs on it),
// instead of one pass over the vectors per term. Same operations in the same
// order as RunCombo, so the numbers are the same to the bit.
// Returns false when the vectors are not serial (the generic path runs).
bool FusedUpdate(CEodeMemRec* ce, const FusedPlan& fp, sunrealtype* l1norm) {
  if (!ce->fused || !ce->fused_ready) return false;
  constexpr sunindextype kBlock = 256;
  sunrealtype y[kBlock];
  const sunindextype n = N_VGetLength(ce->xnext);
  const sunrealtype* xout = fp.terms[fp.n - 1].out;  // the position comes last
  sunrealtype sum = 0;
  for (sunindextype off = 0; off < n; off += kBlock) {
    const sunindextype len = std::min(kBlock, n - off);
    for (int k = 0; k < fp.n; ++k) {
      const FusedTerms& tk = fp.terms[k];
      if (tk.old == nullptr) {
        CombineBlock(tk.m, tk.c, tk.X, off, len, tk.out + off);
        continue;
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
    for (sunindextype i = 0; i < len; ++i) sum += std::fabs(xout[off + i]);
  }
  *l1norm = sum;
  return true;
}

}  // namespace

// Weights of the derivative of order q on the nodes x[0..m-1] at 0 (Fornberg 1988).
void FornbergWeights(int q, int m, const sunrealtype* x, sunrealtype* w) {
  sunrealtype C[2 * kMaxDegree + 1][kMaxDegree] = {};
  C[0][0] = 1;
  sunrealtype c1 = 1;
  for (int i = 1; i < m; ++i) {
    sunrealtype c2 = 1;
    const int mn = std::min(i, q);
    for (int j = 0; j < i; ++j) {
      const sunrealtype c3 = x[i] - x[j];
      c2 *= c3;
      for (int k = mn; k >= 0; --k) {
        if (j == i - 1) {
          C[i][k] = c1 / c2 * ((k > 0 ? k * C[i - 1][k - 1] : 0) - x[i - 1] * C[i - 1][k]);
        }
      }
      for (int k = mn; k >= 0; --k) {
        C[j][k] = (x[i] * C[j][k] - (k > 0 ? k * C[j][k - 1] : 0)) / c3;
      }
    }
    c1 = c2;
  }
  for (int i = 0; i < m; ++i) w[i] = C[i][q];
}

const MethodSet* FindMethodSet(const char* name) {
  if (name == nullptr) return nullptr;
  for (const MethodSet& m : kMethodSets) {
    if (std::strcmp(m.name, name) == 0) return &m;
  }
  return nullptr;
}

int NumMethodSets() { return static_cast<int>(sizeof(kMethodSets) / sizeof(kMethodSets[0])); }

const MethodSet& MethodSetAt(int index) { return kMethodSets[index]; }

void ComputeStepCoeffs(int d, const sunrealtype* p, sunrealtype h, StepCoeffs* co) {
  *co = StepCoeffs{};
  co->h = h;
  // Lower derivatives k = 1..d-2: Taylor from t-h with the top term blended by p_k.
  for (int k = 1; k <= d - 2; ++k) {
    for (int i = 0; i <= d - 2 - k; ++i) co->T[k][k + i] = std::pow(h, i) / Factorial(i);
    const sunrealtype top = std::pow(h, d - 1 - k) / Factorial(d - 1 - k);
    co->T[k][d - 1] += top * (1 - p[k]);
    co->c[k] = top * p[k];
  }
  if (d == 3) co->c[2] = 1;  // D_2 is the top derivative itself
  co->c[d - 1] = 1;
  co->kappa = co->c[1] / co->c[2];
  for (int j = 1; j < d; ++j) co->V0[j] = co->T[1][j] - co->kappa * co->T[2][j];
  // Position: Taylor from t with the top term blended by p_0.
  for (int i = 1; i <= d - 2; ++i) co->w[i] = std::pow(h, i) / Factorial(i);
  const sunrealtype top = std::pow(h, d - 1) / Factorial(d - 1);
  co->wz_old = top * (1 - p[0]);
  co->wz_new = top * p[0];
  sunrealtype cx = co->wz_new;
  for (int i = 1; i <= d - 2; ++i) cx += co->w[i] * co->c[i];
  co->mu = cx / co->c[2];
}

int AllocVectors(CEodeMemRec* ce, N_Vector tmpl) {
  N_Vector* all[] = {&ce->xcur,  &ce->xnext, &ce->xnew,    &ce->ftmp,   &ce->vtmp,
                     &ce->atmp,  &ce->tmp1,  &ce->tmp2,    &ce->tmp3,   &ce->V0,
                     &ce->apred, &ce->ycor,  &ce->ewt,     &ce->zero,   &ce->lstmp,
                     &ce->D[1],  &ce->D[2],  &ce->Dnew[1], &ce->Dnew[2]};
  for (N_Vector* v : all) {
    *v = N_VClone(tmpl);
    if (*v == nullptr) return CE_MEM_FAIL;
  }
  N_VConst(0, ce->zero);
  return CE_SUCCESS;
}

void FreeVectors(CEodeMemRec* ce) {
  N_Vector* all[] = {&ce->xcur,  &ce->xnext, &ce->xnew, &ce->ftmp, &ce->vtmp,
                     &ce->atmp,  &ce->tmp1,  &ce->tmp2, &ce->tmp3, &ce->V0,
                     &ce->apred, &ce->ycor,  &ce->ewt,  &ce->zero, &ce->lstmp};
  for (N_Vector* v : all) {
    if (*v != nullptr) N_VDestroy(*v);
    *v = nullptr;
  }
  for (int k = 0; k < kMaxDegree; ++k) {
    if (ce->D[k] != nullptr) N_VDestroy(ce->D[k]);
    if (ce->Dnew[k] != nullptr) N_VDestroy(ce->Dnew[k]);
    if (ce->comp[k] != nullptr) N_VDestroy(ce->comp[k]);
    if (ce->compnew[k] != nullptr) N_VDestroy(ce->compnew[k]);
    ce->D[k] = ce->Dnew[k] = ce->comp[k] = ce->compnew[k] = nullptr;
  }
  ce->initialized = false;
}

int EvalRhs(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector v, N_Vector f, const char* func) {
  const int rv = ce->f(t, x, v, f, ce->user_data);
  ++ce->nfe;
  if (rv != 0) {
    return ProcessError(ce, CE_RHSFUNC_FAIL, func,
                        "The right-hand side function failed (returned %d) at t = %.17g. A fixed "
                        "step cannot retry with a smaller h: fix f or reduce h.",
                        rv, static_cast<double>(t));
  }
  return CE_SUCCESS;
}

int EvalAccel(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector v, N_Vector a,
              const char* func) {
  int flag = MassUpdate(ce, t, x, func);
  if (flag == CE_SUCCESS) flag = EvalRhs(ce, t, x, v, a, func);
  return flag == CE_SUCCESS ? MassSolve(ce, a, func) : flag;
}

namespace {

// The update after the solve: z = (a - B_2)/c_2 (d = 3: z is a itself), the
// lower derivatives from the history and z, then the position increment.
void BuildPlan(const CEodeMemRec* ce, N_Vector* D, N_Vector* Dn, N_Vector xnext, N_Vector xnew,
               UpdatePlan* plan) {
  const int d = ce->degree;
  const StepCoeffs& co = ce->co;
  plan->n = 0;
  N_Vector a = Dn[2];
  N_Vector z = Dn[d - 1];
  if (d > 3) {
    Combo& cb = plan->combos[plan->n++];
    cb = Combo{};
    cb.Add(1 / co.c[2], a);
    for (int j = 2; j < d; ++j) cb.Add(-co.T[2][j] / co.c[2], D[j]);
    cb.out = z;
  }
  for (int k = 1; k <= d - 2; ++k) {
    if (k == 2) continue;  // D_2(t) = a exactly
    Combo& cb = plan->combos[plan->n++];
    cb = Combo{};
    for (int j = k + 1; j < d; ++j) cb.Add(co.T[k][j], D[j]);
    cb.Add(co.c[k], z);
    cb.old = D[k];
    cb.level = k;
    cb.out = Dn[k];
  }
  Combo& cb = plan->combos[plan->n++];
  cb = Combo{};
  for (int i = 1; i <= d - 2; ++i) cb.Add(co.w[i], Dn[i]);
  cb.Add(co.wz_old, D[d - 1]);
  cb.Add(co.wz_new, z);
  cb.old = xnext;
  cb.level = 0;
  cb.out = xnew;
}

// Raw-pointer form of a plan: each combination with its accumulated term (or,
// compensated, minus its compensation) appended, exactly as RunCombo hands it
// to Combine.
void BuildFusedPlan(const CEodeMemRec* ce, const UpdatePlan& plan, N_Vector* comp,
                    N_Vector* compnew, FusedPlan* fp) {
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
    if (cb.old != nullptr && !ce->compensated) {
      tk.c[tk.m] = 1;
      tk.X[tk.m++] = N_VGetArrayPointer(cb.old);
    } else if (cb.old != nullptr) {
      tk.c[tk.m] = -1;
      tk.X[tk.m++] = N_VGetArrayPointer(comp[cb.level]);
      tk.old = N_VGetArrayPointer(cb.old);
      tk.compnew = N_VGetArrayPointer(compnew[cb.level]);
    }
    tk.out = N_VGetArrayPointer(cb.out);
  }
}

}  // namespace

// The vectors only trade places from step to step (history <-> new every step,
// the three positions in a cycle of three), so six plans, built once per start,
// cover every step: the step itself builds nothing.
void BuildPlans(CEodeMemRec* ce) {
  const int d = ce->degree;
  N_Vector D[kMaxDegree];
  N_Vector Dn[kMaxDegree];
  N_Vector comp[kMaxDegree];
  N_Vector compnew[kMaxDegree];
  for (int k = 0; k < kMaxDegree; ++k) {
    D[k] = ce->D[k];
    Dn[k] = ce->Dnew[k];
    comp[k] = ce->comp[k];
    compnew[k] = ce->compnew[k];
  }
  N_Vector xcur = ce->xcur;
  N_Vector xnext = ce->xnext;
  N_Vector xnew = ce->xnew;
  ce->fused_ready = N_VGetVectorID(ce->xnext) == SUNDIALS_NVEC_SERIAL;
  for (int i = 0; i < kNumPlans; ++i) {
    BuildPlan(ce, D, Dn, xnext, xnew, &ce->plans[i]);
    if (ce->fused_ready) BuildFusedPlan(ce, ce->plans[i], comp, compnew, &ce->fused_plans[i]);
    for (int k = 1; k < d; ++k) std::swap(D[k], Dn[k]);
    for (int k = 0; k <= d - 2; ++k) std::swap(comp[k], compnew[k]);
    N_Vector old = xcur;
    xcur = xnext;
    xnext = xnew;
    xnew = old;
  }
}

int StartDerivatives(CEodeMemRec* ce, sunrealtype t0, N_Vector xs, N_Vector vs, N_Vector as,
                     const std::function<int(sunrealtype, N_Vector, N_Vector, N_Vector)>& accel) {
  const int d = ce->degree;
  if (d >= kHighStartDegree) return StartDerivativesHigh(ce, t0, xs, vs, as, accel);
  const sunrealtype h = ce->h;
  int flag = CE_SUCCESS;
  for (int m = 2; flag == CE_SUCCESS && m <= d - 2; ++m) {
    N_Vector out = ce->D[m + 1];
    const int q = m - 1;  // D_{m+1} is the q-th derivative of the acceleration
    const int r = (q + 1) / 2;
    const int npts = 2 * r + 1;
    sunrealtype nodes[2 * kMaxDegree + 1];
    sunrealtype wts[2 * kMaxDegree + 1];
    for (int j = 0; j < npts; ++j) nodes[j] = (j - r) * h;
    FornbergWeights(q, npts, nodes, wts);
    N_VScale(wts[r], ce->D[2], out);
    for (int j = 0; j < npts && flag == CE_SUCCESS; ++j) {
      if (j == r || wts[j] == 0) continue;
      const sunrealtype s = nodes[j];
      sunrealtype cx[kMaxDegree + 1];
      N_Vector vx[kMaxDegree + 1];
      sunrealtype sp = 1;  // s^i / i!
      for (int i = 0; i <= m; ++i) {
        cx[i] = sp;
        vx[i] = (i == 0) ? ce->xcur : ce->D[i];
        sp *= s / (i + 1);
      }
      N_VLinearCombination(m + 1, cx, vx, xs);
      N_VLinearCombination(m, cx, vx + 1, vs);  // the curve's derivative: same weights, shifted
      flag = accel(t0 + s, xs, vs, as);
      if (flag == CE_SUCCESS) N_VLinearSum(1, out, wts[j], as, out);
    }
  }
  return flag;
}

int StartMethod(CEodeMemRec* ce) {
  static const char* func = "CEodeEvolve";
  const int d = ce->degree;
  const sunrealtype h = ce->h;
  for (int k = 1; k < d; ++k) {
    if (ce->D[k] == nullptr) ce->D[k] = N_VClone(ce->xcur);
    if (ce->Dnew[k] == nullptr) ce->Dnew[k] = N_VClone(ce->xcur);
    if (ce->D[k] == nullptr || ce->Dnew[k] == nullptr) {
      return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
    }
  }
  for (int k = 0; ce->compensated && k <= d - 2; ++k) {
    if (ce->comp[k] == nullptr) ce->comp[k] = N_VClone(ce->xcur);
    if (ce->compnew[k] == nullptr) ce->compnew[k] = N_VClone(ce->xcur);
    if (ce->comp[k] == nullptr || ce->compnew[k] == nullptr) {
      return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
    }
    N_VConst(0, ce->comp[k]);
  }
  ComputeStepCoeffs(d, ce->params, h, &ce->co);
  ce->t_start_h = ce->tcur;
  ce->nsteps_h = 0;
  ce->guard_pending = true;
  ce->xl1_start = N_VL1Norm(ce->xcur);
  BuildPlans(ce);
  if (HasConstraints(ce)) {
    const long int nfe0 = ce->nfe;
    const int flag = ConstrStart(ce, func);
    ce->nfe_start += ce->nfe - nfe0;
    if (flag == CE_SUCCESS) ce->started = true;
    return flag;
  }
  const long int nfe0 = ce->nfe;
  const sunrealtype t = ce->tcur;
  int flag = EvalAccel(ce, t, ce->xcur, ce->D[1], ce->D[2], func);
  if (flag == CE_SUCCESS && !IsFinite(ce->D[2])) {
    flag = ProcessError(ce, CE_FIRST_RHSFUNC_ERR, func,
                        "The initial acceleration is NaN or Inf: f (or the mass solve) returned "
                        "non-finite values at t0 = %.17g.",
                        static_cast<double>(t));
  }
  if (flag == CE_SUCCESS && !ce->zero_start) {
    flag = StartDerivatives(ce, t, ce->xnew, ce->vtmp, ce->atmp,
                            [&](sunrealtype ts, N_Vector xs, N_Vector vs, N_Vector as) {
                              return EvalAccel(ce, ts, xs, vs, as, func);
                            });
  }
  for (int k = 3; flag == CE_SUCCESS && ce->zero_start && k < d; ++k) N_VConst(0, ce->D[k]);
  ce->nfe_start += ce->nfe - nfe0;
  if (flag != CE_SUCCESS) return flag;
  // First position step: the Taylor polynomial of every derivative known at t0.
  sunrealtype cw[kMaxDegree];
  N_Vector vw[kMaxDegree];
  for (int i = 1; i < d; ++i) {
    cw[i - 1] = std::pow(h, i) / Factorial(i);
    vw[i - 1] = ce->D[i];
  }
  N_VLinearCombination(d - 1, cw, vw, ce->tmp1);
  N_VLinearSum(1, ce->xcur, 1, ce->tmp1, ce->xnext);
  ce->started = true;
  return CE_SUCCESS;
}

sunrealtype FormUpdate(CEodeMemRec* ce) {
  const int ip = static_cast<int>(ce->nsteps_h % kNumPlans);
  sunrealtype xl1 = 0;
  if (!FusedUpdate(ce, ce->fused_plans[ip], &xl1)) {
    const UpdatePlan& plan = ce->plans[ip];
    for (int k = 0; k < plan.n; ++k) RunCombo(ce, plan.combos[k]);
    xl1 = N_VL1Norm(ce->xnew);
  }
  return xl1;
}

int TakeStep(CEodeMemRec* ce) {
  static const char* func = "CEodeEvolve";
  const int d = ce->degree;
  const sunrealtype t = ce->t_start_h + static_cast<sunrealtype>(ce->nsteps_h + 1) * ce->h;
  N_Vector* D = ce->D;
  N_Vector* Dn = ce->Dnew;
  N_Vector a = Dn[2];

  // The only solve of the step: the acceleration at t (and multipliers).
  int flag;
  if (HasConstraints(ce)) {
    flag = ConstrSolveStep(ce, t, ce->xnext, a, func);
  } else if (ce->vel_dependent) {
    flag = SolveImplicit(ce, t, ce->xnext, a, func);
  } else {
    // No velocity dependence declared: f sees the last velocity, D_1(t - h).
    flag = EvalAccel(ce, t, ce->xnext, D[1], a, func);
  }
  if (flag != CE_SUCCESS) return flag;

  const sunrealtype xl1 = FormUpdate(ce);

  // Explosive growth: stop long before overflow, while the state is still readable.
  constexpr sunrealtype kGrowthLimit = 1e15;
  constexpr sunrealtype kAbsoluteLimit = 1e150;
  if (std::isfinite(xl1) && (xl1 > kAbsoluteLimit || xl1 > kGrowthLimit * (1 + ce->xl1_start))) {
    return ProcessError(ce, CE_UNSTABLE, func,
                        "The state grew explosively: ||x||_1 = %g at t = %.17g (step %ld), %g at "
                        "the start. h = %g is most likely beyond the stability limit of %s (h * "
                        "omega_max must stay below Omega_max, see CEodeStabilityLimit); reduce h.",
                        static_cast<double>(xl1), static_cast<double>(t), ce->nst + 1,
                        static_cast<double>(ce->xl1_start), static_cast<double>(ce->h),
                        ce->method_name.c_str());
  }
  if (!std::isfinite(xl1)) {
    const sunrealtype xn = N_VMaxNorm(ce->xnext);
    if (!IsFinite(a) && std::isfinite(xn) && xn < 1e100) {
      return ProcessError(ce, CE_RHSFUNC_FAIL, func,
                          "The acceleration became NaN or Inf at t = %.17g (step %ld) while the "
                          "state was finite (max |x| = %g): f returned non-finite values.",
                          static_cast<double>(t), ce->nst + 1, static_cast<double>(xn));
    }
    return ProcessError(ce, CE_UNSTABLE, func,
                        "The state stopped being finite at t = %.17g (step %ld, max |x| was %g): "
                        "h = %g is most likely beyond the stability limit of %s (h * omega_max "
                        "must stay below Omega_max); reduce h.",
                        static_cast<double>(t), ce->nst + 1, static_cast<double>(xn),
                        static_cast<double>(ce->h), ce->method_name.c_str());
  }

  // Commit: the new derivatives become the history.
  for (int k = 1; k < d; ++k) std::swap(D[k], Dn[k]);
  N_Vector old = ce->xcur;
  ce->xcur = ce->xnext;
  ce->xnext = ce->xnew;
  ce->xnew = old;
  if (ce->compensated) {
    for (int k = 0; k <= d - 2; ++k) std::swap(ce->comp[k], ce->compnew[k]);
  }
  ce->tcur = t;
  ++ce->nsteps_h;
  ++ce->nst;
  if (ce->guard_every > 0 && ce->nst % ce->guard_every == 0) return GuardCheck(ce, func);
  return CE_SUCCESS;
}

void Interpolate(CEodeMemRec* ce, sunrealtype s, int k, N_Vector out) {
  const int d = ce->degree;
  const sunrealtype h = ce->h;
  if (s == 0 && k < d) {  // exactly the method's own values at tcur
    N_VScale(1, k == 0 ? ce->xcur : ce->D[k], out);
    return;
  }
  // p(s) = sum_{i<d} D_i s^i/i! + e s^d, with e fixed by p(h) = x(tcur + h).
  const sunrealtype e = Factorial(d) / Factorial(d - k) * std::pow(s, d - k) / std::pow(h, d);
  sunrealtype c[kMaxDegree + 2];
  N_Vector X[kMaxDegree + 2];
  int m = 0;
  for (int i = 1; i < d; ++i) {
    c[m] = (i >= k ? std::pow(s, i - k) / Factorial(i - k) : 0) - e * std::pow(h, i) / Factorial(i);
    X[m++] = ce->D[i];
  }
  N_VLinearSum(1, ce->xnext, -1, ce->xcur, ce->tmp3);
  c[m] = e;
  X[m++] = ce->tmp3;
  if (k == 0) {
    c[m] = 1;
    X[m++] = ce->xcur;
  }
  Combine(m, c, X, out);
}

}  // namespace ceode
