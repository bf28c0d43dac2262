// The adaptive step (docs/theory.md section 12): the step of the fixed run with the interval it
// actually spans in each relation, the local error estimate from divided differences of the
// accelerations (no extra f), the error test with a retry that redoes only the position update,
// and CEodeEvolve's returns by the dense output of the last accepted step.
#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <cstring>
#include <utility>

#include "ceode_adapt.hpp"
#include "ceode_kernels.hpp"
#include "ceode_step.hpp"

namespace ceode {

namespace {

constexpr sunrealtype kGrowthLimit = 1e15;  // as the fixed step's growth check
constexpr int kStartAgain = 1;              // OneStep: the first step failed, start with a smaller

// x^j by multiplication (the remap's and the estimate's powers are small integers).
sunrealtype IntPow(sunrealtype x, int j) {
  sunrealtype r = 1;
  for (int i = 0; i < j; ++i) r *= x;
  return r;
}

// The remap terms that move the node's history from am.hmap to a next step of h (docs/theory.md
// 12.2): the h-dependent part of the consistent history follows the step. None when the history
// is refreshed instead (12.5).
void RemapTerms(CEodeMemRec* ce, AdaptMem* am, sunrealtype h, AdaptPosition* w) {
  w->nremap = 0;
  if (h == am->hmap || RefreshHistory(ce, am, h)) return;
  const int d = ce->degree;
  RemapWeights(*am, d, h, w->rc);
  for (int i = 0; i < am->set.nremap; ++i) {
    const RemapTerm& r = am->set.remap[i];
    w->rY[i] = r.k + r.j == d ? am->yd : ce->D[r.k + r.j];
    w->rD[i] = ce->D[r.k];
  }
  w->nremap = am->set.nremap;
  am->hmap = h;
}

// The position's weights c[0 .. *m - 1] over {x(t_n), D_1 .. D_{d-1} (remapped), yd} for a
// step of ce->h (ce->co's) from a node whose last step was hprev, with its history remapped for
// hmap: the Taylor terms and the top derivative's blend over the new interval,
// z_n - (1 - p0) h yd with the node's own z_n (before the remap).
void PositionTerms(const CEodeMemRec* ce, const AdaptMem& am, sunrealtype hprev, sunrealtype hmap,
                   sunrealtype* c, int* m) {
  const int d = ce->degree;
  const sunrealtype* tw = ce->co.tw;
  // The Taylor weights by whole, a constant-size copy (a few moves): of the entries from d on
  // only entry d is read, as the yd term below.
  std::copy(tw, tw + kMaxDegree, c);
  c[0] = 1;
  // D_{d-1} = z_n + gamma (hmap - hprev) yd after the remap: zero (each term +0) when the
  // history is remapped for the node's own step, as a refreshed one is.
  sunrealtype top_shift = 0;
  if (hmap != hprev) {
    for (int i = 0; i < am.set.nremap; ++i) {
      if (am.set.remap[i].k == d - 1) top_shift += am.set.remap[i].gamma * (hmap - hprev);
    }
  }
  const sunrealtype yd_coef = -tw[d - 1] * (top_shift + (1 - ce->params[0]) * ce->h);
  *m = d;
  if (yd_coef != 0 && hprev > 0) c[(*m)++] = yd_coef;
}

// PositionTerms of the node for the step ce->h into am->pos, kept while h, hprev and hmap stay.
void PositionWeights(CEodeMemRec* ce, AdaptMem* am) {
  const sunrealtype h = ce->h;
  if (h == am->pos_h && am->hprev == am->pos_hprev && am->hmap == am->pos_hmap) return;
  PositionTerms(ce, *am, am->hprev, am->hmap, am->pos.c, &am->pos.m);
  am->pos_h = h;
  am->pos_hprev = am->hprev;
  am->pos_hmap = am->hmap;
}

// The step's coefficients for a new h.
void SetStep(CEodeMemRec* ce, sunrealtype h) {
  if (h != ce->co.h) ComputeStepCoeffs(ce->degree, ce->params, h, &ce->co, true);
  ce->h = h;
}

// The node's next step becomes h: the history remapped for it and x(t_n + h) into xnext, in one
// pass; returns ||x(t_n + h)||_1.
sunrealtype MoveTo(CEodeMemRec* ce, AdaptMem* am, sunrealtype h) {
  AdaptPosition& w = am->pos;
  RemapTerms(ce, am, h, &w);
  SetStep(ce, h);
  PositionWeights(ce, am);
  std::copy(ce->D, ce->D + kMaxDegree, w.X);  // by whole, as PositionTerms' weights
  w.X[0] = ce->xcur;
  if (w.m > ce->degree) w.X[ce->degree] = am->yd;
  w.out = ce->xnext;
  // The weights of the new position come with it, unless the constrained solve moves it.
  const bool moved = ce->step->solve_kind == SolveKind::kConstrained;
  w.weights = moved ? AdaptAfterF::kWeightsNone : am->wkind;
  w.ewt = am->ewt_next;
  am->ewt_next_ready = !moved;
  return am->kernels.Position(&w, &am->dmin_next);
}

// The derivatives at t = tcur + h from the history and the acceleration in Dnew[2]: the fixed
// step's plan without its position sum. The plans of the two history configurations are kept
// while h stays.
const KernelPlan& DerivativePlan(CEodeMemRec* ce, AdaptMem* am) {
  // A configuration without a plan takes the slot the other configuration did not use last.
  int i = ce->D[1] == am->plan_key[0] ? 0 : (ce->D[1] == am->plan_key[1] ? 1 : -1);
  if (i < 0) i = 1 - am->plan_last;
  am->plan_last = i;
  KernelPlan& kp = am->plans[i];
  if (am->plan_h[i] != ce->co.h || am->plan_key[i] != ce->D[1]) {
    // Another h on the same vectors changes only the coefficients.
    const bool same_vectors = am->plan_key[i] == ce->D[1];
    UpdatePlan plan;
    BuildUpdatePlan(ce->degree, ce->co, ce->D, ce->Dnew, ce->xnext, ce->xnew, &plan);
    --plan.n;
    if (!same_vectors || !RefreshPlanCoefficients(plan, &kp)) {
      kp.plan = plan;
      PreparePlan(am->kernels.serial, &kp);
    }
    am->plan_h[i] = ce->co.h;
    am->plan_key[i] = ce->D[1];
  }
  return kp;
}

// The data of D and Dnew for the serial pass (AdaptAfterF::hist_data), looked up once for each
// configuration of the buffers; a third one (the vectors changed) starts the table again.
sunrealtype* const (*HistoryData(CEodeMemRec* ce, AdaptMem* am))[kMaxDegree] {
  const N_Vector key = ce->D[1];
  if (key == am->hist_key[0]) return am->hist_data[0];
  if (key == am->hist_key[1]) return am->hist_data[1];
  const int c = am->hist_key[0] == nullptr || am->hist_key[1] != nullptr ? 0 : 1;
  if (c == 0) am->hist_key[1] = nullptr;
  for (int k = 1; k < ce->degree; ++k) {
    am->hist_data[c][0][k] = NV_DATA_S(ce->D[k]);
    am->hist_data[c][1][k] = NV_DATA_S(ce->Dnew[k]);
  }
  am->hist_key[c] = key;
  return am->hist_data[c];
}

// The derivatives' weights of the serial pass for degree D (a constant, so that the loops
// unroll): BuildUpdatePlan's values in its order into cw; whether none is zero. The smallest
// magnitude tells, without a branch per weight (a NaN is no zero, as for c != 0: min keeps the
// other operand).
template <int D>
bool DerivativeWeightsOf(const StepCoeffs& co, sunrealtype (*cw)[kMaxDegree]) {
  sunrealtype smallest = 1;
  int s = 0;
  const auto put = [&](int j, sunrealtype c) {
    cw[s][j] = c;
    smallest = std::min(smallest, std::fabs(c));
  };
  if (D > 3) {
    put(0, 1 / co.c[2]);
    for (int j = 2; j < D; ++j) put(j - 1, -co.T[2][j] / co.c[2]);
    ++s;
  }
#pragma GCC unroll 8
  for (int k = 1; k <= D - 2; ++k) {
    if (k == 2) continue;
#pragma GCC unroll 8
    for (int j = k + 1; j < D; ++j) put(j - k - 1, co.T[k][j]);
    put(D - k - 1, co.c[k]);
    ++s;
  }
  return smallest > 0;
}

using DerivativeWeightsFn = bool (*)(const StepCoeffs&, sunrealtype (*)[kMaxDegree]);
template <std::size_t... I>
constexpr std::array<DerivativeWeightsFn, sizeof...(I)> DerivativeWeightsTable(
    std::index_sequence<I...> /*d*/) {
  return {&DerivativeWeightsOf<static_cast<int>(I) + kMinDegree>...};
}
// By the degree d = kMinDegree .. kMaxDegree.
constexpr auto kDerivativeWeightsFns =
    DerivativeWeightsTable(std::make_index_sequence<kMaxDegree - kMinDegree + 1>{});

// The derivatives' weights of the serial pass (AdaptAfterF::cw) for the step's h, once per h:
// BuildUpdatePlan's values in its order, and whether none is zero (full).
void DerivativeWeights(CEodeMemRec* ce, AdaptMem* am) {
  if (am->cw_h == ce->co.h) return;
  am->cw_h = ce->co.h;
  am->after.full = kDerivativeWeightsFns[ce->degree - kMinDegree](ce->co, am->after.cw);
}

// The estimate's shape for the step ce->h (kept while h and the number of differences stay,
// AfterFShape): the last of the new divided differences a[t, t_n, ..., t_{n+2-p}] scaled; one
// difference short (the first step of the sets of order d), the top difference available over the
// step stands in for the missing one: an overestimate while h is below the solution's time scale,
// so the first step is tested too; none while the history is shorter still.
void EstimateTerms(CEodeMemRec* ce, AdaptMem* am, AdaptAfterF* w) {
  const int p = am->set.order;
  const int jmax = std::min(p - 1, am->ndata);
  w->ndiff = jmax;
  w->dd_data = am->dd_data;  // the differences' data: their table and the node's half of it
  const sunrealtype h = ce->h;
  if (h != am->est_h) {
    am->est_h = h;
    am->est_scale = am->set.cerr * IntPow(h, p + 1) * am->pfac;
  }
  w->scale = am->est_scale;
  w->est_kind = AdaptAfterF::kEstLast;
  if (p == 1) {  // a set of first order: y'' itself, the new node's acceleration, no difference
    w->est_kind = AdaptAfterF::kEstCopy;
  } else if (jmax == p - 2 && jmax >= 1) {
    w->est_kind = AdaptAfterF::kEstCopy;
    w->scale /= h;
  } else if (jmax < p - 1) {
    w->est_kind = AdaptAfterF::kEstNone;
  }
}

// From this many differences on, the quotients of every slot cost fewer instructions than a
// loop over the differences alone.
constexpr int kWideQuotients = 4;

// The estimate's per-step part: the differences' reciprocal intervals to t and the copied
// difference (kEstCopy), which follow the node.
void EstimateNodeTerms(CEodeMemRec* ce, AdaptMem* am, sunrealtype t, AdaptAfterF* w) {
  const int jmax = w->ndiff;
  w->dd_cur = am->cur;
  if (jmax == 1) {  // degree 3: one difference, no loop set-up for a single quotient
    w->r[0] = 1 / (t - am->tnode[0]);
  } else if (jmax < kWideQuotients) {
    for (int j = 1; j <= jmax; ++j) w->r[j - 1] = 1 / (t - am->tnode[j - 1]);
  } else {
    // Every slot (t follows each node time: finite; the unused ones are not read), a loop of
    // constant length that runs on pairs.
    for (int j = 0; j < kMaxDegree; ++j) w->r[j] = 1 / (t - am->tnode[j]);
  }
  if (w->est_kind == AdaptAfterF::kEstCopy) {
    w->est_src = am->set.order == 1 ? ce->Dnew[2] : am->dd[1 - am->cur][jmax];
  }
}

// The differences' vectors of EstimateTerms for the operations one by one (the serial pass reads
// their data from dd_data).
void DifferenceVectors(CEodeMemRec* ce, AdaptMem* am, AdaptAfterF* w) {
  const int p = am->set.order;
  for (int j = 1; j <= w->ndiff; ++j) {
    w->dnew[j - 1] = j == 1 ? ce->Dnew[2] : am->dd[1 - am->cur][j - 1];
    w->dold[j - 1] = j == 1 ? ce->D[2] : am->dd[am->cur][j - 1];
    w->dout[j - 1] = j == p - 1 ? am->est : am->dd[1 - am->cur][j];
  }
}

// Most steps keep h (the controller's band): the serial pass forms the position of a next step of
// the same h with the new history, as MoveTo would after the step is accepted, into xspec and its
// weights into ewt_spec (AdaptAfterF 7.); NextStep takes them when h stays. On every n this costs
// fewer instructions than the second pass it saves (AVX's three-operand encoding keeps the longer
// pass in registers). A failed test leaves the node's vectors and the last step's left end.
void NextPositionTerms(CEodeMemRec* ce, AdaptMem* am, AdaptAfterF* w) {
  w->spec_m = 0;
  const bool weights_from_tolerances = am->wkind != AdaptAfterF::kWeightsNone && w->positive;
  if (!am->kernels.serial || am->xspec == nullptr || w->weights != AdaptAfterF::kWeightsNone ||
      !weights_from_tolerances || ce->step->solve_kind == SolveKind::kConstrained) {
    return;
  }
  if (am->spec_h != ce->h) {  // after the step: hprev = hmap = h (CommitNode)
    const sunrealtype h = ce->h;
    if (am->pos_h == h && am->pos_hprev == h && am->pos_hmap == h) {  // a refreshed node's own
      std::copy(am->pos.c, am->pos.c + am->pos.m, w->spec_c);
      am->spec_m = am->pos.m;
    } else {
      PositionTerms(ce, *am, h, h, w->spec_c, &am->spec_m);  // kept in w while h stays
    }
    am->spec_h = h;
  }
  w->spec_m = am->spec_m;
  w->spec_weights = am->wkind;
}

// The fields of AdaptAfterF that depend on the step's h, the number of differences and the
// weights' kind only, with the pass they choose: most steps keep all three, and the fields stay.
void AfterFShape(CEodeMemRec* ce, AdaptMem* am, int weights) {
  AdaptAfterF& w = am->after;
  const int ndiff = std::min(am->set.order - 1, am->ndata);
  if (ce->h == am->shape_h && ndiff == w.ndiff && weights == w.weights) return;
  am->shape_h = ce->h;
  w.D = ce->D;  // the arrays themselves: the buffers trade places inside them
  w.Dn = ce->Dnew;
  DerivativeWeights(ce, am);
  EstimateTerms(ce, am, &w);
  w.yc = 1 / ce->h;
  w.weights = weights;
  NextPositionTerms(ce, am, &w);
  am->after_fused = am->kernels.AfterFIsFused(&w);
  am->spec_pass = w.spec_m > 0 && am->after_fused;
}

// The step's vector work once f is known at its end (AdaptAfterF): the derivatives there, the
// divided differences, the local error estimate into est and its norm (scaled for tolerance
// proportionality; 0 while none is estimated), yd over the step into yd_next and the weights of
// the new position into ewt_next (their smallest denominator in *dmin); on the serial pass the
// position of a next step of the same h (NextPositionTerms). AfterFOfShape: on the shape as
// AfterFShape left it.
sunrealtype AfterFOfShape(CEodeMemRec* ce, AdaptMem* am, sunrealtype t) {
  AdaptAfterF& w = am->after;
  EstimateNodeTerms(ce, am, t, &w);
  w.est = am->est;
  w.ewt = am->ewt;
  w.yd = am->yd_next;
  w.x = ce->xnext;
  w.ewt_next = am->ewt_next;
  w.spec_x = am->xspec;
  w.spec_ewt = am->ewt_spec;
  w.kp = nullptr;
  if (am->after_fused) {
    w.hist_data = HistoryData(ce, am);
  } else {
    DifferenceVectors(ce, am, &w);
    w.kp = &DerivativePlan(ce, am);
  }
  am->spec_ready = am->spec_pass;
  sunrealtype dmin = 1;
  const sunrealtype norm = am->kernels.AfterF(w, &dmin, &am->spec_l1);
  if (w.weights != AdaptAfterF::kWeightsNone) am->dmin_next = dmin;
  return w.est_kind == AdaptAfterF::kEstNone ? 0 : norm * am->err_scale;
}

sunrealtype AfterF(CEodeMemRec* ce, AdaptMem* am, sunrealtype t) {
  // The weights of the new position, unless they came with it (MoveTo).
  AfterFShape(ce, am, am->ewt_next_ready ? AdaptAfterF::kWeightsNone : am->wkind);
  return AfterFOfShape(ce, am, t);
}

// x(t + hn; a) for the constrained solve at t = t_n + h: the derivative relations over h, the
// new node's yd, the remap from h to hn and the position over hn, on coefficient arrays over
// {x(t), D_1(t_n), ..., D_{d-1}(t_n), a} (index 0, 1..d-1, d): the weights xoff of x(t) and the
// history, and mu of a (docs/theory.md 12.6). The same operations as AfterF (the
// derivatives and yd), RemapTerms and PositionWeights (MoveTo) perform on the vectors.
void AffineStepWeights(const CEodeMemRec* ce, const AdaptMem& am, sunrealtype hn, sunrealtype* xoff,
                       sunrealtype* mu) {
  using Co = std::array<sunrealtype, kMaxDegree + 1>;
  const int d = ce->degree;
  const StepCoeffs& co = ce->co;
  const sunrealtype h = co.h;
  const auto unit = [](int i) {
    Co e{};
    e[i] = 1;
    return e;
  };
  const auto axpy = [d](sunrealtype c, const Co& y, Co* x) {
    for (int i = 0; i <= d; ++i) (*x)[i] += c * y[i];
  };
  Co z = unit(d);  // d = 3: z is a
  if (d > 3) {
    Co b2{};
    for (int j = 2; j < d; ++j) axpy(co.T[2][j], unit(j), &b2);
    axpy(-1, b2, &z);
    for (sunrealtype& c : z) c /= co.c[2];
  }
  Co D[kMaxDegree] = {};
  for (int k = 1; k < d; ++k) {
    if (k == 2 || k == d - 1) {
      D[k] = k == 2 ? unit(d) : z;
      continue;
    }
    D[k] = unit(k);  // T[k][k] = 1: the accumulated quantity
    for (int j = k + 1; j < d; ++j) axpy(co.T[k][j], unit(j), &D[k]);
    axpy(co.c[k], z, &D[k]);
  }
  if (d == 3) D[2] = unit(d);
  Co yd = z;
  axpy(-1, unit(d - 1), &yd);
  for (sunrealtype& c : yd) c /= h;
  const Co Dunmapped[kMaxDegree] = {D[0], D[1], D[2], D[3], D[4], D[5], D[6], D[7]};
  sunrealtype top_shift = 0;
  for (int i = 0; i < am.set.nremap; ++i) {
    const RemapTerm& r = am.set.remap[i];
    const sunrealtype c = r.gamma * (IntPow(hn, r.j) - IntPow(h, r.j));
    axpy(c, r.k + r.j == d ? yd : Dunmapped[r.k + r.j], &D[r.k]);
    if (r.k == d - 1) top_shift += r.gamma * (hn - h);
  }
  sunrealtype tw[kMaxDegree + 1];
  TaylorWeightsByProducts(hn, d, tw);
  Co x = unit(0);
  for (int i = 1; i < d; ++i) axpy(tw[i], D[i], &x);
  axpy(-tw[d - 1] * (top_shift + (1 - ce->params[0]) * hn), yd, &x);
  std::fill(xoff, xoff + kMaxDegree, 0);
  for (int j = 0; j < d; ++j) xoff[j] = x[j];
  *mu = x[d];
}

// While the stable step decides the steps, the frequency it comes from is estimated again every
// kRefreshSteps steps: the state moves away from where it was estimated (a Kepler orbit whose
// pericentre closes in), and a stale cap lets the step grow past the stability limit.
constexpr long int kRefreshSteps = 50;
int RefreshStableStep(CEodeMemRec* ce, AdaptMem* am, const char* func) {
  if (!am->capped_last || ce->nst - am->nst_refresh < kRefreshSteps) return CE_SUCCESS;
  am->nst_refresh = ce->nst;
  return GuardCheck(ce, func);
}

// The node's next step becomes h (the history remapped, the position again).
void ReviseStep(CEodeMemRec* ce, AdaptMem* am, sunrealtype h) { MoveTo(ce, am, h); }

int ErrFailure(CEodeMemRec* ce, const char* func, sunrealtype t, sunrealtype err, int nef) {
  if (!IsFinite(ce->Dnew[2])) {
    return ProcessError(ce, CE_RHSFUNC_FAIL, func,
                        "The acceleration is NaN or Inf at t = %.17g after %d smaller steps: f "
                        "returns non-finite values.",
                        static_cast<double>(t), nef);
  }
  return ProcessError(ce, CE_ERR_FAILURE, func,
                      "The error test failed %d times at t = %.17g (error norm %g, h = %g, hmin "
                      "= %g): the tolerances cannot be met here; loosen them or check f for a "
                      "discontinuity.",
                      nef, static_cast<double>(t), static_cast<double>(err),
                      static_cast<double>(ce->h), static_cast<double>(ce->adapt->hmin));
}

// The accepted step becomes the node: the history, the positions (x(t_n) stays as the dense
// output's left end), the divided differences and the times. kSteady: from a steady node
// (Steady), whose weights come from the tolerances, whose table is full and whose step, the
// last step and the remap's stay h.
template <bool kSteady>
__attribute__((always_inline)) inline void CommitNodeOf(CEodeMemRec* ce, AdaptMem* am,
                                                        sunrealtype t, sunrealtype err) {
  // yd of the new node (its z, un-remapped, less the node's z over the step) and the weights of
  // its position were formed with the estimate.
  std::swap(am->yd, am->yd_next);
  if (kSteady || am->tol_kind != 2) std::swap(am->ewt, am->ewt_next);
  am->ewt_next_ready = false;
  SwapHistorySlots(ce);
  N_Vector old = ce->xcur;
  ce->xcur = ce->xnext;
  ce->xnext = ce->xnew;
  ce->xnew = old;  // x(t_n): the dense output's left end
  std::swap(am->ele, am->est);
  am->cur = 1 - am->cur;
  // The differences read tnode[0 .. p - 2]: t enters at the front, the others move back by one
  // (the whole array through registers: copies of constant size without overlap compile to a few
  // vector loads and stores, where an overlapping move is a library call).
  sunrealtype moving[kMaxDegree];
  std::memcpy(moving, am->tnode, sizeof moving);
  std::memcpy(am->tnode + 1, moving, sizeof moving);
  am->tnode[0] = t;
  if constexpr (!kSteady) {
    am->ndata = std::min(am->ndata + 1, kMaxDegree);
    am->hprev = am->hmap = am->hlast = ce->h;
    if (am->first) am->first = !AdaptEstimated(*am);  // until a step passes a test: on trial
  }
  am->err = err;
  ce->tcur = t;
  ++ce->nst;
  ++ce->nsteps_h;
}

void CommitNode(CEodeMemRec* ce, AdaptMem* am, sunrealtype t, sunrealtype err) {
  CommitNodeOf<false>(ce, am, t, err);
}

// The first step once the guard's estimate is known (it comes after the start chose h): within
// the stable step. With constraints x(t0 + h) lies on the constraint manifold as solved, so a
// new h means a new start.
int FirstStepWithinStableStep(CEodeMemRec* ce, AdaptMem* am, bool constrained) {
  if (!am->first) return CE_SUCCESS;
  const sunrealtype hs = AdaptStableStep(ce);
  if (ce->h <= hs) return CE_SUCCESS;
  ++am->ncapped;
  if (constrained) {
    am->h_restart = hs;
    return kStartAgain;
  }
  ReviseStep(ce, am, hs);
  am->h0 = hs;
  return CE_SUCCESS;
}

// The solve at t = tcur + h, the derivatives there and the error estimate of the step; with
// constraints the constraint holds at t + h_plan.
int AttemptStep(CEodeMemRec* ce, AdaptMem* am, bool constrained, sunrealtype t, sunrealtype* err,
                const char* func) {
  sunrealtype tnext = t + ce->h;
  if (constrained) {
    sunrealtype xoff[kMaxDegree];
    sunrealtype mu = 0;
    AffineStepWeights(ce, *am, am->h_plan, xoff, &mu);
    ConstrSetStepPosition(ce, xoff, mu);
    tnext = t + am->h_plan;
  }
  const int flag = ce->step->solve(ce, t, tnext, ce->xnext, ce->Dnew[2], func);
  if (flag != CE_SUCCESS) return flag;
  *err = AfterF(ce, am, t);
  return CE_SUCCESS;
}

// After a failed test (the nef-th on this step): a new start with a smaller step while the start
// is on trial or x(t) must be solved for again (constraints); otherwise the position update from
// the node again with a smaller step; CE_ERR_FAILURE after maxnef failures or at hmin.
int RetryAfterFailure(CEodeMemRec* ce, AdaptMem* am, bool constrained, sunrealtype t,
                      sunrealtype err, int nef, const char* func) {
  if ((am->first || constrained) && am->start_fails + 1 < am->maxnef) {
    ++am->start_fails;
    am->h_restart = AdaptRetryStep(ce, err);
    am->fail_restart = true;
    return kStartAgain;
  }
  if (constrained) return ErrFailure(ce, func, t, err, am->start_fails + 1);
  if (nef >= am->maxnef || ce->h <= am->hmin) return ErrFailure(ce, func, t, err, nef);
  MoveTo(ce, am, AdaptRetryStep(ce, err));
  return CE_SUCCESS;
}

// Growth that the relative error weights follow: stop long before overflow, as the fixed step.
int CheckGrowth(CEodeMemRec* ce, sunrealtype xl1, sunrealtype t, const char* func) {
  if (xl1 <= kGrowthLimit * (1 + ce->xl1_start)) return CE_SUCCESS;
  return ProcessError(ce, CE_UNSTABLE, func,
                      "The state grew explosively or stopped being finite (||x||_1 = %g at t = "
                      "%.17g, %g at the start) although every step passed its error test: the "
                      "step sequence excited a parasitic mode of %s (docs/theory.md section "
                      "12.5). Tighten the tolerances or use a set of lower degree.",
                      static_cast<double>(xl1), static_cast<double>(t),
                      static_cast<double>(ce->xl1_start), ce->method_name.c_str());
}

// MoveTo out of line: a step that changes h (few) leaves the step's path short.
__attribute__((noinline)) sunrealtype MoveToApart(CEodeMemRec* ce, AdaptMem* am, sunrealtype h) {
  return MoveTo(ce, am, h);
}

// MoveTo's result for an unchanged step (no remap, the same weights), made with the step's pass
// (spec_ready), and its growth check.
int TakeNextPosition(CEodeMemRec* ce, AdaptMem* am, sunrealtype t, const char* func) {
  std::swap(ce->xnext, am->xspec);
  std::swap(am->ewt_next, am->ewt_spec);
  am->ewt_next_ready = true;
  am->dmin_next = 1;
  am->spec_ready = false;
  return CheckGrowth(ce, am->spec_l1, t, func);
}

// The accepted node's next step (with constraints the planned one, and the plan of the step after
// it) and the position at its end.
int NextStep(CEodeMemRec* ce, AdaptMem* am, bool constrained, sunrealtype t, sunrealtype err,
             int nef, sunrealtype tlimit, const char* func) {
  bool capped = false;
  sunrealtype h = 0;
  if (constrained) {
    h = am->h_plan;
    am->h_plan = AdaptNextStep(ce, err, h, ce->tcur + h, tlimit, &capped);
    const int flag = AdaptCheckVelocityRoundOff(ce, h, func);
    if (flag != CE_SUCCESS) return flag;
  } else {
    h = AdaptNextStep(ce, err, ce->h, ce->tcur, tlimit, &capped);
    if (nef > 0) h = std::min(h, ce->h);  // no growth right after a failed test
  }
  if (capped) ++am->ncapped;
  am->capped_last = capped;
  if (am->spec_ready && h == ce->h && !constrained) return TakeNextPosition(ce, am, t, func);
  return CheckGrowth(ce, MoveToApart(ce, am, h), t, func);
}

// The end of the step from tcur: tlimit itself where the step ends there (lands on tstop exactly).
sunrealtype StepEnd(const CEodeMemRec* ce, sunrealtype tlimit) {
  return ce->h == tlimit - ce->tcur ? tlimit : ce->tcur + ce->h;
}

// After a step to *t whose test failed (*err > 1, or NaN): retries until one passes (or a
// schedule decides the step), the failures counted in *nef.
__attribute__((noinline)) int RetryUntilAccepted(CEodeMemRec* ce, AdaptMem* am, bool constrained,
                                                 sunrealtype tlimit, sunrealtype* t,
                                                 sunrealtype* err, int* nef, const char* func) {
  while (!(*err <= 1) && am->schedule == nullptr) {
    ++am->netf;
    int flag = RetryAfterFailure(ce, am, constrained, *t, *err, ++*nef, func);
    if (flag != CE_SUCCESS) return flag;
    *t = StepEnd(ce, tlimit);
    flag = AttemptStep(ce, am, constrained, *t, err, func);
    if (flag != CE_SUCCESS) return flag;
  }
  return CE_SUCCESS;
}

// The step to t that passed its test (after nef failures) becomes the node, then the next step's
// size and position.
int AcceptStep(CEodeMemRec* ce, AdaptMem* am, bool constrained, sunrealtype t, sunrealtype err,
               int nef, sunrealtype tlimit, const char* func) {
  CommitNode(ce, am, t, err);
  int flag = CE_SUCCESS;
  if (am->tol_kind == 2) {
    flag = AdaptWeights(ce, ce->xcur, func);
  } else if (!(am->dmin_next > 0)) {
    flag = AdaptWeightsDefined(ce, am->dmin_next, func);
  }
  if (flag == CE_SUCCESS) flag = RefreshStableStep(ce, am, func);
  if (flag == CE_SUCCESS) flag = NextStep(ce, am, constrained, t, err, nef, tlimit, func);
  if (flag != CE_SUCCESS) return flag;
  if (ce->guard.every > 0 && ce->nst % ce->guard.every == 0) return GuardCheck(ce, func);
  return CE_SUCCESS;
}

// One accepted step (with as many retries as the error test asks for), then the next step's
// size and position.
int OneStep(CEodeMemRec* ce, AdaptMem* am, sunrealtype tlimit, const char* func) {
  const bool constrained = ce->step->solve_kind == SolveKind::kConstrained;
  int flag = FirstStepWithinStableStep(ce, am, constrained);
  if (flag != CE_SUCCESS) return flag;
  int nef = 0;
  sunrealtype err = 0;
  sunrealtype t = StepEnd(ce, tlimit);
  flag = AttemptStep(ce, am, constrained, t, &err, func);
  if (flag == CE_SUCCESS && !(err <= 1)) {  // NaN fails the test
    flag = RetryUntilAccepted(ce, am, constrained, tlimit, &t, &err, &nef, func);
  }
  if (flag != CE_SUCCESS) return flag;
  return AcceptStep(ce, am, constrained, t, err, nef, tlimit, func);
}

// OneStep out of line, for LeanUntil's rare steps.
__attribute__((noinline)) int OneStepApart(CEodeMemRec* ce, AdaptMem* am, sunrealtype tlimit,
                                           const char* func) {
  return OneStep(ce, am, tlimit, func);
}

// AcceptStep out of line, for LeanRetry.
__attribute__((noinline)) int AcceptStepApart(CEodeMemRec* ce, AdaptMem* am, sunrealtype t,
                                              sunrealtype err, int nef, sunrealtype tlimit,
                                              const char* func) {
  return AcceptStep(ce, am, false, t, err, nef, tlimit, func);
}

// The rest of a LeanStep whose test failed at t: OneStep's retries and acceptance.
__attribute__((noinline)) int LeanRetry(CEodeMemRec* ce, AdaptMem* am, sunrealtype t,
                                        sunrealtype err, sunrealtype tlimit, const char* func) {
  int nef = 0;
  const int flag = RetryUntilAccepted(ce, am, false, tlimit, &t, &err, &nef, func);
  if (flag != CE_SUCCESS) return flag;
  return AcceptStepApart(ce, am, t, err, nef, tlimit, func);
}

// OneStep where LeanCall holds for the call and the start is behind (not first): the same
// operations without the tests that these decide.
int LeanStep(CEodeMemRec* ce, AdaptMem* am, sunrealtype tlimit, const char* func) {
  sunrealtype err = 0;
  const sunrealtype t = StepEnd(ce, tlimit);
  int flag = AttemptStep(ce, am, false, t, &err, func);
  if (flag != CE_SUCCESS) return flag;
  if (!(err <= 1)) return LeanRetry(ce, am, t, err, tlimit, func);  // NaN fails the test
  CommitNode(ce, am, t, err);
  if (!(am->dmin_next > 0)) flag = AdaptWeightsDefined(ce, am->dmin_next, func);
  if (flag == CE_SUCCESS) flag = RefreshStableStep(ce, am, func);
  if (flag == CE_SUCCESS) flag = NextStep(ce, am, false, t, err, 0, tlimit, func);
  return flag;
}

// Whether the node is steady: its next step repeats its last one in everything that AfterF's
// shape, the position and the bounds of h depend on. The last step kept h within its bounds (not
// capped, ratio 1, the stop time not within two steps), its pass formed the next position and
// the weights (TakeNextPosition), the start and the differences' table are behind. Then each
// next step that keeps h keeps the node steady (SteadyStep): the stable step and the bounds are
// those of this call, which no step in it changes.
bool Steady(CEodeMemRec* ce, const AdaptMem& am, sunrealtype tlimit) {
  const sunrealtype h = ce->h;
  const sunrealtype rem = tlimit - ce->tcur;
  return !am.first && !am.capped_last && am.eta_prev == 1 && am.ewt_next_ready &&
         am.dmin_next == 1 && am.ndata == kMaxDegree && am.after.ndiff == am.set.order - 1 &&
         am.after.weights == AdaptAfterF::kWeightsNone && am.spec_pass && am.shape_h == h &&
         am.hprev == h && am.hmap == h && AdaptEstimated(am) && !(rem > 0 && rem < 2 * h) &&
         h >= am.hmin && (am.hmax <= 0 || h <= am.hmax) && h <= AdaptStableStep(ce);
}

// LeanStep from a steady node (Steady): the same operations on the same values without the tests
// that the steady state settles (AfterF's shape, the weights' source, the bounds of h, the stop
// time behind the step's end); *steady false when the node it leaves may not be steady.
// kDirect: the explicit solve without a mass matrix, f called directly (as SolveExplicit does).
template <bool kDirect>
__attribute__((always_inline)) inline int SteadyStep(CEodeMemRec* ce, AdaptMem* am,
                                                     sunrealtype tlimit, const char* func,
                                                     bool* steady) {
  const sunrealtype h = ce->h;
  const sunrealtype t = ce->tcur + h;  // StepEnd's: the step ends short of tlimit
  const int flag = kDirect ? EvalRhs(ce, t, ce->xnext, ce->D[1], ce->Dnew[2], func)
                           : ce->step->solve(ce, t, t + h, ce->xnext, ce->Dnew[2], func);
  if (flag != CE_SUCCESS) return flag;
  const sunrealtype err = AfterFOfShape(ce, am, t);
  if (!(err <= 1)) {  // NaN fails the test
    *steady = false;
    return LeanRetry(ce, am, t, err, tlimit, func);
  }
  CommitNodeOf<true>(ce, am, t, err);
  // AdaptNextStep's bounds keep h while the stop time is not within two steps.
  const sunrealtype rem = tlimit - t;
  if (!(rem > 0 && rem < 2 * h) && AdaptKeepsStep(ce, err)) {
    return TakeNextPosition(ce, am, t, func);
  }
  *steady = false;
  return NextStep(ce, am, false, t, err, 0, tlimit, func);
}

// x and x' at tcur + s, s in [-hlast, 0] (the history at tcur and x at its left end), and whether
// both are finite: at tcur the method's own values, copied and tested in one pass.
bool Output(CEodeMemRec* ce, sunrealtype s, N_Vector xout, N_Vector vout) {
  if (s == 0) return CopyPairFinite(ce->xcur, ce->D[1], xout, vout);
  Interpolate(ce, s, 0, xout);
  Interpolate(ce, s, 1, vout);
  return AllFinite(xout) && AllFinite(vout);
}

}  // namespace

namespace {

// The stop time for this call (SUN_BIG_REAL without one), with the next step ending on it or the
// two before it sharing what remains (with constraints a next step past it starts the method
// again there).
int ApproachStopTime(CEodeMemRec* ce, AdaptMem* am, sunrealtype troundoff, sunrealtype* tlimit,
                     const char* func) {
  *tlimit = SUN_BIG_REAL;
  if (!ce->tstop_set) return CE_SUCCESS;
  if (ce->tstop < ce->tcur - troundoff) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "The stop time %.17g is behind the current time %.17g.",
                        static_cast<double>(ce->tstop), static_cast<double>(ce->tcur));
  }
  *tlimit = ce->tstop;
  const sunrealtype rem = *tlimit - ce->tcur;
  if (ce->step->solve_kind != SolveKind::kConstrained) {
    if (rem > 0 && ce->h > rem) ReviseStep(ce, am, rem);
    if (rem > 0 && ce->h < rem && 2 * ce->h > rem) ReviseStep(ce, am, rem / 2);
    return CE_SUCCESS;
  }
  if (rem > 0 && ce->h > rem) {
    am->h_restart = rem;
    const int flag = StartMethod(ce);
    if (flag != CE_SUCCESS) return flag;
  }
  if (rem - ce->h > 0 && am->h_plan > rem - ce->h) am->h_plan = rem - ce->h;
  return CE_SUCCESS;
}

