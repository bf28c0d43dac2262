// The start of the method (docs/theory.md section 6): the vectors of a run, the history at t0
// (consistent: the higher derivatives by central differences of the acceleration, for high
// degrees by Picard sweeps of central stencils; or the zero start), the first position step,
// and StartMethod, which ends by choosing the step (ChooseStep, ceode_step.cpp).
#include <algorithm>

#include "ceode_adapt.hpp"
#include "ceode_kernels.hpp"

namespace ceode {

int AllocVectors(CEodeMemRec* ce, N_Vector tmpl) {
  if (!AllocStepRecord(ce)) return CE_MEM_FAIL;
  N_Vector* all[] = {&ce->xcur, &ce->xnext, &ce->xnew, &ce->vtmp, &ce->atmp,    &ce->tmp1,
                     &ce->tmp2, &ce->tmp3,  &ce->D[1], &ce->D[2], &ce->Dnew[1], &ce->Dnew[2]};
  for (N_Vector* v : all) {
    *v = CloneVector(tmpl);
    if (*v == nullptr) return CE_MEM_FAIL;
  }
  return CE_SUCCESS;
}

bool NeedsSolverWork(const CEodeMemRec* ce) {
  return ce->ls.LS != nullptr || ce->nls.NLS != nullptr || ce->ls.mfn != nullptr ||
         ce->ls.M != nullptr || ce->vel_dependent || ce->adapters.first_order != nullptr ||
         HasConstraints(ce);
}

// The solvers' work vectors, cloned by the (re)start that needs them: an explicit run without a
// mass matrix, linear or nonlinear solver makes none of these seven.
int AllocSolverWork(CEodeMemRec* ce, const char* func) {
  if (ce->zero != nullptr) return CE_SUCCESS;
  N_Vector* work[] = {&ce->ftmp, &ce->V0, &ce->apred, &ce->ycor, &ce->ewt, &ce->lstmp, &ce->zero};
  for (N_Vector* v : work) {
    if (!CloneMissing(v, ce->xcur)) return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
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
  for (N_Vector& w : ce->compwork) {
    if (w != nullptr) N_VDestroy(w);
    w = nullptr;
  }
  ce->initialized = false;
}

namespace {

// The widest stencil's half width: an order never exceeds the degree (HalfWidth).
constexpr int kMaxHalfWidth = (kMaxDegree - 1) / 2;

// The order the start serves: a named set's order, else d (orders reach d, never d + 1).
int StartOrder(const CEodeMemRec* ce) {
  const int d = ce->degree;
  const MethodSet* m = NamedSetWithParams(d, ce->params);
  return m != nullptr ? std::min(m->order_x, d) : d;
}

// Half width R of the stencil: the q-th derivative of the acceleration on 2R + 1 nodes
// spaced h errs by O(h^(2R+1-q)), so D_k = a^(k-2) errs by O(h^(2R+3-k)); an order-p set
// keeps its order when that is O(h^(p+1-k)), i.e. 2R + 2 >= p, and the stencil must reach the
// derivative d - 3 (2R >= d - 3): R = 2 at degree 6, 3 at degrees 7 and 8.
int HalfWidth(const CEodeMemRec* ce) {
  return std::max((StartOrder(ce) - 1) / 2, (ce->degree - 2) / 2);
}

// The gain g of a sweep: an error e in D_k reaches the samples as the term e s^k / k! of the
// position (f does not read the velocity) or e s^(k-1) / (k-1)! of the velocity (it does), which
// the stencil differentiates exactly into D_(k+2) or D_(k+1) (times df/dx or df/dv): each sweep
// moves every error g derivatives up, so the derivatives below 3 + g i are fixed after i sweeps.
int SweepGain(bool vel_dependent) { return vel_dependent ? 1 : 2; }

// Sweeps until D_3 .. D_(d-1) are fixed and only the stencil's truncation is left (see
// StartDerivativesHigh): d - 3 when f reads the velocity, ceil((d - 3) / 2) when it does not
// (docs/theory.md section 6.3).
int Sweeps(int d, bool vel_dependent) { return vel_dependent ? d - 3 : (d - 2) / 2; }

// The half width of sweep i (from 1) of S. The last one is R. Before it a narrower stencil
// suffices: an error O(h^e) that sweep i leaves in D_k ends, moved g (S - i) derivatives up, in
// D_(k + g(S-i)), which needs O(h^(p+1-k-g(S-i))). The stencil's truncation, O(h^(2r+3-k)), meets
// that when 2r >= p - 2 - g(S - i); so does its aliasing, the terms of degree above 2r of an
// error not fixed yet (O(1), in D_k' from k' = 3 + g(i - 1) on), which reach D_k as
// O(h^(k'+g-k)). Hence r = max(1, ceil((p - 2 - g(S - i)) / 2)) (docs/theory.md section 6.3).
int SweepHalfWidth(int i, int sweeps, int R, int p, bool vel_dependent) {
  if (i == sweeps) return R;
  const int twice = p - 2 - SweepGain(vel_dependent) * (sweeps - i);
  return std::min(R, std::max(1, (twice + 1) / 2));
}

// The Taylor curve at s: xs = sum_{i<d} D_i s^i/i! (D_0 = x), vs its derivative (the same
// weights, shifted).
void TaylorPlan(const CEodeMemRec* ce, sunrealtype s, N_Vector xs, N_Vector vs, KernelPlan* sp) {
  const int d = ce->degree;
  UpdatePlan& p = sp->plan;
  p.n = 2;
  p.combos[0] = Combo{};
  p.combos[1] = Combo{};
  sunrealtype w = 1;  // s^i / i!
  for (int i = 0; i < d; ++i) {
    p.combos[0].Add(w, i == 0 ? ce->xcur : ce->D[i]);
    if (i < d - 1) p.combos[1].Add(w, ce->D[i + 1]);
    w *= s / (i + 1);
  }
  p.combos[0].out = xs;
  p.combos[1].out = vs;
}

// The central stencils' weights at unit spacing, w[r - 1][q][j] for the q-th derivative (q <= 2r)
// from the node j - r, computed once: a start scales them by h^-q instead of building its tables.
using StencilWeights = sunrealtype[kMaxDegree][2 * kMaxDegree + 1];
const StencilWeights& UnitStencil(int r) {
  static const auto* const weights = [] {
    static StencilWeights w[kMaxHalfWidth];
    for (int hw = 1; hw <= kMaxHalfWidth; ++hw) {
      sunrealtype nodes[2 * kMaxDegree + 1] = {};
      for (int j = 0; j <= 2 * hw; ++j) nodes[j] = j - hw;
      FornbergTable(std::min(2 * hw, kMaxDegree - 1), 2 * hw + 1, nodes, w[hw - 1]);
    }
    return w;
  }();
  return weights[r - 1];
}

// The stencil of half width r: D_3 .. D_(min(d-1, 2r+2)) from a_0 (in D_2) and the samples at
// s = jh, j = -r..r, j != 0 (sample[]: by their index on the widest stencil), term for term in the
// order of a running sum, so the derivatives come out as if accumulated node by node.
void StencilPlan(const CEodeMemRec* ce, int R, int r, const N_Vector* sample, KernelPlan* sp) {
  const int top = std::min(ce->degree - 1, 2 * r + 2);  // the highest derivative it reaches
  const StencilWeights& w = UnitStencil(r);
  UpdatePlan& p = sp->plan;
  p.n = top - 2;
  sunrealtype scale = 1;  // h^-q
  for (int k = 3; k <= top; ++k) {
    scale /= ce->h;
    Combo& cb = p.combos[k - 3];
    cb = Combo{};
    cb.Add(w[k - 2][r] * scale, ce->D[2]);
    for (int j = 0; j <= 2 * r; ++j) {
      const int jR = j - r + R;  // the node's index on the widest stencil
      if (j != r) cb.Add(w[k - 2][j] * scale, sample[jR < R ? jR : jR - 1]);
    }
    cb.out = ce->D[k];
  }
}

// Each sweep evaluates the acceleration at its 2r nodes along the Taylor polynomial of all current
// derivatives and replaces those its stencil reaches (SweepGain, SweepHalfWidth): d - 3 or
// ceil((d - 3) / 2) sweeps leave only the last stencil's own O(h^(2R+1-q)) truncation. The samples
// of a sweep are kept (in Dnew[1..d-1] and as: 2R <= d vectors, all free before the first step) and
// combined once at the sweep's end.
int StartDerivativesHigh(
    CEodeMemRec* ce, sunrealtype t0, N_Vector xs, N_Vector vs, N_Vector as,
    const std::function<int(sunrealtype, N_Vector, N_Vector, N_Vector)>& accel) {
  const int d = ce->degree;
  const sunrealtype h = ce->h;
  const int R = HalfWidth(ce);
  sunrealtype nodes[2 * kMaxHalfWidth];  // s of sample i: -R h .. -h, h .. R h
  for (int i = 0; i < 2 * R; ++i) nodes[i] = (i < R ? i - R : i - R + 1) * h;
  N_Vector sample[2 * kMaxHalfWidth];
  for (int i = 0; i < 2 * R; ++i) sample[i] = i + 1 < d ? ce->Dnew[i + 1] : as;
  // The start's combinations on the serial backend where the step's update would run on it.
  const bool serial = FusedKernelOn(ce) && N_VGetVectorID(ce->xcur) == SUNDIALS_NVEC_SERIAL;
  KernelPlan taylor[2 * kMaxHalfWidth];  // a plan is a few kilobytes: as many as the nodes
  bool prepared[2 * kMaxHalfWidth] = {};
  KernelPlan stencil;
  int stencil_r = 0;
  for (int k = 3; k < d; ++k) N_VConst(0, ce->D[k]);
  int flag = CE_SUCCESS;
  const int sweeps = Sweeps(d, ce->vel_dependent);
  const int p = StartOrder(ce);
  for (int sweep = 1; sweep <= sweeps && flag == CE_SUCCESS; ++sweep) {
    const int r = SweepHalfWidth(sweep, sweeps, R, p, ce->vel_dependent);
    for (int i = R - r; i < R + r && flag == CE_SUCCESS; ++i) {
      if (!prepared[i]) {
        TaylorPlan(ce, nodes[i], xs, vs, &taylor[i]);
        PreparePlan(serial, &taylor[i]);
        prepared[i] = true;
      }
      RunPlan(taylor[i], ce->n);
      flag = accel(t0 + nodes[i], xs, vs, sample[i]);
    }
    if (flag != CE_SUCCESS) break;
    if (r != stencil_r) {
      StencilPlan(ce, R, r, sample, &stencil);
      PreparePlan(serial, &stencil);
      stencil_r = r;
    }
    RunPlan(stencil, ce->n);
  }
  return flag;
}

}  // namespace

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
      TaylorWeights(s, m + 1, cx);
      for (int i = 0; i <= m; ++i) vx[i] = (i == 0) ? ce->xcur : ce->D[i];
      N_VLinearCombination(m + 1, cx, vx, xs);
      N_VLinearCombination(m, cx, vx + 1, vs);  // the curve's derivative: same weights, shifted
      flag = accel(t0 + s, xs, vs, as);
      if (flag == CE_SUCCESS) N_VLinearSum(1, out, wts[j], as, out);
    }
  }
  return flag;
}

