// The step module's record (CEodeMemRec::step), private to ceode_step.cpp and
// ceode_step_plans.cpp, which alone write it: the update options, and what ChooseStep decides
// once per start (the solve, the update plans and their kernel, the many-step loop), so that a
// step tests no configuration flag; and the history's swap, which the fixed and the adaptive
// step share.
#ifndef CEODE_SRC_CEODE_STEP_HPP_
#define CEODE_SRC_CEODE_STEP_HPP_

#include <array>
#include <utility>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "ceode_kernels.hpp"

namespace ceode {

// What the update of one step returns: CE_VECTOROP_ERR when the global reduction of the growth
// check's norm failed (xl1 is then NaN), and ||x(t + h)||_1.
struct UpdateResult {
  int flag;
  sunrealtype xl1;
};

using SolveFn = int (*)(CEodeMemRec* ce, sunrealtype t, sunrealtype tnext, N_Vector x, N_Vector a,
                        const char* func);
using UpdateFn = UpdateResult (*)(CEodeMemRec* ce, const StepMem& sm);
using StepsFn = int (*)(CEodeMemRec* ce, sunrealtype target, long int max_steps, long int* taken);
using FastStepFn = int (*)(CEodeMemRec* ce, N_Vector xout, N_Vector vout, sunrealtype* tret);

struct StepMem {
  // Options
  bool fused = true;     // CEodeSetFusedKernel: the serial backend where the vectors allow it
  bool in_place = true;  // CEodeSetInPlaceUpdate: in-place plans allowed

  // The step, chosen once (ChooseStep)
  SolveKind implicit = SolveKind::kNewton;  // ceode_pc.cpp's choice for a velocity dependence
  SolveKind solve_kind = SolveKind::kExplicit;
  SolveFn solve = nullptr;    // the acceleration at t (TakeStep)
  UpdateFn update = nullptr;  // the derivatives and x(t + h) after the solve (TakeStep)
  StepsFn steps = nullptr;    // TakeSteps: the lean loop or ManySteps
  // TakeDirectStep: one step of the configuration (LeanOneStep on the lean one, else TakeStep)
  int (*one)(CEodeMemRec* ce) = nullptr;
  bool one_call = false;  // serial vectors: OneStepEvolve's and NormalEvolve's direct paths
  bool lean_one = false;  // one_call on the lean configuration: the direct paths inline its step
  // OneStepEvolve's direct path: while |tcur| stays at or below it, the grid's times are exact to
  // far inside GridTolerance (one step always remains before tcur + h and ends on it); negative
  // where the run has no direct path (not one_call).
  sunrealtype direct_tmax = -1;
  // OneStepEvolve's fast path: while nsteps_h is below it, a call's step is within direct_tmax,
  // ends more than a step before the stop time, has no guard check at its end, and the options
  // DirectOptions tests are as they were when OneStepChecked found them so (FastSpanEnd), so
  // that the call tests nothing but its arguments. 0: closed (StepOptionsChanged).
  long int fast_until = 0;
  // The step of a call on that span (one_call runs), chosen with the configuration
  // (BuildFastPhases): the lean configuration's call of f or the solve, the commit's swap of the
  // history and the copy of one unknown or of more.
  FastStepFn fast_step = nullptr;
  // The fast path's commit, per configuration (by plan_ix, one_call runs): the data of x(tcur)
  // and D_1 after its step, the outputs' sources, and the configuration that follows, in arrays
  // of their own (each entry is then one indexed load).
  struct FastPhases {
    std::array<const sunrealtype*, kNumPlans> x{};
    std::array<const sunrealtype*, kNumPlans> v{};
    std::array<int, kNumPlans> next{};
  };
  FastPhases fast_phases;
  // The step's growth check in one test (LeanOneStep): ||x(t + h)||_1 passes while it is at or
  // below this, the lesser of GrowthBound and the absolute limit (NaN and Inf do not).
  sunrealtype growth_limit = 0;
  // Within direct_tmax, GridTolerance(ce, h) is 1e-8 h: that value (grid_tol) and h less it
  // (grid_remain, StepsRemain's bound), computed as those functions compute them (NormalEvolve).
  sunrealtype grid_tol = 0;
  sunrealtype grid_remain = 0;