int TooMuchWork(CEodeMemRec* ce, long int nsteps, sunrealtype tout, const char* func) {
  return ProcessError(ce, CE_TOO_MUCH_WORK, func,
                      "%ld steps taken before reaching tout = %.17g (t = %.17g): raise the "
                      "limit with CEodeSetMaxNumSteps or loosen the tolerances.",
                      nsteps, static_cast<double>(tout), static_cast<double>(ce->tcur));
}

// A step's flag: a new start where the step asks for one (not a step), otherwise the step counted.
int AfterStep(CEodeMemRec* ce, AdaptMem* am, int flag, long int* nsteps) {
  if (flag == kStartAgain) return StartMethod(ce);
  if (flag == CE_SUCCESS) {
    am->start_fails = 0;
    ++*nsteps;
  }
  return flag;
}

// Accepted steps until done().
template <typename Done>
int StepUntil(CEodeMemRec* ce, AdaptMem* am, sunrealtype tout, sunrealtype tlimit, Done done,
              const char* func) {
  long int nsteps = 0;
  while (!done(nsteps)) {
    if (nsteps >= ce->mxstep) return TooMuchWork(ce, nsteps, tout, func);
    const int flag = AfterStep(ce, am, OneStep(ce, am, tlimit, func), &nsteps);
    if (flag != CE_SUCCESS) return flag;
  }
  return CE_SUCCESS;
}

