// The step (docs/theory.md section 2.2): the acceleration solve, the update of the derivatives
// and x(t + h), the growth check and the commit, one step at a time (TakeStep) or many in a row
// (the lean loop). What a step runs is chosen once per start (ChooseStep, at the end of this
// file) and kept in the step module's record (ceode_step.hpp), so that a step tests no
// configuration flag. The update plans are built in ceode_step_plans.cpp, the start in
// ceode_start.cpp, the coefficients in ceode_method.cpp.
#include "ceode_step.hpp"

#include <algorithm>
#include <climits>
#include <cmath>

namespace ceode {

int RhsFailed(CEodeMemRec* ce, int rv, sunrealtype t, const char* func) {
  return ProcessError(ce, CE_RHSFUNC_FAIL, func,
                      "The right-hand side function failed (returned %d) at t = %.17g. A fixed "
                      "step cannot retry with a smaller h: fix f or reduce h.",
                      rv, static_cast<double>(t));
}

int EvalAccel(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector v, N_Vector a,
              const char* func) {
  // No mass matrix (M = I): MassUpdate and MassSolve would do nothing; skip their calls.
  if (!HasMassMatrix(ce)) return EvalRhs(ce, t, x, v, a, func);
  int flag = MassUpdate(ce, t, x, func);
  if (flag == CE_SUCCESS) flag = EvalRhs(ce, t, x, v, a, func);
  return flag == CE_SUCCESS ? MassSolve(ce, a, func) : flag;
}

int SolveExplicit(CEodeMemRec* ce, sunrealtype t, sunrealtype /*tnext*/, N_Vector x, N_Vector a,
                  const char* func) {
  // No velocity dependence declared: f sees the last velocity, D_1(t - h).
  return EvalAccel(ce, t, x, ce->D[1], a, func);
}

namespace {

// Time k steps after tcur, from the last (re)start, so that rounding does not accumulate.
sunrealtype StepTime(const CEodeMemRec* ce, int k) {
  return ce->t_start_h + static_cast<sunrealtype>(ce->nsteps_h + k) * ce->h;
}

// ||x||_1 over every rank from this rank's part (any: a vector of the run, for its
// communicator); a failed reduction is CE_VECTOROP_ERR, not a state that is not finite.
inline UpdateResult GlobalL1(N_Vector any, sunrealtype local) {
  if (N_VDotProdMultiAllReduce(1, any, &local) != 0) return {CE_VECTOROP_ERR, std::nan("")};
  return {CE_SUCCESS, local};
}

// The step's update after the solve on each backend (StepMem::update); each returns
// ||x(t + h)||_1 for the growth check.
UpdateResult UpdateOnSerial(CEodeMemRec* /*ce*/, const StepMem& sm) {
  const int ip = sm.plan_ix;
  return {CE_SUCCESS, sm.kernels[ip](sm.fused_plans[ip], sm.len)};
}
UpdateResult UpdateOnMpi(CEodeMemRec* ce, const StepMem& sm) {  // the local part, one allreduce
  const int ip = sm.plan_ix;
  return GlobalL1(ce->xnew, sm.kernels[ip](sm.fused_plans[ip], sm.len));
}
UpdateResult UpdateOnReference(CEodeMemRec* ce, const StepMem& sm) {
  UpdateReference(sm.plans[sm.plan_ix],
                  {ce->compensated, ce->comp, ce->compnew, ce->tmp1, ce->compwork});
  return {CE_SUCCESS, N_VL1Norm(ce->xnew)};
}

// The bound on ||x||_1 relative to the start's, and whether a finite ||x||_1 has grown past it
// (or past an absolute limit): explosively.
inline sunrealtype GrowthBound(const CEodeMemRec* ce) {
  constexpr sunrealtype kGrowthLimit = 1e15;
  return kGrowthLimit * (1 + ce->xl1_start);
}
constexpr sunrealtype kAbsoluteLimit = 1e150;
inline bool Exploded(sunrealtype xl1, sunrealtype bound) {
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
  if (!ce->step->in_place_active) return "the state returned is that of the last completed step";
  return x_kept ? "the position returned is the last completed step's, the velocity the failed "
                  "step's (written in place): restart with CEodeReInit"
                : "the position and velocity returned are the failed step's (written in place): "
                  "restart with CEodeReInit";
}

// Explosive growth or a non-finite state: stop long before overflow, while the state is still
// readable, and say whether f or the step size is to blame. x_kept: x(t) is still in xnext.
int CheckState(CEodeMemRec* ce, sunrealtype t, UpdateResult r, const char* func,
               bool x_kept = true) {
  const sunrealtype xl1 = r.xl1;
  if (r.flag != CE_SUCCESS) {
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
// Two rotations of the history and three of the positions are the identity.
__attribute__((always_inline)) inline void RotateHistory(CEodeMemRec* ce, const StepMem& sm) {
  if (sm.in_place_active) {  // the other levels were written over their history
    std::swap(ce->D[2], ce->Dnew[2]);
    if (ce->degree > 3) std::swap(ce->D[ce->degree - 1], ce->Dnew[ce->degree - 1]);
  } else {
    SwapHistorySlots(ce);
  }
  if (ce->compensated) std::swap(ce->comp, ce->compnew);
}
__attribute__((always_inline)) inline void RotatePositions(CEodeMemRec* ce) {
  N_Vector old = ce->xcur;
  ce->xcur = ce->xnext;
  ce->xnext = ce->xnew;
  ce->xnew = old;
}
__attribute__((always_inline)) inline void RotateVectors(CEodeMemRec* ce, StepMem* sm) {
  RotateHistory(ce, *sm);
  RotatePositions(ce);
  sm->plan_ix = sm->plan_ix == kNumPlans - 1 ? 0 : sm->plan_ix + 1;
}

__attribute__((always_inline)) inline void Commit(CEodeMemRec* ce, StepMem* sm, sunrealtype t) {
  RotateVectors(ce, sm);
  ce->tcur = t;
  ++ce->nsteps_h;
  ++ce->nst;
}

}  // namespace

// One step: solve for the acceleration at t (the solve chosen at the start, see ChooseStep; the
// constraint holds at tnext), update the derivatives and x(t + h), check, commit.
int TakeStep(CEodeMemRec* ce) {
  static const char* func = "CEodeEvolve";
  StepMem* sm = ce->step.get();
  const sunrealtype t = StepTime(ce, 1);
  const sunrealtype tnext = StepTime(ce, 2);
  int flag = sm->solve(ce, t, tnext, ce->xnext, ce->Dnew[2], func);
  if (flag == CE_SUCCESS) {
    const UpdateResult r = sm->update(ce, *sm);  // NaN on a failed reduction
    if (!std::isfinite(r.xl1) || Exploded(r.xl1, GrowthBound(ce))) {
      flag = CheckState(ce, t, r, func);
    }
  }
  if (flag != CE_SUCCESS) return flag;
  Commit(ce, sm, t);
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
  LeapKernels leap;  // StepMem::leap_kernels of the plan
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
    return target - tj > StepReach(ce);
  };
  const sunrealtype guess = std::floor((target - ce->tcur) / ce->h);
  long int j =
      guess > 0 ? static_cast<long int>(std::min(guess, static_cast<sunrealtype>(cap))) : 0;
  while (j > 0 && !remains(j - 1)) --j;
  while (j < cap && remains(j)) ++j;
  return j;
}

// x(tcur) from x(tcur + h) less the last step's position increment (BuildUpdatePlan's last sum),
// after the lean loop wrote the position over it: equal to rounding, not bit for bit. The d = 3
// case that needs f's buffer is excluded by xin_ready.
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
  if (co.wz_old != 0) {  // z(tcur - h)
    c[m] = -co.wz_old;
    X[m++] = ce->Dnew[d - 1];
  }
  c[m] = -co.wz_new;
  X[m++] = ce->D[d - 1];
  N_VLinearCombination(m, c, X, ce->xcur);
}

// How the lean loop ended, for LeanExit.
struct LeanEnd {
  long int steps = 0;           // completed
  long int moved = 0;           // of them, those that rotated the positions
  bool over = false;            // the last completed step wrote the position over x(tcur)
  bool failed_over = false;     // the failing update wrote over x(tcur + h)
  bool carried = false;         // the last completed step left the half-step velocity in D_1
  bool failed_carried = false;  // the failing update wrote the half-step velocity into D_1
  bool accel_lost = false;      // f's failing call was handed the buffer of a(tcur) (LeapRun)
  N_Vector failed_a = nullptr;  // where the failing update's acceleration is
  int rv = 0;
  bool state_ok = true;
  sunrealtype t = 0;
  UpdateResult update = {CE_SUCCESS, 0};
};

// D_1 = u - c_0 a: the velocity from the half-step velocity u = v + c_0 a a run of G3 steps
// carried (LeapKernels), equal to rounding.
void VelocityFromHalfStep(CEodeMemRec* ce, const StepMem& sm, N_Vector a) {
  N_VLinearSum(1, ce->D[1], -sm.plans[sm.plan_ix].combos[0].c[0], a, ce->D[1]);
}

// f failed in a run whose later steps share one acceleration buffer (LeapRun), which held a(tcur):
// x(tcur) = x(tcur + h) - h u, a(tcur) evaluated again there, v = u - c a, each to rounding.
int LostAccelerationExit(CEodeMemRec* ce, const StepMem& sm, const LeanEnd& e, const char* func) {
  const Combo& drift = sm.plans[sm.plan_ix].combos[2];  // x(t) + h u
  N_VLinearSum(1, ce->xnext, -drift.c[0], ce->D[1], ce->xcur);
  const int rv = CallRhs(ce, ce->tcur, ce->xcur, ce->D[1], ce->D[2]);
  ++ce->nfe;
  if (rv != 0) return RhsFailed(ce, rv, ce->tcur, func);
  VelocityFromHalfStep(ce, sm, ce->D[2]);
  return RhsFailed(ce, e.rv, e.t, func);
}

// Brings the vectors to the state TakeStep would have left (the position and a carried
// velocity to rounding, or the failed step's, where it was written over), then reports as
// TakeStep does.
int LeanExit(CEodeMemRec* ce, StepMem* sm, int ip, const LeanEnd& e, long int* taken) {
  static const char* func = "CEodeEvolve";
  if (e.steps % 2 != 0) RotateHistory(ce, *sm);
  for (long int j = 0; j < e.moved % 3; ++j) RotatePositions(ce);
  sm->plan_ix = ip;
  *taken = e.steps;
  if (e.rv != 0) {
    if (e.accel_lost) return LostAccelerationExit(ce, *sm, e, func);
    if (e.carried) VelocityFromHalfStep(ce, *sm, ce->D[2]);
    if (e.over) RebuildPosition(ce);
    return RhsFailed(ce, e.rv, e.t, func);
  }
  if (!e.state_ok) {
    if (e.failed_a != ce->Dnew[2]) N_VScale(1, e.failed_a, ce->Dnew[2]);  // CheckState reads it
    if (e.failed_carried) VelocityFromHalfStep(ce, *sm, ce->Dnew[2]);
    if (e.over) N_VScale(1, e.failed_over ? ce->xnext : ce->xnew, ce->xcur);
    return CheckState(ce, e.t, e.update, func, !e.failed_over);
  }
  const bool guard_due = e.steps > 0 && ce->guard.every > 0 && ce->nst % ce->guard.every == 0;
  return guard_due ? GuardCheck(ce, func) : CE_SUCCESS;
}

// G3_CD's run carrying the half-step velocity (StepMem::leap) over at least three steps: every
// step after the first has f write one buffer, the last step's, and the middle steps' update read
// it there (mid), so that the run touches x, u and one acceleration, as the leapfrog does.
struct LeapRun {
  N_Vector a = nullptr;        // that buffer; nullptr: no such run
  N_Vector first_a = nullptr;  // the first step's acceleration
  FusedPlan mid;               // fused_plans_xin with that buffer as the acceleration
};
void PrepareLeapRun(const StepMem& sm, const PhaseVectors* pv, int ip, long int count, LeapRun* r) {
  if (!sm.leap || count < 3) return;
  r->a = pv[(ip + ((count - 1) % 2) * 3) % kNumPlans].a;  // every step but the last moves 3 on
  r->first_a = pv[ip].a;
  r->mid = sm.fused_plans_xin[(ip + 3) % kNumPlans];  // x, u: the same buffers in every phase
  sunrealtype* a = SerialData(r->a);
  r->mid.terms[0].X[2] = a;
  r->mid.terms[1].X[1] = a;
}

// Step `steps` of the lean loop's update after f: the in-place plan (over) or the out-of-place
// one, with G3_CD's half-step velocity carried the kernel of the first, a middle or the last step.
template <bool kLeap>
inline sunrealtype LeanUpdate(const PhaseVectors& p, const StepMem& sm, const LeapRun& run,
                              long int steps, bool over) {
  const sunindextype len = sm.len;
  if constexpr (!kLeap) return over ? p.update_over(*p.plan_over, len) : p.update(*p.plan, len);
  if (!over) return (steps > 0 ? p.leap.last : p.update)(*p.plan, len);
  if (steps == 0) return p.leap.first(*p.plan_over, len);
  return run.a != nullptr ? p.leap.mid(run.mid, len) : p.leap.mid(*p.plan_over, len);
}

// TakeStep's explicit step on serial (kMpi: NVECTOR_PARALLEL, the same kernel on this rank's
// part, one allreduce per step) vectors without a mass matrix, many in a row: f's vectors come
// from a table of the six configurations and the vectors rotate once at the end, so that a step
// at n = 1 is f, the update and a few tests (bench_step). With in-place plans every step but the
// last writes x(t + 2h) over x(t + h), as a hand loop does (docs/theory.md, "In-place update").
template <bool kMpi, bool kLeap>
__attribute__((noinline)) int LeanExplicitSteps(CEodeMemRec* ce, StepMem* sm, sunrealtype target,
                                                long int max_steps, long int* taken) {
  PhaseVectors pv[kNumPlans];
  int ip = sm->plan_ix;
  for (int j = 0; j < kNumPlans; ++j) {
    const int i = (ip + j) % kNumPlans;
    const bool over = sm->xin_ready;
    pv[i] = {ce->xnext,           ce->D[1],           ce->Dnew[2],
             &sm->fused_plans[i], sm->kernels[i],     over ? &sm->fused_plans_xin[i] : nullptr,
             sm->kernels_xin[i],  sm->leap_kernels[i]};
    RotateVectors(ce, sm);
  }
  const sunrealtype bound = GrowthBound(ce);  // xl1_start is fixed between restarts
  const CEodeRhsFn rhs = ce->adapters.rhs;    // CallRhs's, kept in registers across the run
  void* const rhs_data = ce->adapters.rhs_data;
  const long int count = LeanStepCount(ce, target, max_steps);
  LeapRun run;
  if constexpr (kLeap) PrepareLeapRun(*sm, pv, ip, count, &run);
  LeanEnd e;
  while (e.steps < count) {
    e.t = StepTime(ce, 1);
    const PhaseVectors& p = pv[ip];
    const N_Vector a = kLeap && run.a != nullptr && e.steps > 0 ? run.a : p.a;
    e.rv = rhs(e.t, p.x, p.v, a, rhs_data);
    ++ce->nfe;
    if (e.rv != 0) {
      e.accel_lost = kLeap && a == run.a && (e.steps > 1 || run.a == run.first_a);
      break;
    }
    const bool over = p.plan_over != nullptr && e.steps + 1 < count;
    e.update.xl1 = LeanUpdate<kLeap>(p, *sm, run, e.steps, over);
    if constexpr (kMpi) e.update = GlobalL1(p.x, e.update.xl1);  // one allreduce, as TakeStep's
    e.state_ok = std::isfinite(e.update.xl1) && !Exploded(e.update.xl1, bound);
    if (!e.state_ok) {
      e.failed_over = over;
      e.failed_carried = kLeap && over;
      e.failed_a = a;
      break;
    }
    ce->tcur = e.t;
    ++ce->nsteps_h;
    ++ce->nst;
    ++e.steps;
    e.over = over;
    e.carried = kLeap && over;
    e.moved += over ? 0 : 1;
    ip += over ? 3 : 1;                    // over: the positions keep their buffers
    if (ip >= kNumPlans) ip -= kNumPlans;  // a compare, where % 6 is a multiply and shifts
  }
  return LeanExit(ce, sm, ip, e, taken);
}

// The direct paths' span of the grid, in steps: where |tcur| + |t_start_h| <= DirectTimeSpan() h,
// every time of the grid (t_start_h + k h, and tcur + h) is within 5 rounding units of it,
// 2.5e-10 h, of its exact value, and the grid tolerance is 1e-8 h (64 rounding units of tcur are
// less): one step always remains before tcur + h (StepsRemain) and ends on it (OnGrid), with a
// margin of 40. Never in single precision (below one step).
constexpr sunrealtype DirectTimeSpan() { return SUN_RCONST(1e-10) / SUN_UNIT_ROUNDOFF; }

// Whether the stop time, if one is set, leaves a call ending at t (within direct_tmax) as it is:
// more than a step beyond t, where EvolveTarget's round-off margin (at most 1e-8 h there) cannot
// reach.
inline bool StopBeyond(const CEodeMemRec* ce, sunrealtype t) {
  return !ce->tstop_set || ce->tstop - t > ce->h;
}

// StepMem::steps without the lean loop: TakeStep as many times in a row as LeanStepCount admits,
// so that a run of implicit steps does not go back to StepTo after each; one step where only a
// few remain (CE_ONE_STEP calls decide on the distance alone, as LeanOrOneStep's).
int ManySteps(CEodeMemRec* ce, sunrealtype target, long int max_steps, long int* taken) {
  const bool run = target - ce->tcur > kLeanMinSteps * ce->h && max_steps >= kLeanMinSteps;
  const long int count = run ? std::max(1L, LeanStepCount(ce, target, max_steps)) : 1;
  const sunrealtype h = ce->h;  // a step that changes h (a guard check) ends the run
  long int k = 0;
  int flag = CE_SUCCESS;
  while (k < count && ce->h == h && (flag = TakeStep(ce)) == CE_SUCCESS) ++k;
  *taken = k;
  return flag;
}

// TakeStep on the lean loop's configuration, one step: f called directly and the update's
// kernel run directly (no solve or backend to dispatch), out of place, as the lean loop's last
// step. What CE_ONE_STEP and outputs a few steps apart take.
template <bool kMpi>
__attribute__((always_inline)) inline int LeanOneStep(CEodeMemRec* ce) {
  static const char* func = "CEodeEvolve";
  StepMem* sm = ce->step.get();
  const sunrealtype t = StepTime(ce, 1);
  const int rv = CallRhs(ce, t, ce->xnext, ce->D[1], ce->Dnew[2]);
  ++ce->nfe;
  if (rv != 0) return RhsFailed(ce, rv, t, func);
  const int ip = sm->plan_ix;
  UpdateResult r = {CE_SUCCESS, sm->kernels[ip](sm->fused_plans[ip], sm->len)};
  if constexpr (kMpi) r = GlobalL1(ce->xnext, r.xl1);
  if (!(r.xl1 <= sm->growth_limit)) {  // not finite, or Exploded: TakeStep's test in one compare
    const int flag = CheckState(ce, t, r, func);
    if (flag != CE_SUCCESS) return flag;
  }
  Commit(ce, sm, t);
  if (ce->guard.every > 0 && ce->nst % ce->guard.every == 0) return GuardCheck(ce, func);
  return CE_SUCCESS;
}

// StepMem::steps with the lean loop: it runs unless only a few steps remain (CE_ONE_STEP calls
// decide on the distance alone); those are taken here one by one, as StepTo would ask for them.
template <bool kMpi, bool kLeap>
int LeanOrOneStep(CEodeMemRec* ce, sunrealtype target, long int max_steps, long int* taken) {
  if (target - ce->tcur > kLeanMinSteps * ce->h && max_steps >= kLeanMinSteps) {
    return LeanExplicitSteps<kMpi, kLeap>(ce, ce->step.get(), target, max_steps, taken);
  }
  long int k = 0;
  int flag = CE_SUCCESS;
  do {
    flag = LeanOneStep<kMpi>(ce);
    k += flag == CE_SUCCESS ? 1 : 0;
  } while (flag == CE_SUCCESS && k < max_steps && StepsRemain(ce, target));
  *taken = k;
  return flag;
}

}  // namespace

