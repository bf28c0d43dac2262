// The step module's record (ceode_step.hpp) outside the step itself: its lifetime, the update
// options, and the update plans of the six vector configurations with the backend that runs
// them. ChooseStep (ceode_step.cpp) calls BuildPlans once per start and after an option change.
#include <nvector/nvector_serial.h>

#include <cmath>
#include <new>
#include <utility>

#include "ceode_step.hpp"

namespace ceode {

void StepMemFree::operator()(StepMem* sm) const { delete sm; }

bool AllocStepRecord(CEodeMemRec* ce) {
  if (ce->step == nullptr) ce->step.reset(new (std::nothrow) StepMem);
  return ce->step != nullptr;
}

namespace {

// An option of the update: kept for the next start, and applied to a running method at once
// (the plans are rebuilt from the current vectors: the run goes on unchanged).
int SetUpdateOption(CEodeMemRec* ce, bool StepMem::*option, bool on, const char* func) {
  if (!AllocStepRecord(ce)) return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
  ce->step.get()->*option = on;
  if (ce->started) ChooseStep(ce, false);
  return CE_SUCCESS;
}

}  // namespace

int SetFusedKernel(CEodeMemRec* ce, bool on, const char* func) {
  return SetUpdateOption(ce, &StepMem::fused, on, func);
}

int SetInPlaceUpdate(CEodeMemRec* ce, bool on, const char* func) {
  return SetUpdateOption(ce, &StepMem::in_place, on, func);
}

bool FusedKernelOn(const CEodeMemRec* ce) { return ce->step == nullptr || ce->step->fused; }

bool SerialBackend(const CEodeMemRec* ce) { return ce->step != nullptr && ce->step->serial; }

// The vectors only trade places from step to step (history <-> new every step,
// the three positions in a cycle of three), so six plans, built once per start,
// cover every step: the step itself builds nothing. In-place plans write the InPlaceLevel
// derivatives over their history (Dn[k] = D[k], never swapped): the explicit fused step only,
// whose update runs once per step after f, uncompensated (docs/theory.md, "In-place update").
// The lean loop's steps that write the position over x(t + h) trade only the history's places:
// plan_ix, not the step count, names the configuration.
namespace {

// G3_CD's step as the leapfrog's kick and drift: with p_0 = 1 and p_1 = 1/2 the update
// v = v_old + c (a_old + a), x(t + h) = x(t) + h v + h^2/2 a is, to rounding of its weights
// (h c = h^2/2), v = (v_old + c a_old) + c a, u = v + c a, x(t + h) = x(t) + h u, with u the
// half-step velocity, formed in the work vector tmp3. Its first rounding, v_old + c a_old, is the
// last step's u: the lean loop carries u in place of v and reads a_old in its first step alone
// (LeapKernels), with the bits of the steps one by one. Every backend runs the plans so from
// kSmallSystem unknowns on, where the traffic matters; smaller systems, the compensated sums and
// the implicit steps keep the general form, whose shape kernel is cheaper per call.
bool LeapForm(const CEodeMemRec* ce, const StepMem* sm) {
  const StepCoeffs& co = ce->co;
  if (ce->degree != 3 || co.wz_old != 0 || ce->compensated || ce->n < kSmallSystem ||
      sm->solve_kind != SolveKind::kExplicit) {
    return false;
  }
  const sunrealtype c = co.T[1][2];
  const sunrealtype drift = co.w[1] * c;  // the weight of a in x(t + h) through u
  return c == co.c[1] && c != 0 &&
         std::fabs(drift - co.wz_new) <= 4 * SUN_UNIT_ROUNDOFF * co.wz_new;
}
void WriteLeapForm(const CEodeMemRec* ce, UpdatePlan* plan) {
  const StepCoeffs& co = ce->co;
  Combo& velocity = plan->combos[0];  // c a_old + c a, the old velocity leading
  Combo position = plan->combos[1];
  velocity.lead_old = true;
  Combo& half = plan->combos[1];
  half = Combo{};
  half.Add(1, velocity.out);
  half.Add(co.T[1][2], velocity.X[1]);
  half.out = ce->tmp3;
  Combo& drift = plan->combos[2];
  drift = Combo{};
  drift.Add(co.w[1], ce->tmp3);
  drift.old = position.old;
  drift.out = position.out;
  drift.lead_old = true;
  plan->n = 3;
}

// The six plans from the current vectors; returns whether the fused backend can run them. With
// in_place, also the plans that write the position over its last value; *xin: all were built.
bool BuildPlanCycle(CEodeMemRec* ce, StepMem* sm, bool in_place, bool fusable, bool* xin) {
  const int d = ce->degree;
  const bool leap = LeapForm(ce, sm);
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
    const int ip = (sm->plan_ix + i) % kNumPlans;
    BuildUpdatePlan(d, ce->co, D, Dn, xnext, xnew, &sm->plans[ip]);
    if (leap) WriteLeapForm(ce, &sm->plans[ip]);
    if (fusable) {
      fusable = BuildFusedPlan(sm->plans[ip], {ce->compensated, comp, compnew, nullptr},
                               &sm->fused_plans[ip]);
    }
    if (*xin && fusable) {
      UpdatePlan over = sm->plans[ip];
      Combo& position = over.combos[over.n - 1];
      position.out = position.old;
      *xin = BuildFusedPlan(over, {false, comp, compnew, nullptr}, &sm->fused_plans_xin[ip]);
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

void BuildPlans(CEodeMemRec* ce, StepMem* sm) {
  const bool serial = N_VGetVectorID(ce->xnext) == SUNDIALS_NVEC_SERIAL;
  const bool mpi = !serial && sun::LocalArrayWithReduce(ce->xnext);
  sm->len = serial ? ce->n : (mpi ? ce->xnext->ops->nvgetlocallength(ce->xnext) : 0);
  // In-place plans run on the fused backend only (the N_Vector reference's combinations must
  // not write an input), so when it refuses them the ordinary plans are built instead.
  bool in_place = sm->in_place && sm->fused && (serial || mpi) && !ce->compensated &&
                  sm->solve_kind == SolveKind::kExplicit && sm->len >= kInPlaceMinLen;
  bool xin = false;
  bool fusable = BuildPlanCycle(ce, sm, in_place, serial || mpi, &xin);
  if (in_place && !fusable) {
    in_place = false;
    fusable = BuildPlanCycle(ce, sm, false, serial || mpi, &xin);
  }
  sm->in_place_active = in_place;
  // The position over its last value loses x(tcur); after a failing f the lean loop rebuilds it
  // from x(tcur + h) and the history, which for d = 3 needs the old z (f's buffer) to be unused.
  sm->xin_ready = xin && fusable && (ce->degree > 3 || ce->co.wz_old == 0);
  sm->serial = fusable && serial;
  sm->mpi = fusable && mpi;
  // Below kSmallSystem entries a plan's kernel depends on its terms, weights and which of its
  // vectors are the same (SerialKernel), and the six configurations' plans differ only by a
  // permutation of the vectors: one plan's kernel serves all six (choosing it once spares
  // the setup of a short run five tests of the roles). Larger systems also test alignments.
  for (int i = 0; i < kNumPlans; ++i) {
    const bool own = i == 0 || sm->len >= kSmallSystem;
    sm->kernels[i] = !fusable ? nullptr
                     : own    ? SerialKernel(sm->fused_plans[i], sm->len)
                              : sm->kernels[0];
    sm->kernels_xin[i] = !sm->xin_ready ? nullptr
                         : own          ? SerialKernel(sm->fused_plans_xin[i], sm->len)
                                        : sm->kernels_xin[0];
  }
  // The half-step velocity reaches f in place of D_1(t - h): only where f does not read it.
  sm->leap = sm->xin_ready && VelocityUnread(ce);
  for (int i = 0; i < kNumPlans && sm->leap; ++i) {
    LeapKernels last;  // the last step writes the position out of place: its own streaming
    sm->leap = LeapKernelsOf(sm->fused_plans_xin[i], sm->len, &sm->leap_kernels[i]) &&
               LeapKernelsOf(sm->fused_plans[i], sm->len, &last);
    sm->leap_kernels[i].last = last.last;
  }
}

void NoPlans(StepMem* sm) {
  sm->in_place_active = sm->xin_ready = sm->leap = false;
  sm->serial = sm->mpi = false;
  for (int i = 0; i < kNumPlans; ++i) sm->kernels[i] = sm->kernels_xin[i] = nullptr;
}

}  // namespace ceode