// Whether a call without roots can run LeanUntil: no constraints, weights from the tolerances, no
// schedule and no periodic guard check, which stay for the call.
bool LeanCall(const CEodeMemRec* ce, const AdaptMem* am) {
  return ce->root == nullptr && ce->step->solve_kind != SolveKind::kConstrained &&
         am->tol_kind != 2 && am->schedule == nullptr && ce->guard.every == 0;
}

// StepUntil for such a call, done when tcur reaches tend or after max_steps steps: most steps are
// SteadyStep's, the others LeanStep's, the start's first steps OneStep's.
template <bool kDirect>
__attribute__((flatten)) int LeanUntilOf(CEodeMemRec* ce, AdaptMem* am, sunrealtype tout,
                                         sunrealtype tend, sunrealtype tlimit, long int max_steps,
                                         const char* func) {
  long int nsteps = 0;
  bool steady = Steady(ce, *am, tlimit);
  while (nsteps < max_steps && !(ce->tcur >= tend)) {
    if (nsteps >= ce->mxstep) return TooMuchWork(ce, nsteps, tout, func);
    int step = CE_SUCCESS;
    if (steady) {
      step = SteadyStep<kDirect>(ce, am, tlimit, func, &steady);
    } else {
      step = am->first ? OneStepApart(ce, am, tlimit, func) : LeanStep(ce, am, tlimit, func);
      steady = step == CE_SUCCESS && Steady(ce, *am, tlimit);
    }
    const int flag = AfterStep(ce, am, step, &nsteps);
    if (flag != CE_SUCCESS) return flag;
  }
  return CE_SUCCESS;
}

