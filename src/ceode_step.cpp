// The degree-generic conditionally explicit step (docs/theory.md section 2), its
// coefficients, the start of the method and the dense output. One code path
// serves every degree: the parameter sets are data in kMethodSets.
#include <nvector/nvector_serial.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>

#include "ceode_fused.hpp"

namespace ceode {

namespace {

// Named parameter sets (docs/theory.md section 5): alpha, beta, gamma, zeta, then the stability
// limit Omega_max and the default number of PC corrections (both derived by the library's own
// routines and checked against them by the tests). Measured properties (orders, stability
// limits) are in docs/stability.md and the tests.
const MethodSet kMethodSets[] = {
    {"G3_CD", 3, {1.0, 0.5}, 2.0, 1},
    {"G3_A43", 3, {4.0 / 3.0, 0.5}, 1.5491933384830241, 1},
    {"G3_A2", 3, {2.0, 0.5}, 1.1547005383792901, 1},
    {"G4_A54", 4, {5.0 / 4.0, 1.0 / 3.0, 0.5}, 0.0, 2},
    {"G4_A14", 4, {1.0 / 4.0, 1.0 / 3.0, 0.5}, 1.2649110640675025, 1},
    {"G4_A34", 4, {3.0 / 4.0, 1.0 / 3.0, 0.5}, 1.7320508139458268, 1},
    {"G5", 5, {4.0 / 5.0, 1.0, 1.0, 1.0}, 0.0, 2},
    {"G5_TOP", 5, {1.62, 1.03522, 1.0291293, 1.016}, 0.068165690514902844, 2},
    {"G5_ONES", 5, {1.0, 1.0, 1.0, 1.0}, 0.0, 2},
    // Sets found by `ceode-stability find` (commands in docs/stability.md). G5_O4, order 4 in
    // x and x', keeps 98.5 % of central differences' interval (1.97 of 2), under damping too.
    {"G5_O4",
     5,
     {0.92577028540744155, 9.9999972798814163, 6.878731145481118, 0.63619887668052599},
     1.970651340728419,
     2},
    {"G6_O5",
     6,
     {7.8581049690442608, 3.2003060015391878, 2.306472520152492, 1.445972372099134,
      0.78920709629572905},
     0.80495242331772077,
     2},
    {"G6_O6",
     6,
     {2.438146987413893, 1.260773492352264, 1.0359340008566345, 0.84442784269433835,
      0.57681936136099354},
     0.066156247720114997,
     2},
    {"G7_O7",
     7,
     {19.362993681325158, 15.310841926671563, 8.7099568711498723, 3.9685609709725753,
      2.3539640770647496, 0.90130820250696653},
     1.0320137727279115,
     2},
    {"G8_O8",
     8,
     {399.99982239054896, 278.28678067794129, 134.15990720943549, 51.039413540261052,
      20.827940678986256, 6.8588048481939303, 2.805527440772015},
     0.98912640770612792,
     2},
};

sunrealtype Factorial(int n) {
  sunrealtype r = 1;
  for (int i = 2; i <= n; ++i) r *= i;
  return r;
}

}  // namespace

// Weights of the derivatives of orders 0..q on the nodes x[0..m-1] at 0 (Fornberg 1988): the
// recursion builds every lower order on the way, and each order's weights do not depend on
// the higher ones, so one call serves every order with the numbers of separate calls.
void FornbergTable(int q, int m, const sunrealtype* x, sunrealtype (*w)[2 * kMaxDegree + 1]) {
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
  for (int k = 0; k <= q; ++k) {
    for (int i = 0; i < m; ++i) w[k][i] = C[i][k];
  }
}

void FornbergWeights(int q, int m, const sunrealtype* x, sunrealtype* w) {
  sunrealtype table[kMaxDegree][2 * kMaxDegree + 1];
  FornbergTable(q, m, x, table);
  std::copy(table[q], table[q] + m, w);
}

const MethodSet* FindMethodSet(const char* name) {
  if (name == nullptr) return nullptr;
  for (const MethodSet& m : kMethodSets) {
    if (std::strcmp(m.name, name) == 0) return &m;
  }
  return nullptr;
}

const MethodSet* NamedSetWithParams(int degree, const sunrealtype* params) {
  for (const MethodSet& m : kMethodSets) {
    if (m.degree == degree && std::equal(params, params + degree - 1, m.params.begin())) return &m;
  }
  return nullptr;
}

int NumMethodSets() { return static_cast<int>(sizeof(kMethodSets) / sizeof(kMethodSets[0])); }

const MethodSet& MethodSetAt(int index) { return kMethodSets[index]; }

void ComputeStepCoeffs(int d, const sunrealtype* p, sunrealtype h, StepCoeffs* co) {
  *co = StepCoeffs{};
  co->h = h;
  sunrealtype tw[kMaxDegree + 1] = {};  // h^i / i!
  TaylorWeights(h, d, tw);
  // The predictor's weights, once per h: every step reads them (PredictAccel, SolvePC).
  TaylorWeights(h, d - 2, co->pred);
  // Lower derivatives k = 1..d-2: Taylor from t-h with the top term blended by p_k.
  for (int k = 1; k <= d - 2; ++k) {
    for (int i = 0; i <= d - 2 - k; ++i) co->T[k][k + i] = tw[i];
    const sunrealtype top = tw[d - 1 - k];
    co->T[k][d - 1] += top * (1 - p[k]);
    co->c[k] = top * p[k];
  }
  if (d == 3) co->c[2] = 1;  // D_2 is the top derivative itself
  co->c[d - 1] = 1;
  co->kappa = co->c[1] / co->c[2];
  for (int j = 1; j < d; ++j) co->V0[j] = co->T[1][j] - co->kappa * co->T[2][j];
  // Position: Taylor from t with the top term blended by p_0.
  for (int i = 1; i <= d - 2; ++i) co->w[i] = tw[i];
  const sunrealtype top = tw[d - 1];
  co->wz_old = top * (1 - p[0]);
  co->wz_new = top * p[0];
  sunrealtype cx = co->wz_new;
  for (int i = 1; i <= d - 2; ++i) cx += co->w[i] * co->c[i];
  co->mu = cx / co->c[2];
}

int AllocVectors(CEodeMemRec* ce, N_Vector tmpl) {
  N_Vector* all[] = {&ce->xcur, &ce->xnext, &ce->xnew, &ce->vtmp, &ce->atmp,    &ce->tmp1,
                     &ce->tmp2, &ce->tmp3,  &ce->D[1], &ce->D[2], &ce->Dnew[1], &ce->Dnew[2]};
  for (N_Vector* v : all) {
    *v = N_VClone(tmpl);
    if (*v == nullptr) return CE_MEM_FAIL;
  }
  return CE_SUCCESS;
}

bool NeedsSolverWork(const CEodeMemRec* ce) {
  return ce->ls.LS != nullptr || ce->nls.NLS != nullptr || ce->ls.mfn != nullptr ||
         ce->ls.M != nullptr || ce->vel_dependent || ce->adapters.first_order != nullptr ||
         HasConstraints(ce);
}

// Each N_VClone costs about a thousand instructions in Debian's -O0 SUNDIALS (the operation
// table is copied entry by entry): an explicit run without a mass matrix, linear or nonlinear
// solver never clones these seven (docs/results.md, high-degree sets).
int AllocSolverWork(CEodeMemRec* ce, const char* func) {
  if (ce->zero != nullptr) return CE_SUCCESS;
  N_Vector* work[] = {&ce->ftmp, &ce->V0, &ce->apred, &ce->ycor, &ce->ewt, &ce->lstmp, &ce->zero};
  for (N_Vector* v : work) {
    if (*v == nullptr) *v = N_VClone(ce->xcur);
    if (*v == nullptr) return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
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

namespace {

int RhsFailed(CEodeMemRec* ce, int rv, sunrealtype t, const char* func) {
  return ProcessError(ce, CE_RHSFUNC_FAIL, func,
                      "The right-hand side function failed (returned %d) at t = %.17g. A fixed "
                      "step cannot retry with a smaller h: fix f or reduce h.",
                      rv, static_cast<double>(t));
}

}  // namespace

int EvalRhs(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector v, N_Vector f, const char* func) {
  const int rv = CallRhs(ce, t, x, v, f);
  ++ce->nfe;
  return rv == 0 ? CE_SUCCESS : RhsFailed(ce, rv, t, func);
}

int EvalAccel(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector v, N_Vector a,
              const char* func) {
  // No mass matrix (M = I): MassUpdate and MassSolve would do nothing; skip their calls.
  if (ce->ls.mfn == nullptr && ce->ls.M == nullptr) return EvalRhs(ce, t, x, v, a, func);
  int flag = MassUpdate(ce, t, x, func);
  if (flag == CE_SUCCESS) flag = EvalRhs(ce, t, x, v, a, func);
  return flag == CE_SUCCESS ? MassSolve(ce, a, func) : flag;
}

// Every Taylor polynomial of the library (step coefficients, predictors, starts, dense output)
// takes its weights from here.
// The first two weights are exactly 1 and s (pow(s, 0) and pow(s, 1) are exact): no pow call.
void TaylorWeights(sunrealtype s, int m, sunrealtype* w) {
  for (int i = 0; i < m; ++i) w[i] = i == 0 ? 1 : (i == 1 ? s : std::pow(s, i) / Factorial(i));
}

void PredictAccel(const CEodeMemRec* ce, N_Vector a) {
  const int d = ce->degree;
  N_VLinearCombination(d - 2, const_cast<sunrealtype*>(ce->co.pred),
                       const_cast<N_Vector*>(ce->D + 2), a);
}

void VelocityOffset(int d, const StepCoeffs& co, N_Vector* D, N_Vector V0) {
  N_VLinearCombination(d - 1, const_cast<sunrealtype*>(co.V0 + 1), D + 1, V0);
}

int SolveExplicit(CEodeMemRec* ce, sunrealtype t, sunrealtype /*tnext*/, N_Vector x, N_Vector a,
                  const char* func) {
  // No velocity dependence declared: f sees the last velocity, D_1(t - h).
  return EvalAccel(ce, t, x, ce->D[1], a, func);
}

// The update after the solve: z = (a - B_2)/c_2 (d = 3: z is a itself), the
// lower derivatives from the history and z, then the position increment.
void BuildUpdatePlan(int d, const StepCoeffs& co, N_Vector* D, N_Vector* Dn, N_Vector xnext,
                     N_Vector xnew, UpdatePlan* plan) {
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

// The vectors only trade places from step to step (history <-> new every step,
// the three positions in a cycle of three), so six plans, built once per start,
// cover every step: the step itself builds nothing. In-place plans write the InPlaceLevel
// derivatives over their history (Dn[k] = D[k], never swapped): the explicit fused step only,
// whose update runs once per step after f, uncompensated (docs/theory.md, "In-place update").
// The lean loop's steps that write the position over x(t + h) trade only the history's places:
// plan_ix, not the step count, names the configuration.
namespace {

// The six plans from the current vectors; returns whether the fused backend can run them. With
// in_place, also the plans that write the position over its last value; *xin: all were built.
bool BuildPlanCycle(CEodeMemRec* ce, bool in_place, bool fusable, bool* xin) {
  const int d = ce->degree;
  N_Vector D[kMaxDegree];
  N_Vector Dn[kMaxDegree];
  N_Vector comp[kMaxDegree];
  N_Vector compnew[kMaxDegree];
  for (int k = 0; k < kMaxDegree; ++k) {
    D[k] = ce->D[k];
    Dn[k] = in_place && k > 0 && k < d && InPlaceLevel(d, k) ? ce->D[k] : ce->Dnew[k];
    comp[k] = ce->comp[k];
    compnew[k] = ce->compnew[k];
  }
  N_Vector xcur = ce->xcur;
  N_Vector xnext = ce->xnext;
  N_Vector xnew = ce->xnew;
  *xin = in_place && fusable;
  for (int i = 0; i < kNumPlans; ++i) {
    const int ip = (ce->plan_ix + i) % kNumPlans;
    BuildUpdatePlan(d, ce->co, D, Dn, xnext, xnew, &ce->plans[ip]);
    if (fusable) {
      fusable = BuildFusedPlan(ce->plans[ip], {ce->compensated, comp, compnew, nullptr},
                               &ce->fused_plans[ip]);
    }
    if (*xin && fusable) {
      UpdatePlan over = ce->plans[ip];
      Combo& position = over.combos[over.n - 1];
      position.out = position.old;
      *xin = BuildFusedPlan(over, {false, comp, compnew, nullptr}, &ce->fused_plans_xin[ip]);
    }
    for (int k = 1; k < d; ++k) std::swap(D[k], Dn[k]);
    for (int k = 0; k <= d - 2; ++k) std::swap(comp[k], compnew[k]);
    N_Vector old = xcur;
    xcur = xnext;
    xnext = xnew;
    xnew = old;
  }
  return fusable;
}

}  // namespace

void BuildPlans(CEodeMemRec* ce) {
  const bool serial = N_VGetVectorID(ce->xnext) == SUNDIALS_NVEC_SERIAL;
  const bool mpi = !serial && sun::LocalArrayWithReduce(ce->xnext);
  ce->fused_len = serial ? ce->n : (mpi ? ce->xnext->ops->nvgetlocallength(ce->xnext) : 0);
  // In-place plans run on the fused backend only (the N_Vector reference's combinations must
  // not write an input), so when it refuses them the ordinary plans are built instead.
  bool in_place = ce->in_place && ce->fused && (serial || mpi) && !ce->compensated &&
                  ce->solve_accel == SolveExplicit && ce->fused_len >= kInPlaceMinLen;
  bool xin = false;
  bool fusable = BuildPlanCycle(ce, in_place, serial || mpi, &xin);
  if (in_place && !fusable) {
    in_place = false;
    fusable = BuildPlanCycle(ce, false, serial || mpi, &xin);
  }
  ce->in_place_active = in_place;
  // The position over its last value loses x(tcur); after a failing f the lean loop rebuilds it
  // from x(tcur + h) and the history, which for d = 3 needs the old z (f's buffer) to be unused.
  ce->xin_ready = xin && fusable && (ce->degree > 3 || ce->co.wz_old == 0);
  ce->fused_ready = fusable && serial;
  ce->fused_mpi = fusable && mpi;
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

bool CloneIfMissing(N_Vector* v, N_Vector tmpl) {
  if (*v == nullptr) *v = N_VClone(tmpl);
  return *v != nullptr;
}

// The derivative vectors of the degree (and their compensations) exist once per degree.
int AllocHistory(CEodeMemRec* ce, const char* func) {
  const int d = ce->degree;
  bool ok = true;
  for (int k = 1; k < d; ++k) {
    ok = ok && CloneIfMissing(&ce->D[k], ce->xcur) && CloneIfMissing(&ce->Dnew[k], ce->xcur);
  }
  for (int k = 0; ce->compensated && k <= d - 2; ++k) {
    ok = ok && CloneIfMissing(&ce->comp[k], ce->xcur) && CloneIfMissing(&ce->compnew[k], ce->xcur);
    if (ok) N_VConst(0, ce->comp[k]);
  }
  return ok ? CE_SUCCESS : ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
}

// The unconstrained start: a0 = M^{-1} f(t0, x0, v0), the higher derivatives (consistent start)
// or zeros (the paper's zero start), then the first position step: the Taylor polynomial of
// every derivative known at t0.
int OdeStart(CEodeMemRec* ce, const char* func) {
  const int d = ce->degree;
  const sunrealtype t = ce->tcur;
  const bool preset = ce->adapters.history_preset;  // from Reset (an adapter's restart)
  ce->adapters.history_preset = false;
  int flag = preset ? CE_SUCCESS : EvalAccel(ce, t, ce->xcur, ce->D[1], ce->D[2], func);
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
  ComputeStepCoeffs(ce->degree, ce->params, ce->h, &ce->co);
  ce->t_start_h = ce->tcur;
  ce->nsteps_h = 0;
  ce->plan_ix = 0;
  ce->guard.pending = true;
  ce->xl1_start = N_VL1Norm(ce->xcur);
  ce->solve_accel = HasConstraints(ce)  ? ConstrSolveStep
                    : ce->vel_dependent ? SolveImplicit
                                        : SolveExplicit;
  const long int nfe0 = ce->nfe;
  flag = HasConstraints(ce) ? ConstrStart(ce, func) : OdeStart(ce, func);
  ce->nfe_start += ce->nfe - nfe0;  // the start's evaluations, reported apart from the steps'
  if (flag == CE_SUCCESS) flag = ChooseImplicitSolve(ce, func);  // may replace solve_accel
  if (flag == CE_SUCCESS) BuildPlans(ce);  // in place or not depends on the solve
  if (flag == CE_SUCCESS) ce->started = true;
  return flag;
}

namespace {

// Time k steps after tcur, from the last (re)start, so that rounding does not accumulate.
sunrealtype StepTime(const CEodeMemRec* ce, int k) {
  return ce->t_start_h + static_cast<sunrealtype>(ce->nsteps_h + k) * ce->h;
}

// ||x||_1 over every rank from this rank's part (any: a vector of the run, for its
// communicator); NaN when the reduction failed.
inline sunrealtype GlobalL1(CEodeMemRec* ce, N_Vector any, sunrealtype local) {
  if (N_VDotProdMultiAllReduce(1, any, &local) != 0) {
    ce->reduce_failed = true;  // CheckState names the communication, not the state
    return std::nan("");
  }
  return local;
}

// The step's update after the solve (inlined into TakeStep: a call less per step); returns
// ||x(t + h)||_1 for the growth check, NaN when its global reduction failed.
inline sunrealtype Update(CEodeMemRec* ce) {
  const int ip = ce->plan_ix;
  if (ce->fused && ce->fused_ready) return UpdateSerial(ce->fused_plans[ip], ce->n);
  if (ce->fused && ce->fused_mpi) {  // the same kernel on the local part, one allreduce
    return GlobalL1(ce, ce->xnew, UpdateSerial(ce->fused_plans[ip], ce->fused_len));
  }
  UpdateReference(ce->plans[ip], {ce->compensated, ce->comp, ce->compnew, ce->tmp1});
  return N_VL1Norm(ce->xnew);
}

// The bound on ||x||_1 relative to the start's, and whether a finite ||x||_1 has grown past it
// (or past an absolute limit): explosively.
inline sunrealtype GrowthBound(const CEodeMemRec* ce) {
  constexpr sunrealtype kGrowthLimit = 1e15;
  return kGrowthLimit * (1 + ce->xl1_start);
}
inline bool Exploded(sunrealtype xl1, sunrealtype bound) {
  constexpr sunrealtype kAbsoluteLimit = 1e150;
  return xl1 > kAbsoluteLimit || xl1 > bound;
}

// A non-finite update after the lean loop wrote the position over x(t): the acceleration tells
// f from the step size (x(t) was finite when it passed the last step's check).
int PositionLostFailure(CEodeMemRec* ce, sunrealtype t, const char* func) {
  if (!IsFinite(ce->Dnew[2])) {
    return ProcessError(ce, CE_RHSFUNC_FAIL, func,
                        "The acceleration became NaN or Inf at t = %.17g (step %ld) from a finite "
                        "state: f returned non-finite values.",
                        static_cast<double>(t), ce->nst + 1);
  }
  return ProcessError(ce, CE_UNSTABLE, func,
                      "The state stopped being finite at t = %.17g (step %ld) with a finite "
                      "acceleration: h = %g is most likely beyond the stability limit of %s (h * "
                      "omega_max must stay below Omega_max); reduce h.",
                      static_cast<double>(t), ce->nst + 1, static_cast<double>(ce->h),
                      ce->method_name.c_str());
}

// What a step that failed after its update gives back: the in-place plans have written the
// velocity (and, when x_kept is false, the position) over the last completed step's.
const char* ReturnedState(const CEodeMemRec* ce, bool x_kept) {
  if (!ce->in_place_active) return "the state returned is that of the last completed step";
  return x_kept ? "the position returned is the last completed step's, the velocity the failed "
                  "step's (written in place): restart with CEodeReInit"
                : "the position and velocity returned are the failed step's (written in place): "
                  "restart with CEodeReInit";
}

// Explosive growth or a non-finite state: stop long before overflow, while the state is still
// readable, and say whether f or the step size is to blame. x_kept: x(t) is still in xnext.
int CheckState(CEodeMemRec* ce, sunrealtype t, sunrealtype xl1, const char* func,
               bool x_kept = true) {
  if (ce->reduce_failed) {
    ce->reduce_failed = false;
    return ProcessError(ce, CE_VECTOROP_ERR, func,
                        "The global reduction of the step's growth check failed at t = %.17g (step "
                        "%ld): N_VDotProdMultiAllReduce (an MPI_Allreduce on NVECTOR_PARALLEL) "
                        "returned an error, so the vector's communicator failed; %s "
                        "(docs/theory.md, \"In-place update\").",
                        static_cast<double>(t), ce->nst + 1, ReturnedState(ce, x_kept));
  }
  if (std::isfinite(xl1) && Exploded(xl1, GrowthBound(ce))) {
    return ProcessError(ce, CE_UNSTABLE, func,
                        "The state grew explosively: ||x||_1 = %g at t = %.17g (step %ld), %g at "
                        "the start. h = %g is most likely beyond the stability limit of %s (h * "
                        "omega_max must stay below Omega_max, see CEodeStabilityLimit); reduce h.",
                        static_cast<double>(xl1), static_cast<double>(t), ce->nst + 1,
                        static_cast<double>(ce->xl1_start), static_cast<double>(ce->h),
                        ce->method_name.c_str());
  }
  if (std::isfinite(xl1)) return CE_SUCCESS;
  if (!x_kept) return PositionLostFailure(ce, t, func);
  const sunrealtype xn = MaxNormOrNaN(ce->xnext);  // NaN-blind N_VMaxNorm would say 0
  if (!std::isfinite(xn)) {  // x(t) passed the last step's check: a callback overwrote it
    return ProcessError(ce, CE_RHSFUNC_FAIL, func,
                        "The position x(t) became non-finite (max |x| = %g) during the step at "
                        "t = %.17g: a callback (f, the mass or Jacobian function) wrote NaN or "
                        "Inf into its input x; callbacks must not modify x.",
                        static_cast<double>(xn), static_cast<double>(t));
  }
  if (!IsFinite(ce->Dnew[2]) && xn < 1e100) {
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

// The new derivatives become the history; the three positions rotate.
// Whole arrays, not the degree's slots: a fixed-length swap compiles to a few vector moves
// instead of a loop; the slots at and above the degree are spare buffers and D[0] is unused.
// Two rotations of the history and three of the positions are the identity.
inline void RotateHistory(CEodeMemRec* ce) {
  if (ce->in_place_active) {  // the other levels were written over their history
    std::swap(ce->D[2], ce->Dnew[2]);
    if (ce->degree > 3) std::swap(ce->D[ce->degree - 1], ce->Dnew[ce->degree - 1]);
  } else {
    std::swap(ce->D, ce->Dnew);
  }
  if (ce->compensated) std::swap(ce->comp, ce->compnew);
}
inline void RotatePositions(CEodeMemRec* ce) {
  N_Vector old = ce->xcur;
  ce->xcur = ce->xnext;
  ce->xnext = ce->xnew;
  ce->xnew = old;
}
inline void RotateVectors(CEodeMemRec* ce) {
  RotateHistory(ce);
  RotatePositions(ce);
  ce->plan_ix = ce->plan_ix == kNumPlans - 1 ? 0 : ce->plan_ix + 1;
}

void Commit(CEodeMemRec* ce, sunrealtype t) {
  RotateVectors(ce);
  ce->tcur = t;
  ++ce->nsteps_h;
  ++ce->nst;
}

}  // namespace

// One step: predict and solve for the acceleration at t (the solve chosen at the start:
// SolveExplicit, SolveImplicit or ConstrSolveStep; the constraint holds at tnext), update the
// derivatives and x(t + h), check, commit.
int TakeStep(CEodeMemRec* ce) {
  static const char* func = "CEodeEvolve";
  const sunrealtype t = StepTime(ce, 1);
  const sunrealtype tnext = StepTime(ce, 2);
  int flag = ce->solve_accel(ce, t, tnext, ce->xnext, ce->Dnew[2], func);
  if (flag == CE_SUCCESS) {
    const sunrealtype xl1 = Update(ce);
    if (!std::isfinite(xl1) || Exploded(xl1, GrowthBound(ce))) flag = CheckState(ce, t, xl1, func);
  }
  if (flag != CE_SUCCESS) return flag;
  Commit(ce, t);
  if (ce->guard.every > 0 && ce->nst % ce->guard.every == 0) return GuardCheck(ce, func);
  return CE_SUCCESS;
}

namespace {

// The vectors f reads and writes in one of the six configurations of the step.
struct PhaseVectors {
  N_Vector x, v, a;
  const FusedPlan* plan;
  SerialKernelFn update;       // UpdateSerial's kernel for the plan, chosen once
  const FusedPlan* plan_over;  // the plan writing the position over x(t + h); nullptr: none
  SerialKernelFn update_over;
};

// Below this many steps to go the table of the lean loop costs more than it saves (CE_ONE_STEP).
constexpr long int kLeanMinSteps = 8;

// The steps the lean loop takes unless one fails: at most max_steps, none past the guard's next
// check, and as many as StepsRemain admits on the very times the loop will set (StepTime), so
// that the loop knows its last step in advance.
long int LeanStepCount(const CEodeMemRec* ce, sunrealtype target, long int max_steps) {
  long int cap = max_steps;
  if (ce->guard.every > 0) cap = std::min(cap, ce->guard.every - ce->nst % ce->guard.every);
  const auto remains = [&](long int j) {
    const sunrealtype tj =
        j == 0 ? ce->tcur : ce->t_start_h + static_cast<sunrealtype>(ce->nsteps_h + j) * ce->h;
    return target - tj > ce->h * (1 - 1e-8);
  };
  const sunrealtype guess = std::floor((target - ce->tcur) / ce->h);
  long int j =
      guess > 0 ? static_cast<long int>(std::min(guess, static_cast<sunrealtype>(cap))) : 0;
  while (j > 0 && !remains(j - 1)) --j;
  while (j < cap && remains(j)) ++j;
  return j;
}

// x(tcur) from x(tcur + h) less the last step's position increment (BuildUpdatePlan's last sum),
// after the lean loop wrote the position over it: equal to rounding, not bit for bit.
void RebuildPosition(CEodeMemRec* ce) {
  const int d = ce->degree;
  const StepCoeffs& co = ce->co;
  sunrealtype c[kMaxDegree + 2];
  N_Vector X[kMaxDegree + 2];
  int m = 0;
  c[m] = 1;
  X[m++] = ce->xnext;
  for (int i = 1; i <= d - 2; ++i) {
    c[m] = -co.w[i];
    X[m++] = ce->D[i];
  }
  if (co.wz_old != 0) {  // z(tcur - h); d = 3 (f's buffer) is excluded by xin_ready
    c[m] = -co.wz_old;
    X[m++] = ce->Dnew[d - 1];
  }
  c[m] = -co.wz_new;
  X[m++] = ce->D[d - 1];
  N_VLinearCombination(m, c, X, ce->xcur);
}

// How the lean loop ended, for LeanExit.
struct LeanEnd {
  long int steps = 0;        // completed
  long int moved = 0;        // of them, those that rotated the positions
  bool over = false;         // the last completed step wrote the position over x(tcur)
  bool failed_over = false;  // the failing update wrote over x(tcur + h)
  int rv = 0;
  bool state_ok = true;
  sunrealtype t = 0, xl1 = 0;
};

// Brings the vectors to the state TakeStep would have left (the position to rounding, or the
// failed step's, where it was written over), then reports as TakeStep does.
int LeanExit(CEodeMemRec* ce, int ip, const LeanEnd& e, long int* taken) {
  static const char* func = "CEodeEvolve";
  if (e.steps % 2 != 0) RotateHistory(ce);
  for (long int j = 0; j < e.moved % 3; ++j) RotatePositions(ce);
  ce->plan_ix = ip;
  *taken = e.steps;
  if (e.rv != 0) {
    if (e.over) RebuildPosition(ce);
    return RhsFailed(ce, e.rv, e.t, func);
  }
  if (!e.state_ok) {
    if (e.over) N_VScale(1, e.failed_over ? ce->xnext : ce->xnew, ce->xcur);
    return CheckState(ce, e.t, e.xl1, func, !e.failed_over);
  }
  const bool guard_due = e.steps > 0 && ce->guard.every > 0 && ce->nst % ce->guard.every == 0;
  return guard_due ? GuardCheck(ce, func) : CE_SUCCESS;
}

// TakeStep's explicit step on serial (or NVECTOR_PARALLEL: the same kernel on this rank's part,
// one allreduce per step) vectors without a mass matrix, many in a row: f's vectors
// come from a table of the six configurations and the vectors rotate once at the end, so that a
// step at n = 1 is f, the update and a few tests (bench_step, docs/results.md). With in-place
// plans every step but the last writes x(t + 2h) over x(t + h), as a hand loop does
// (docs/theory.md, "In-place update").
__attribute__((noinline)) int LeanExplicitSteps(CEodeMemRec* ce, sunrealtype target,
                                                long int max_steps, long int* taken) {
  const sunindextype len = ce->fused_len;  // this rank's part on NVECTOR_PARALLEL
  PhaseVectors pv[kNumPlans];
  int ip = ce->plan_ix;
  for (int j = 0; j < kNumPlans; ++j) {
    const int i = (ip + j) % kNumPlans;
    const FusedPlan* over = ce->xin_ready ? &ce->fused_plans_xin[i] : nullptr;
    pv[i] = {ce->xnext,
             ce->D[1],
             ce->Dnew[2],
             &ce->fused_plans[i],
             SerialKernel(ce->fused_plans[i], len),
             over,
             over != nullptr ? SerialKernel(*over, len) : nullptr};
    RotateVectors(ce);
  }
  const sunrealtype bound = GrowthBound(ce);  // xl1_start is fixed between restarts
  // The right-hand side is chosen once: the user's f directly, or the adapters' (CallRhs).
  const bool own_f = ce->adapters.rhs == nullptr;
  const CEodeRhsFn rhs = own_f ? ce->f : ce->adapters.rhs;
  void* const rhs_data = own_f ? ce->user_data : static_cast<void*>(ce);
  const long int count = LeanStepCount(ce, target, max_steps);
  LeanEnd e;
  while (e.steps < count) {
    e.t = StepTime(ce, 1);
    const PhaseVectors& p = pv[ip];
    e.rv = rhs(e.t, p.x, p.v, p.a, rhs_data);
    ++ce->nfe;
    if (e.rv != 0) break;
    const bool over = p.plan_over != nullptr && e.steps + 1 < count;
    e.xl1 = over ? p.update_over(*p.plan_over, len) : p.update(*p.plan, len);
    if (ce->fused_mpi) e.xl1 = GlobalL1(ce, p.x, e.xl1);  // one allreduce, as TakeStep's
    e.state_ok = std::isfinite(e.xl1) && !Exploded(e.xl1, bound);
    if (!e.state_ok) {
      e.failed_over = over;
      break;
    }
    ce->tcur = e.t;
    ++ce->nsteps_h;
    ++ce->nst;
    ++e.steps;
    e.over = over;
    e.moved += over ? 0 : 1;
    ip = (ip + (over ? 3 : 1)) % kNumPlans;  // over: the positions keep their buffers
  }
  return LeanExit(ce, ip, e, taken);
}

}  // namespace

int TakeSteps(CEodeMemRec* ce, sunrealtype target, long int max_steps, long int* taken) {
  // The distance first: a CE_ONE_STEP call decides on it alone.
  const bool lean = target - ce->tcur > kLeanMinSteps * ce->h && max_steps >= kLeanMinSteps &&
                    ce->fused && (ce->fused_ready || ce->fused_mpi) &&
                    ce->solve_accel == SolveExplicit && ce->ls.mfn == nullptr &&
                    ce->ls.M == nullptr;
  if (lean) return LeanExplicitSteps(ce, target, max_steps, taken);
  const int flag = TakeStep(ce);
  *taken = flag == CE_SUCCESS ? 1 : 0;
  return flag;
}

namespace {

// The one-step output copies: memcpy on serial vectors (N_VScale(1, ...) is a multiply loop,
// unoptimised in Debian's -O0 SUNDIALS build), N_VScale elsewhere. Same values either way.
// Once both IDs say serial, the content is read directly (NV_DATA_S, NV_LENGTH_S): every
// getter is two calls through SUNDIALS, and these copies run twice per CE_ONE_STEP call.
void CopyVector(N_Vector from, N_Vector to) {
  if (N_VGetVectorID(from) == SUNDIALS_NVEC_SERIAL && N_VGetVectorID(to) == SUNDIALS_NVEC_SERIAL) {
    const sunrealtype* src = NV_DATA_S(from);
    sunrealtype* dst = NV_DATA_S(to);
    if (src != nullptr && dst != nullptr) {
      if (src != dst) std::memcpy(dst, src, sizeof(sunrealtype) * NV_LENGTH_S(from));
      return;
    }
  }
  N_VScale(1, from, to);
}

// p(s) = sum_{i<d} D_i s^i/i! + e s^d, with e fixed by p(h) = x(tcur + h). Apart from
// Interpolate so that the copy at s = 0 (every CE_ONE_STEP output) does not set up its frame.
__attribute__((noinline)) void InterpolatePolynomial(CEodeMemRec* ce, sunrealtype s, int k,
                                                     N_Vector out) {
  const int d = ce->degree;
  const sunrealtype h = ce->h;
  const sunrealtype e = Factorial(d) / Factorial(d - k) * std::pow(s, d - k) / std::pow(h, d);
  sunrealtype ts[kMaxDegree + 1];
  sunrealtype th[kMaxDegree + 1];
  TaylorWeights(s, d, ts);
  TaylorWeights(h, d, th);
  sunrealtype c[kMaxDegree + 2];
  N_Vector X[kMaxDegree + 2];
  int m = 0;
  for (int i = 1; i < d; ++i) {
    c[m] = (i >= k ? ts[i - k] : 0) - e * th[i];
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

}  // namespace

void Interpolate(CEodeMemRec* ce, sunrealtype s, int k, N_Vector out) {
  if (s == 0 && k < ce->degree) {  // exactly the method's own values at tcur
    CopyVector(k == 0 ? ce->xcur : ce->D[k], out);
    return;
  }
  InterpolatePolynomial(ce, s, k, out);
}

}  // namespace ceode