int TakeSteps(CEodeMemRec* ce, sunrealtype target, long int max_steps, long int* taken) {
  return ce->step->steps(ce, target, max_steps, taken);
}

namespace {

// xout = x(tcur), vout = D_1 on serial vectors, and whether they are finite: at one unknown
// without a loop's set-up, the test on the two values.
__attribute__((always_inline)) inline bool CopyPairFiniteSerial(const CEodeMemRec* ce,
                                                                N_Vector xout, N_Vector vout) {
  const sunrealtype* x = NV_DATA_S(ce->xcur);
  const sunrealtype* v = NV_DATA_S(ce->D[1]);
  if (ce->n != 1) return CopyPairFiniteApart(ce->xcur, ce->D[1], xout, vout);
  return CopyPairFiniteOf<1>(x, v, NV_DATA_S(xout), NV_DATA_S(vout));
}

}  // namespace

namespace {

// StepMem::fast_until from the current step on: the first k >= nsteps_h at which a call starting
// at StepTime's time for k would leave direct_tmax's span, come within a step of the stop time or
// end its step on a guard check (0 where the current call does). |t| <= direct_tmax and the stop
// time's margin are the direct path's conditions on a call's start, here on the times the steps
// will set; both are monotone in k (as those times are) from a k where they hold, so that they
// hold on one run of k, whose end the distances in steps give to within a step or two.
long int FastSpanEnd(const CEodeMemRec* ce, const StepMem& sm) {
  const long int k0 = ce->nsteps_h;
  const long int every = ce->guard.every;
  // nst = nst - nsteps_h + k at every k of the run: the steps keep the two counts together.
  const long int to_check = every > 0 ? (every - (ce->nst + 1) % every) % every : LONG_MAX;
  const long int end = k0 + std::min(to_check, LONG_MAX - k0);  // no overflow for any period
  const auto holds = [&](long int k) {
    const sunrealtype t = ce->t_start_h + static_cast<sunrealtype>(k) * ce->h;  // StepTime's
    return std::fabs(t) <= sm.direct_tmax && StopBeyond(ce, t + ce->h);
  };
  if (end <= k0 || !DirectOptions(ce) || !holds(k0)) return 0;
  sunrealtype room = (sm.direct_tmax - ce->tcur) / ce->h;  // at most 2 DirectTimeSpan()
  if (ce->tstop_set) room = std::min(room, (ce->tstop - ce->tcur) / ce->h);
  long int k = k0 + static_cast<long int>(std::min(room, static_cast<sunrealtype>(end - 1 - k0)));
  while (k > k0 && !holds(k)) --k;
  while (k + 1 < end && holds(k + 1)) ++k;
  return k + 1;
}

// The arguments of a call on a fast span: serial outputs of the run's length, tret, a finite tout
// (tout - tout is NaN exactly where tout is not, which the general path refuses).
__attribute__((always_inline)) inline bool FastArguments(const CEodeMemRec* ce, sunrealtype tout,
                                                         N_Vector xout, N_Vector vout,
                                                         const sunrealtype* tret) {
  return SerialOfLength(xout, ce->n) && SerialOfLength(vout, ce->n) && tret != nullptr &&
         !std::isnan(tout - tout);
}

// One step of the configuration (StepMem::one; LeanOneStep not inlined here: OneStepEvolve's
// alone) towards target = tcur + h, then the outputs, on OneStepChecked's direct path.
__attribute__((noinline)) int DirectOneStep(CEodeMemRec* ce, sunrealtype target, N_Vector xout,
                                            N_Vector vout, sunrealtype* tret) {
  const int flag = ce->step->one(ce);
  if (flag != CE_SUCCESS || !OnGrid(ce, target) || !CopyPairFiniteSerial(ce, xout, vout)) {
    return OneStepRest(ce, flag, target, xout, vout, tret);
  }
  *tret = ce->tretlast = ce->tcur;
  return CE_SUCCESS;
}

// OneStepEvolve outside its fast path: the same path with its tests of the configuration and
// of the grid (a step must remain before tcur + h and end on it to round-off), taken where h is
// near the round-off of t or the run has no direct path. Opens the fast path where the run
// allows it from here on (FastSpanEnd).
__attribute__((noinline)) int OneStepChecked(CEodeMemRec* ce, sunrealtype tout, N_Vector xout,
                                             N_Vector vout, sunrealtype* tret) {
  StepMem* sm = ce->step.get();
  // Error control has no fast span (FastSpanEnd): its calls come here, and go on to its own path.
  if (AdaptOn(ce)) return AdaptCall(ce, tout, xout, vout, tret, CE_ONE_STEP);
  const long int span = FastSpanEnd(ce, *sm);
  sm->fast_until = span;
  const sunrealtype target = ce->tcur + ce->h;
  const bool direct = FastArguments(ce, tout, xout, vout, tret) && ce->started &&
                      ce->step->one_call && DirectConfiguration(ce) && StepsRemain(ce, target);
  if (!direct) return EvolveOneStepGeneral(ce, tout, xout, vout, tret);
  return DirectOneStep(ce, target, xout, vout, tret);
}

}  // namespace