// LeanUntilOf with the call of f chosen once for the call.
__attribute__((noinline)) int LeanUntil(CEodeMemRec* ce, AdaptMem* am, sunrealtype tout,
                                        sunrealtype tend, sunrealtype tlimit, long int max_steps,
                                        const char* func) {
  if (ChosenSolve(ce) == SolveKind::kExplicit && !HasMassMatrix(ce)) {
    return LeanUntilOf<true>(ce, am, tout, tend, tlimit, max_steps, func);
  }
  return LeanUntilOf<false>(ce, am, tout, tend, tlimit, max_steps, func);
}

// Whether the call reached its stop time tlimit.
bool AtLimit(const CEodeMemRec* ce, sunrealtype tlimit, sunrealtype troundoff) {
  return ce->tstop_set && ce->tcur >= tlimit - troundoff;
}

// StepsOfCall's steps with their tests (roots, constraints, user weights, a schedule or a periodic
// guard check), out of line: AdaptEvolve, which a call without them runs through, keeps a small
// frame.
__attribute__((noinline, flatten)) int StepsWithTests(CEodeMemRec* ce, AdaptMem* am,
                                                      sunrealtype tout, sunrealtype tlimit,
                                                      sunrealtype troundoff, int itask,
                                                      int* root_flag, const char* func) {
  const sunrealtype tend = tout - troundoff;
  const bool tout_only = ce->root == nullptr && !ce->tstop_set && itask == CE_NORMAL;
  const auto done = [&](long int nsteps) {
    if (tout_only) return ce->tcur >= tend;
    if (ce->root != nullptr) {
      *root_flag = RootCheck(ce, itask == CE_NORMAL ? std::min(tout, ce->tcur) : ce->tcur, func);
      if (*root_flag != CE_SUCCESS) return true;
    }
    if (AtLimit(ce, tlimit, troundoff)) return true;
    return itask == CE_ONE_STEP ? nsteps > 0 : ce->tcur >= tend;
  };
  return StepUntil(ce, am, tout, tlimit, done, func);
}