namespace {

// The derivative vectors of the degree (and their compensations) exist once per degree.
int AllocHistory(CEodeMemRec* ce, const char* func) {
  const int d = ce->degree;
  bool ok = true;
  for (int k = 1; k < d; ++k) {
    ok = ok && CloneMissing(&ce->D[k], ce->xcur) && CloneMissing(&ce->Dnew[k], ce->xcur);
  }
  for (int k = 0; ce->compensated && k <= d - 2; ++k) {
    ok = ok && CloneMissing(&ce->comp[k], ce->xcur) && CloneMissing(&ce->compnew[k], ce->xcur);
    if (ok) N_VConst(0, ce->comp[k]);
  }
  for (int k = 0; ce->compensated && k < kCompWork; ++k) {
    ok = ok && CloneMissing(&ce->compwork[k], ce->xcur);
  }
  return ok ? CE_SUCCESS : ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
}

// The unconstrained start: a0 = M^{-1} f(t0, x0, v0), the higher derivatives (consistent start)
// or zeros (the paper's zero start), then the first position step: the Taylor polynomial of
// every derivative known at t0. accel: D_2 holds a0 already (error control's first step took it).
int OdeStart(CEodeMemRec* ce, const char* func, bool accel) {
  const int d = ce->degree;
  const sunrealtype t = ce->tcur;
  const bool preset = ce->adapters.history_preset;  // from Reset (an adapter's restart)
  ce->adapters.history_preset = false;
  int flag = preset || accel ? CE_SUCCESS : EvalAccel(ce, t, ce->xcur, ce->D[1], ce->D[2], func);
  if (flag == CE_SUCCESS && !IsFinite(ce->D[2])) {
    flag = ProcessError(ce, CE_FIRST_RHSFUNC_ERR, func,
                        "The initial acceleration is NaN or Inf: f (or the mass solve) returned "
                        "non-finite values at t0 = %.17g.",
                        static_cast<double>(t));
  }
  if (flag == CE_SUCCESS && !ce->zero_start && !preset) {
    flag = StartDerivatives(ce, t, ce->xnew, ce->vtmp, ce->atmp,
                            [&](sunrealtype ts, N_Vector xs, N_Vector vs, N_Vector as) {
                              return EvalAccel(ce, ts, xs, vs, as, func);
                            });
  }
  if (flag != CE_SUCCESS) return flag;
  if (!preset) GuardStartAccel(ce);  // D_2 = M^{-1} f(t0, x0, v0), evaluated here
  for (int k = 3; ce->zero_start && k < d; ++k) N_VConst(0, ce->D[k]);
  sunrealtype cw[kMaxDegree];
  N_Vector vw[kMaxDegree];
  TaylorWeights(ce->h, d, cw);
  for (int i = 1; i < d; ++i) vw[i - 1] = ce->D[i];
  N_VLinearCombination(d - 1, cw + 1, vw, ce->tmp1);
  N_VLinearSum(1, ce->xcur, 1, ce->tmp1, ce->xnext);
  return CE_SUCCESS;
}

}  // namespace