namespace {

// f failed on the fast path: reported as LeanOneStep reports it, then the last good state
// (OneStepRest). Out of line: the fast path keeps nothing of its own across the report.
__attribute__((noinline, cold)) int FastRhsFailed(CEodeMemRec* ce, int rv, sunrealtype t,
                                                  N_Vector xout, N_Vector vout, sunrealtype* tret) {
  const int flag = RhsFailed(ce, rv, t, "CEodeEvolve");
  return OneStepRest(ce, flag, ce->tcur, xout, vout, tret);
}

// The update's kernel on the current configuration (UpdateOnSerial's): ||x(t + h)||_1.
__attribute__((always_inline)) inline sunrealtype FastUpdate(const CEodeMemRec* ce) {
  const StepMem* sm = ce->step.get();
  const int ip = sm->plan_ix;
  return sm->kernels[ip](sm->fused_plans[ip], sm->len);
}

// Commit on the fast path, then xout = x(tcur), vout = D_1 and whether they are finite. At one
// unknown only the velocity is tested: x(tcur) was this step's x(t), the accumulated term of the
// position it wrote (BuildUpdatePlan), so a NaN or Inf in it failed the growth check already.
// kSwap: the history's swap where it is a fixed one (2: D_1 and D_2 at degree 3; 4:
// RotateHistory's four slots at degree 4; 0: RotateHistory); kOne: one unknown.
template <int kSwap, bool kOne>
__attribute__((always_inline)) inline bool FastCommit(CEodeMemRec* ce, StepMem* sm, sunrealtype t,
                                                      N_Vector xout, N_Vector vout) {
  const StepMem::FastPhases& ph = sm->fast_phases;
  const auto ip = static_cast<unsigned>(sm->plan_ix);  // 0..5: its load is the index's widening
  const int next = ph.next[ip];
  if constexpr (kSwap == 2) {
    SwapSlots<2>(ce->D + 1, ce->Dnew + 1);
  } else if constexpr (kSwap == 4) {
    SwapSlots<4>(ce->D, ce->Dnew);
  } else {
    RotateHistory(ce, *sm);
  }
  RotatePositions(ce);
  sm->plan_ix = next;
  ce->tcur = t;
  ++ce->nsteps_h;
  ++ce->nst;
  if constexpr (!kOne) {
    return CopyPairFiniteApart(ce->xcur, ce->D[1], xout, vout);
  } else {
    const sunrealtype v = ph.v[ip][0];
    NV_DATA_S(xout)[0] = ph.x[ip][0];
    NV_DATA_S(vout)[0] = v;
    return !std::isnan(v - v);  // v - v is NaN exactly where v is not finite
  }
}

// A call's step on a fast span (StepMem::fast_until: opened by OneStepChecked): the solve
// (kLean: the call of f, LeanOneStep's step without its guard test, the span ending before a
// step with a check), the update's kernel, the commit (FastCommit's kSwap and kOne) and the
// outputs' copy, with the tests of the call's arguments alone; every failure the caller
// module's (OneStepRest).
template <bool kLean, int kSwap, bool kOne>
int FastStep(CEodeMemRec* ce, N_Vector xout, N_Vector vout, sunrealtype* tret) {
  static const char* func = "CEodeEvolve";
  const sunrealtype t = StepTime(ce, 1);
  if constexpr (kLean) {
    const int rv = CallRhs(ce, t, ce->xnext, ce->D[1], ce->Dnew[2]);
    ++ce->nfe;
    if (rv != 0) return FastRhsFailed(ce, rv, t, xout, vout, tret);
  } else {
    const int flag = ce->step->solve(ce, t, StepTime(ce, 2), ce->xnext, ce->Dnew[2], func);
    if (flag != CE_SUCCESS) return OneStepRest(ce, flag, ce->tcur, xout, vout, tret);
  }
  const sunrealtype xl1 = FastUpdate(ce);
  // Not finite, or Exploded: TakeStep's test in one compare.
  if (!(xl1 <= ce->step->growth_limit)) {
    const int flag = CheckState(ce, t, {CE_SUCCESS, xl1}, func);
    if (flag != CE_SUCCESS) return OneStepRest(ce, flag, ce->tcur, xout, vout, tret);
  }
  // Read after the calls: a value fewer kept across them, so the function saves fewer registers.
  StepMem* sm = ce->step.get();
  // Outputs that are not finite: reported as ReturnAtTarget reports them (the step ended on
  // tcur, the target, to round-off).
  if (!FastCommit<kSwap, kOne>(ce, sm, t, xout, vout)) {
    return OneStepRest(ce, CE_SUCCESS, ce->tcur, xout, vout, tret);
  }
  *tret = ce->tretlast = t;
  return CE_SUCCESS;
}

// FastStep for the configuration: lean (the call of f) or solved, the swap 0, 2 or 4, one
// unknown or more.
template <bool kLean, int kSwap>
constexpr std::array<FastStepFn, 2> kFastStepsOf = {&FastStep<kLean, kSwap, false>,
                                                    &FastStep<kLean, kSwap, true>};
template <bool kLean>
constexpr std::array<std::array<FastStepFn, 2>, 3> kFastStepsBySwap = {
    kFastStepsOf<kLean, 0>, kFastStepsOf<kLean, 2>, kFastStepsOf<kLean, 4>};
constexpr std::array<std::array<std::array<FastStepFn, 2>, 3>, 2> kFastSteps = {
    kFastStepsBySwap<false>, kFastStepsBySwap<true>};

// StepMem::fast_step, and fast_phases from the current vectors: six commits' rotations (the
// identity), each configuration's outputs read after its own. At degree 3 the fast commit swaps
// the two derivatives alone: RotateHistory's other two slots are D_0 (unused) and a spare.
void BuildFastPhases(CEodeMemRec* ce, StepMem* sm) {
  const bool plain = !sm->in_place_active && !ce->compensated;
  const int swap = plain && ce->degree == 3 ? 2 : (plain && ce->degree == 4 ? 4 : 0);
  sm->fast_step = kFastSteps[sm->lean_one ? 1 : 0][swap / 2][ce->n == 1 ? 1 : 0];
  if (!sm->one_call) return;  // serial vectors: their data directly
  for (int j = 0; j < kNumPlans; ++j) {
    const int ip = sm->plan_ix;
    RotateVectors(ce, sm);
    sm->fast_phases.x[ip] = NV_DATA_S(ce->xcur);
    sm->fast_phases.v[ip] = NV_DATA_S(ce->D[1]);
    sm->fast_phases.next[ip] = sm->plan_ix;
  }
}

}  // namespace