// The steps of a CEodeEvolve call: until the last covers tout (CE_NORMAL) or one step
// (CE_ONE_STEP), never past the stop time tlimit, and each accepted step (and what is left of the
// last) checked for roots first, *root_flag their verdict.
int StepsOfCall(CEodeMemRec* ce, AdaptMem* am, sunrealtype tout, sunrealtype tlimit,
                sunrealtype troundoff, int itask, int* root_flag, const char* func) {
  // Without roots a call ends on one time alone, tout's or the stop time's where that comes first
  // (or after one step): one test a step.
  const sunrealtype tend = tout - troundoff;
  if (LeanCall(ce, am)) {
    const sunrealtype tstop_end = ce->tstop_set ? tlimit - troundoff : SUN_BIG_REAL;
    if (itask == CE_ONE_STEP) return LeanUntil(ce, am, tout, tstop_end, tlimit, 1, func);
    return LeanUntil(ce, am, tout, std::min(tend, tstop_end), tlimit, LONG_MAX, func);
  }
  return StepsWithTests(ce, am, tout, tlimit, troundoff, itask, root_flag, func);
}
}  // namespace

namespace {

// AdaptEvolve before its check of the outputs; *finite: whether the outputs written are finite
// (unset where none are written).
inline int StepsAndOutputs(CEodeMemRec* ce, const char* func, sunrealtype tout, N_Vector xout,
                           N_Vector vout, sunrealtype* tret, int itask, bool* finite) {
  AdaptMem* am = ce->adapt.get();
  am->tout_hint = tout;  // as AdaptSetTarget, which Evolve calls before the start
  const sunrealtype troundoff = 100 * SUN_UNIT_ROUNDOFF * (std::fabs(ce->tcur) + ce->h);
  *tret = ce->tcur;
  if (itask == CE_NORMAL && tout < ce->tcur - am->hlast - troundoff) {
    return ProcessError(ce, CE_BAD_T, func,
                        "tout = %.17g is behind the last step [%.17g, %.17g]: CEODE integrates "
                        "forward only; call CEodeReInit to go back.",
                        static_cast<double>(tout), static_cast<double>(ce->tcur - am->hlast),
                        static_cast<double>(ce->tcur));
  }
  sunrealtype tlimit = SUN_BIG_REAL;
  int flag = ApproachStopTime(ce, am, troundoff, &tlimit, func);
  if (flag != CE_SUCCESS) return flag;
  int root_flag = CE_SUCCESS;  // each accepted step (and what is left of the last) checked first
  flag = StepsOfCall(ce, am, tout, tlimit, troundoff, itask, &root_flag, func);
  if (flag == CE_SUCCESS) flag = root_flag;
  if (flag == CE_ROOT_RETURN) {
    const sunrealtype tr = RootTime(ce);
    *finite = Output(ce, tr - ce->tcur, xout, vout);
    *tret = ce->tretlast = tr;
    return flag;
  }
  if (flag != CE_SUCCESS) {
    *finite = Output(ce, 0, xout, vout);
    *tret = ce->tretlast = ce->tcur;
    return flag;
  }
  // tout inside the last step, before the stop time, is returned as without a stop time.
  const bool tout_first = itask == CE_NORMAL && tout < tlimit - troundoff;
  const bool at_stop = AtLimit(ce, tlimit, troundoff) && !tout_first;
  const sunrealtype tr = itask == CE_ONE_STEP || at_stop ? ce->tcur : std::min(tout, ce->tcur);
  *finite = Output(ce, tr - ce->tcur, xout, vout);
  *tret = ce->tretlast = tr;
  if (!at_stop) return CE_SUCCESS;
  ce->tstop_set = false;
  return CE_TSTOP_RETURN;
}

}  // namespace

__attribute__((flatten)) int AdaptEvolve(CEodeMemRec* ce, const char* func, sunrealtype tout,
                                         N_Vector xout, N_Vector vout, sunrealtype* tret,
                                         int itask) {
  bool finite = true;
  const int flag = StepsAndOutputs(ce, func, tout, xout, vout, tret, itask, &finite);
  return CheckReturned(ce, func, finite, xout, flag);
}

}  // namespace ceode