int StartMethod(CEodeMemRec* ce) {
  static const char* func = "CEodeEvolve";
  int flag = AllocHistory(ce, func);
  if (flag != CE_SUCCESS) return flag;
  const long int nfe0 = ce->nfe;
  const bool adapt = AdaptOn(ce);
  bool accel = false;  // a0 in D_2 from error control's first step
  if (adapt) flag = AdaptStart(ce, func, &accel);
  if (flag != CE_SUCCESS) return flag;
  ComputeStepCoeffs(ce->degree, ce->params, ce->h, &ce->co);
  ce->t_start_h = ce->tcur;
  ce->nsteps_h = 0;
  ce->guard.pending = true;
  ce->xl1_start = N_VL1Norm(ce->xcur);
  flag = HasConstraints(ce) ? ConstrStart(ce, func) : OdeStart(ce, func, accel);
  ce->nfe_start += ce->nfe - nfe0;  // the start's evaluations, reported apart from the steps'
  if (flag == CE_SUCCESS && adapt) AdaptStartHistory(ce);
  if (flag == CE_SUCCESS) flag = ChooseImplicitSolve(ce, func);  // PC, Newton or AUTO
  if (flag == CE_SUCCESS) ChooseStep(ce, true);
  if (flag == CE_SUCCESS) ce->started = true;
  return flag;
}

}  // namespace ceode