// A call on the configuration's fast span takes the step chosen for it (StepMem::fast_step): the
// lean configuration's as many instructions as the lean loop's step and the copy. Every other
// case is OneStepChecked's.
int OneStepEvolve(CEodeMemRec* ce, sunrealtype tout, N_Vector xout, N_Vector vout,
                  sunrealtype* tret) {
  const StepMem* sm = ce->step.get();
  if (ce->nsteps_h < sm->fast_until && FastArguments(ce, tout, xout, vout, tret)) {
    return sm->fast_step(ce, xout, vout, tret);
  }
  return OneStepChecked(ce, tout, xout, vout, tret);
}

// As OneStepEvolve, for CE_NORMAL: a call at most the lean loop's minimum of steps ahead (from
// further the lean loop runs, on EvolveNormalGeneral's path, as it would there), tout in the span
// too (every time of the call is then where GridTolerance is grid_tol), and more steps allowed
// than it can take. The steps as StepTo takes them (LeanOrOneStep's one by one, while StepsRemain),
// and the outputs as ReturnAtTarget gives them.
int NormalEvolve(CEodeMemRec* ce, sunrealtype tout, N_Vector xout, N_Vector vout, sunrealtype* tret,
                 int itask) {
  const StepMem* sm = ce->step.get();
  const bool direct = itask == CE_NORMAL && ce->started && std::fabs(ce->tcur) <= sm->direct_tmax &&
                      std::fabs(tout) <= sm->direct_tmax && tout >= ce->tcur &&
                      tout - ce->tcur <= kLeanMinSteps * ce->h && ce->mxstep > kLeanMinSteps &&
                      DirectOptions(ce) && StopBeyond(ce, tout) && SerialOfLength(xout, ce->n) &&
                      SerialOfLength(vout, ce->n) && tret != nullptr;
  if (!direct) return EvolveNormalGeneral(ce, tout, xout, vout, tret, itask);
  while (tout - ce->tcur > sm->grid_remain) {  // StepsRemain
    const int flag = sm->lean_one ? LeanOneStep<false>(ce) : sm->one(ce);
    if (flag != CE_SUCCESS) return OneStepRest(ce, flag, tout, xout, vout, tret);
  }
  const sunrealtype s = std::fabs(tout - ce->tcur) <= sm->grid_tol ? 0 : tout - ce->tcur;
  const bool finite =
      s == 0 ? CopyPairFiniteSerial(ce, xout, vout) : OutputState(ce, s, xout, vout);
  if (!finite) return OneStepRest(ce, CE_SUCCESS, tout, xout, vout, tret);
  *tret = ce->tretlast = s == 0 ? ce->tcur : tout;
  return CE_SUCCESS;
}