  // The update plans (ceode_step_plans.cpp)
  bool in_place_active = false;  // the plans update InPlaceLevel derivatives in place
  bool serial = false;           // serial vectors: fused_plans valid, raw arrays of length n
  bool mpi = false;              // NVECTOR_PARALLEL: fused_plans valid on the local part
  sunindextype len = 0;          // entries the serial backend runs over (local on NVECTOR_PARALLEL)
  std::array<UpdatePlan, kNumPlans> plans;  // by plan_ix
  std::array<FusedPlan, kNumPlans> fused_plans;
  std::array<SerialKernelFn, kNumPlans> kernels{};  // SerialKernel of each fused plan at len
  // The same plans writing x(t + 2h) over x(t + h) (docs/theory.md, "In-place update"): the lean
  // loop's steps before its last one, when xin_ready.
  std::array<FusedPlan, kNumPlans> fused_plans_xin;
  std::array<SerialKernelFn, kNumPlans> kernels_xin{};
  bool xin_ready = false;
  // G3's run of steps carrying the half-step velocity in D_1 (LeapKernels): its kernels for the
  // first, the middle (both on fused_plans_xin) and the last step (on fused_plans) of a run.
  bool leap = false;
  std::array<LeapKernels, kNumPlans> leap_kernels{};
  // The configuration of the vectors: the history's phase (period 2) is plan_ix % 2 and the
  // positions' (period 3) plan_ix % 3. A step advances both (+1); an in-place-position step
  // only the history's (+3).
  int plan_ix = 0;
};

// a[0, M) and b[0, M) trade places, two pointers a move where SSE2 has them (a swap of the
// arrays can compile to a loop, or through the stack).
template <int M>
inline void SwapSlots(N_Vector* a, N_Vector* b) {
#if defined(__SSE2__)
  static_assert(M % 2 == 0 && sizeof(N_Vector) == 8, "pairs of 64-bit pointers");
  if constexpr (M > 0) {
    auto* pa = reinterpret_cast<__m128i*>(a);
    auto* pb = reinterpret_cast<__m128i*>(b);
    const __m128i ta = _mm_loadu_si128(pa);
    const __m128i tb = _mm_loadu_si128(pb);
    _mm_storeu_si128(pa, tb);
    _mm_storeu_si128(pb, ta);
    SwapSlots<M - 2>(a + 2, b + 2);
  }
#else
  for (int j = 0; j < M; ++j) std::swap(a[j], b[j]);
#endif
}

// D and Dnew trade places: fixed lengths, not the degree's slots, the first four (degree <= 4) or
// the whole arrays, a few vector moves instead of a loop; the slots at and above the degree are
// spare buffers and D[0] is unused.
__attribute__((always_inline)) inline void SwapHistorySlots(CEodeMemRec* ce) {
  if (ce->degree <= 4) {  // half the arrays: a few moves fewer per step
    SwapSlots<4>(ce->D, ce->Dnew);
  } else {
    SwapSlots<kMaxDegree>(ce->D, ce->Dnew);
  }
}

// ceode_step_plans.cpp: the six plans (and their kernels) from the current vectors, and which
// backend runs them (in_place_active, serial, mpi, len, xin_ready). Reads sm->solve_kind.
void BuildPlans(CEodeMemRec* ce, StepMem* sm);
// None, for a method whose steps error control takes: no kernel, no serial or MPI backend.
void NoPlans(StepMem* sm);

}  // namespace ceode

#endif  // CEODE_SRC_CEODE_STEP_HPP_