bool TakeDirectStep(CEodeMemRec* ce, int* flag) {
  const StepMem* sm = ce->step.get();
  if (sm == nullptr || sm->one == nullptr) return false;
  *flag = sm->one(ce);
  return true;
}

void SetImplicitSolve(CEodeMemRec* ce, SolveKind kind) { ce->step->implicit = kind; }

SolveKind ChosenSolve(const CEodeMemRec* ce) { return ce->step->solve_kind; }

namespace {
void CloseSpans(StepMem* sm) { sm->fast_until = 0; }
}  // namespace

void StepRestart(CEodeMemRec* ce) {
  if (ce->step == nullptr) return;
  ce->step->direct_tmax = -1;
  CloseSpans(ce->step.get());
}

void StepOptionsChanged(CEodeMemRec* ce) {
  if (ce->step != nullptr) CloseSpans(ce->step.get());
}

// The step of each path of docs/theory.md: TakeStep with the solve of the kind,
//   kExplicit     SolveExplicit (above; section 4.1),
//   kNewton       SolveImplicit (ceode_nls.cpp; section 4.2),
//   kPC           SolvePC (ceode_pc.cpp; section 4.3),
//   kAuto         SolveAuto (ceode_pc.cpp: PC or Newton by the coupling; section 4.3),
//   kConstrained  ConstrSolveStep (ceode_constraints.cpp; section 8),
//   kDiagonal     SolveDiagonal (ceode_pc.cpp: f affine in x' with a diagonal Jacobian; 4.3),
// then the update on the backend the vectors allow (serial, this rank's part of NVECTOR_PARALLEL,
// or the N_Vector reference). The explicit step without a mass matrix on the serial backend takes
// many steps per call in the lean loop (LeanExplicitSteps).
void ChooseStep(CEodeMemRec* ce, bool restart) {
  StepMem* sm = ce->step.get();
  if (restart) {
    sm->plan_ix = 0;
    sm->solve_kind = HasConstraints(ce)  ? SolveKind::kConstrained
                     : ce->vel_dependent ? sm->implicit
                                         : SolveKind::kExplicit;
  }
  constexpr SolveFn kSolve[] = {SolveExplicit, SolveImplicit,   SolvePC,
                                SolveAuto,     ConstrSolveStep, SolveDiagonal};
  sm->solve = kSolve[static_cast<int>(sm->solve_kind)];
  // In place or not depends on the solve. Error control steps with passes of its own
  // (ceode_adapt_step.cpp), and a fixed step starts the method again: no plans then.
  if (AdaptOn(ce)) {
    NoPlans(sm);
  } else {
    BuildPlans(ce, sm);
  }
  const bool serial = sm->fused && sm->serial;
  const bool mpi = sm->fused && sm->mpi;
  sm->update = serial ? UpdateOnSerial : (mpi ? UpdateOnMpi : UpdateOnReference);
  const bool lean = (serial || mpi) && sm->solve_kind == SolveKind::kExplicit && !HasMassMatrix(ce);
  // G3_CD's carried half-step velocity (StepMem::leap) is a variant of the loop, chosen here.
  constexpr StepsFn kLean[2][2] = {{LeanOrOneStep<false, false>, LeanOrOneStep<false, true>},
                                   {LeanOrOneStep<true, false>, LeanOrOneStep<true, true>}};
  sm->steps = !lean ? ManySteps : kLean[mpi ? 1 : 0][sm->leap ? 1 : 0];
  sm->one = !lean ? TakeStep : (mpi ? LeanOneStep<true> : LeanOneStep<false>);
  sm->one_call = serial;
  sm->lean_one = lean && serial;
  sm->growth_limit = std::min(GrowthBound(ce), kAbsoluteLimit);  // xl1_start is the start's
  sm->grid_tol = SUN_RCONST(1e-8) * ce->h;                       // GridTolerance's second term
  sm->grid_remain = ce->h - sm->grid_tol;
  sm->direct_tmax = sm->one_call ? DirectTimeSpan() * ce->h - std::fabs(ce->t_start_h) : -1;
  CloseSpans(sm);  // the next checked call opens them for this configuration
  BuildFastPhases(ce, sm);
}

}  // namespace ceode
