// Private memory structure and internal interfaces of CEODE. Not installed.
#ifndef CEODE_SRC_CEODE_IMPL_HPP_
#define CEODE_SRC_CEODE_IMPL_HPP_

#include <ceode/ceode.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "ceode_sundials.hpp"

namespace ceode {

// Degree d carries D_0 .. D_{d-1}; d = 3 .. kMaxDegree.
constexpr int kMaxDegree = 8;
constexpr int kCompWork = 9;  // scratch vectors of the reference's error-free compensated sums
constexpr int kMinDegree = 3;

// One named parameter set of docs/theory.md section 5 (table in ceode_method.cpp).
struct MethodSet {
  const char* name;
  int degree;
  std::array<sunrealtype, kMaxDegree - 1> params;
  // CEodeStabilityLimit(degree, params, 0) as this library computes it (0: unstable for every
  // step), so that the guard and its advice look it up instead of scanning the spectrum
  // (1 to 18 ms a set); test_stability recomputes every entry.
  sunrealtype omega_max;
  // DefaultPCCorrections' rule from the set's orders (CEodeMethodOrder), so that setting a
  // method does not solve its order conditions (about 25 000 instructions); test_pc checks
  // every entry against the rule.
  int pc_corrections;
  // The order in x (CEodeMethodOrder), for error control: solving the order conditions costs up
  // to a millisecond a start; test_adapt checks every entry.
  int order_x;
};
const MethodSet* FindMethodSet(const char* name);
// The named set with exactly these parameters, or nullptr (custom parameters).
const MethodSet* NamedSetWithParams(int degree, const sunrealtype* params);
int NumMethodSets();
const MethodSet& MethodSetAt(int index);

// Coefficients of one step of size h, derived from (degree, params, h) only.
// History H_j = D_j(t-h), j = 1..d-1; unknown top derivative z = D_{d-1}(t).
//   D_k(t) = sum_j T[k][j] H_j + c[k] z          (k = 1 .. d-2)
//   z      = (a - B_2) / c[2],   B_2 = sum_j T[2][j] H_j  (d = 3: z = a)
//   x(t+h) - x(t) = sum_{i=1}^{d-2} w[i] D_i(t) + wz_old H_{d-1} + wz_new z
//   v(a)   = sum_j V0[j] H_j + kappa a              (velocity as a function of a)
//   x(t+h) = X0 + mu (a - B_2)                      (used by the constraint solve)
struct StepCoeffs {
  // The degree the entries belong to: ComputeStepCoeffs writes every entry the formulas below
  // give, the others stay zero while the degree stays (0: none set).
  int degree = 0;
  sunrealtype h = 0;
  sunrealtype T[kMaxDegree][kMaxDegree] = {};
  sunrealtype c[kMaxDegree] = {};
  sunrealtype w[kMaxDegree] = {};
  sunrealtype wz_old = 0;
  sunrealtype wz_new = 0;
  sunrealtype V0[kMaxDegree] = {};
  sunrealtype kappa = 0;
  sunrealtype mu = 0;
  sunrealtype pred[kMaxDegree] = {};    // h^i/i!, i < d - 2: the predictor's weights of D_2..
  sunrealtype tw[kMaxDegree + 1] = {};  // h^i/i!, i < d: the position's Taylor weights
};
// With products, the Taylor weights by w[i] = w[i-1] s / i (the adaptive step, whose h changes
// often); otherwise by pow, the values every fixed run has had.
void ComputeStepCoeffs(int degree, const sunrealtype* params, sunrealtype h, StepCoeffs* co,
                       bool products = false);

// Finite-difference weights w of the q-th derivative at 0 on the m nodes x (Fornberg).
void FornbergWeights(int q, int m, const sunrealtype* x, sunrealtype* w);
// The same for every order 0..q at once (q < kMaxDegree): w[k] holds order k.
void FornbergTable(int q, int m, const sunrealtype* x, sunrealtype (*w)[2 * kMaxDegree + 1]);

struct UpdatePlan;  // ceode_kernels.hpp
struct StepMem;     // ceode_step.hpp: the step module's record
struct StepMemFree {
  void operator()(StepMem* sm) const;
};
struct AdaptMem;  // ceode_adapt.hpp: the error-control module's record
struct AdaptMemFree {
  void operator()(AdaptMem* am) const;
};
struct CERootMem;  // ceode_root.cpp: the root-finding module's record
struct RootMemFree {
  void operator()(CERootMem* rm) const;
};

// The acceleration solve of a step, chosen once per start: explicit (docs/theory.md section
// 4.1), the nonlinear solver (4.2), prediction-correction (4.3), either by the coupling (AUTO,
// 4.3), the constrained solve (section 8), or the exact one for a diagonal df/dx' (4.3).
enum class SolveKind { kExplicit, kNewton, kPC, kAuto, kConstrained, kDiagonal };

// What the factored matrix of the attached linear solver holds.
enum class Holds { kNothing, kMass, kNewton };

// Defaults of the options, written once (CEodeMemRec and the setters that restore them).
constexpr long int kDefaultMaxSteps = 500000000L;
constexpr long int kDefaultJacEvalFrequency = 20;

// History and new derivatives swap every step and the three position buffers
// rotate with period 3: six configurations in all.
constexpr int kNumPlans = 6;

// In-place plans (docs/theory.md, "In-place update"): from this many (local) entries on, the
// fused explicit step updates D_1 and D_3 .. D_{d-2} in their own buffers; below it the
// vectors of a step fit in the first cache levels and there is no traffic to save.
constexpr sunindextype kInPlaceMinLen = 1024;
// Whether derivative level k of degree d is updated in place by an in-place plan: all but
// D_2 (f's output buffer) and the top derivative z (read as history by later sums).
constexpr bool InPlaceLevel(int d, int k) { return k != 2 && k != d - 1; }

struct FirstOrder;  // ceode_first_order.cpp
struct Forcing;     // ceode_forcing.cpp

// What CEODE evaluates when it is not the user's f(t, x, v, user_data) alone, and what a Reset
// hands the next start. f and user_data always stay the user's: the adapters read them.
struct Adapters {
  // The right-hand side as the steps call it, rhs(t, x, v, f, rhs_data): the user's f with
  // user_data, or an adapter's with the memory. Set by SelectRhs only, whenever f, user_data or
  // an adapter changes, so that no step decides it again.
  CEodeRhsFn rhs = nullptr;
  void* rhs_data = nullptr;
  FirstOrder* first_order = nullptr;  // CEodeInitFirstOrder's F gives the acceleration
  Forcing* forcing = nullptr;         // the inner stepper's, on top of either (ceode_forcing.hpp)
  void* stepper = nullptr;            // the inner stepper that drives this memory
  // D_2..D_{d-1} at tcur came with the last Reset: the next start evaluates nothing and only
  // forms x(t0 + h). Cleared by that start.
  bool history_preset = false;
};

}  // namespace ceode

struct CEodeMemRec;

namespace ceode {

// Each record below belongs to one module and is written only by that module's file, as
// SUNDIALS hangs CVLsMemRec off cv_lmem; the others read it.

// Mass matrix, linear solver and velocity Jacobian (ceode_ls.cpp).
struct LsMem {
  CEodeMassFn mfn = nullptr;
  SUNMatrix M = nullptr;
  bool mass_constant = true;
  bool mass_evaluated = false;      // M holds M(x, t) at least once
  bool mass_dirty = true;           // M changed since A was last factored from it
  Holds a_holds = Holds::kNothing;  // what the factored A is
  SUNLinearSolver LS = nullptr;
  SUNMatrix A = nullptr;
  SUNMatrix Jsave = nullptr;
  CEodeVelJacFn jac = nullptr;
  bool matrix_free = false;
  bool jac_current = false;
  long int nst_lastsetup = -1;
  sunrealtype kappa_setup = 0;  // kappa of the last Newton matrix setup
  long int msbj = kDefaultJacEvalFrequency;
  bool msbj_set = false;  // CEodeSetJacEvalFrequency called with msbj > 0 (see MatrixUsable)
  bool own_lu = false;    // the Newton matrix is factored with pivots below (LsUseOwnLu)
  std::vector<sunindextype> pivots;
  sunrealtype** lu_cols = nullptr;  // the factored columns of A
  long int nsetups = 0;
  long int nsolves = 0;
  long int nje = 0;
  long int nfeDQ = 0;
  long int nme = 0;
};

// The data of the nonlinear solve's work vectors for its serial backend (ceode_nls_direct.cpp).
struct NlsRaw {
  sunindextype n = 0;
  sunrealtype *apred = nullptr, *atmp = nullptr, *vtmp = nullptr, *V0 = nullptr, *ftmp = nullptr,
              *ewt = nullptr, *ycor = nullptr, *delta = nullptr;
};

// The nonlinear solve of the velocity-dependent step (ceode_nls.cpp, ceode_nls_direct.cpp).
struct NlsMem {
  SUNNonlinearSolver NLS = nullptr;
  bool own = false;
  int maxcor = 6;
  bool maxcor_set = false;  // the constrained solve keeps its own default until set
  sunrealtype reltol = 1e-12;
  sunrealtype abstol = 0;  // 0: relative to the acceleration's max norm
  bool tol_set = false;    // the constrained solve keeps its own default until set
  sunrealtype crate = 1;
  sunrealtype delp = 0;
  sunrealtype t_eval = 0;     // time of the current implicit system
  N_Vector x_eval = nullptr;  // position of the current implicit system (not owned)
  int cb_flag = 0;            // CE_* flag of a callback failure inside the NLS
  bool direct = false;        // the serial backend (ceode_nls_direct.cpp) runs the iteration
  bool jcur = false;          // its "matrix is current"
  NlsRaw raw;                 // its arrays
  N_Vector delta = nullptr;   // its correction vector
  long int nni = 0;
  long int nnf = 0;
  long int nsteps = 0;  // steps solved by the nonlinear solver
};

// CorrectPC's serial form without a mass matrix for the run's degree (ceode_pc.cpp, chosen at each
// start).
using PcPlannedFn = int (*)(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector a, int k,
                            const char* func);

// Prediction-correction, CE_IMPLICIT_AUTO and velocity-dependence detection (ceode_pc.cpp).
struct PcMem {
  int mode = CE_IMPLICIT_AUTO;         // the library chooses (docs/theory.md section 4.3)
  bool mode_set = false;               // CEodeSetImplicitMode called
  bool active = false;                 // AUTO: the step in use is prediction-correction
  long int nst_check = 0;              // AUTO: nst at the last check of the choice
  N_Vector dir = nullptr;              // AUTO: the power iteration's direction, kept warm
  int corrections = 0;                 // 0: k_default
  int k_default = 1;                   // with the method (DefaultPCCorrections)
  int vel_request = -1;                // CEodeSetVelocityDependence's value; -1: never called
  CEodeRhsFn vel_checked_f = nullptr;  // f already probed (no mode set: once per f)
  bool vel_detected = false;           // the last probe found a dependence
  sunrealtype coupling = 0;            // last estimate of kappa ||M^{-1} df/dv|| (0: none)
  sunrealtype theta = 0;               // last measured contraction of the corrections (0: none)
  bool theta_last = false;             // theta is newer than coupling
  bool serial = false;                 // the velocity combinations run on the serial backend
  long int nsteps = 0;                 // steps solved by prediction-correction
  long int ncorr = 0;                  // its evaluation-corrections (one f each)
  long int nfe = 0;                    // f evaluations of the detection and the checks
  // The serial combinations of a step's corrections for one configuration of the buffers at one
  // h: the predicted velocity's weights cp over D_1 .. D_{d-1}, the corrected one's cc over them
  // and a, their data in x (D_1 .. D_{d-1}, a) and vtmp's in out. The buffers trade places every
  // step, so two are kept, each keyed by its vectors (PcPlanFor); a start clears them.
  struct Plan {
    sunrealtype h = 0;
    N_Vector key[4] = {};  // D_1, D_2, D_{d-1} and a
    sunrealtype cp[kMaxDegree] = {};
    sunrealtype cc[kMaxDegree] = {};
    const sunrealtype* x[kMaxDegree] = {};
    sunrealtype* out = nullptr;
  };
  Plan plans[2];
  int plan_last = 1;              // the slot the last step used
  PcPlannedFn planned = nullptr;  // nullptr on other backends or with a mass matrix
  // CEodeSetVelJacDiagonal: f affine in x' with df/dx' = diag(c) (a copy of c), the step's solve
  // exact in one f (SolveDiagonal); 1 / (1 - kappa c) for the step diag_h (0: none yet).
  N_Vector diag = nullptr;
  N_Vector diag_inv = nullptr;
  sunrealtype diag_h = 0;
};

// The runtime stability guard (ceode_guard.cpp).
struct GuardMem {
  int mode = CE_GUARD_WARN;
  long int every = 0;  // 0: at start only
  sunrealtype omega_user = 0;
  sunrealtype omega_est = 0;
  sunrealtype omega_limit = 0;  // Omega_max of the method, computed lazily
  bool warned = false;
  bool pending = false;  // check at the next CEodeEvolve (start, new omega or mode)
  long int nfe = 0;      // f evaluations of its Lanczos iteration
  long int nme = 0;      // mass evaluations into its own copy of M
  long int nsetups = 0;  // factorisations of its own copy of M
  void* work = nullptr;  // scratch, M copy and solver
  // CEodeSetGuardReuse: the last run's estimate stands for the first check after a restart
  bool reuse = false;
  bool carried = false;  // omega_est is the last run's, not yet used by this one
  // D_2 = f(tcur, xcur, D_1) from the start (no mass matrix), valid at step accel_nst
  bool accel = false;
  long int accel_nst = 0;
};

// Index-3 constraints (ceode_constraints.cpp).
struct ConstrMem {
  CEodeConstrFn phi_fn = nullptr;
  CEodeConstrJacFn G_fn = nullptr;
  sunindextype nc = 0;
  N_Vector lambda = nullptr;
  N_Vector phi = nullptr;
  bool template_checked = false;  // Phi seen to write every template entry
  bool schur = true;              // Schur complement for small saddle systems (SaddleSetup)
  long int nce = 0;
  long int nge = 0;  // constraint Jacobian (CEodeConstrJacFn) evaluations
  // The saddle-point solver's own statistics (CEODE's getters add them to the other solvers').
  long int nni = 0;
  long int nnf = 0;
  long int nje = 0;
  long int nsetups = 0;
  long int nsolves = 0;
  void* work = nullptr;  // the saddle-point workspace
};

// Consistent initial conditions of the constrained problem (ceode_ic.cpp).
struct IcMem {
  bool pending = false;  // the next start checks x0, v0 (set by CEodeInit and CEodeReInit)
  sunrealtype dx = 0;    // the last CEodeCalcIC's move of x (max norm)
  sunrealtype dv = 0;    // and of v
};

}  // namespace ceode

// The solver memory. Named like SUNDIALS' CVodeMemRec so users reading a
// debugger recognise it.
struct CEodeMemRec {
  SUNContext sunctx = nullptr;

  // Problem
  CEodeRhsFn f = nullptr;
  void* user_data = nullptr;
  bool initialized = false;
  sunindextype n = 0;  // global length of x

  // Method
  int degree = 3;
  sunrealtype params[ceode::kMaxDegree] = {1.0, 0.5};
  std::string method_name = "G3_CD";
  bool zero_start = false;
  bool compensated = false;
  // The step module's record (ceode_step.hpp): the update options, plans and kernels, and the
  // step chosen at the start. Created with the first option or CEodeInit.
  std::unique_ptr<ceode::StepMem, ceode::StepMemFree> step;
  // The error-control module's record (ceode_adapt.hpp): created by the first tolerances call.
  std::unique_ptr<ceode::AdaptMem, ceode::AdaptMemFree> adapt;
  // The root-finding module's record (ceode_root.cpp): created by CEodeRootInit with nrtfn > 0,
  // null otherwise (the run then tests this pointer only).
  std::unique_ptr<ceode::CERootMem, ceode::RootMemFree> root;
  sunrealtype h = 0;  // 0 until CEodeSetFixedStep; with error control, the next step to take
  ceode::StepCoeffs co;

  // State: derivatives D_1..D_{d-1} at tcur, x at tcur and at tcur + h.
  sunrealtype tcur = 0;
  sunrealtype tretlast = 0;
  sunrealtype t_start_h = 0;  // time of the last (re)start; tcur = t_start_h + nsteps_h * h
  long int nsteps_h = 0;
  bool started = false;  // history built for the current method and h
  N_Vector xcur = nullptr;
  N_Vector xnext = nullptr;
  N_Vector xnew = nullptr;
  // Kahan compensation of the accumulated quantities (compensated summation):
  // index 0 is x(tcur + h), index k the derivative D_k; double-buffered like D.
  N_Vector comp[ceode::kMaxDegree] = {};
  N_Vector compnew[ceode::kMaxDegree] = {};
  N_Vector compwork[ceode::kCompWork] = {};  // the reference's error-free increments (kernels)
  N_Vector D[ceode::kMaxDegree] = {};
  N_Vector Dnew[ceode::kMaxDegree] = {};

  // Work vectors
  N_Vector ftmp = nullptr;
  N_Vector vtmp = nullptr;
  N_Vector atmp = nullptr;
  N_Vector tmp1 = nullptr;
  N_Vector tmp2 = nullptr;
  N_Vector tmp3 = nullptr;
  N_Vector V0 = nullptr;  // velocity offset of the implicit system
  N_Vector apred = nullptr;
  N_Vector ycor = nullptr;
  N_Vector ewt = nullptr;
  N_Vector zero = nullptr;

  // Options
  sunrealtype tstop = 0;
  bool tstop_set = false;
  long int mxstep = ceode::kDefaultMaxSteps;

  bool vel_dependent = false;  // the step solves for the acceleration (velocity dependence)
  N_Vector lstmp = nullptr;    // solution vector of linear solves
  sunrealtype xl1_start = 0;   // ||x||_1 at the last (re)start, reference for explosive growth

  // The modules' records
  ceode::LsMem ls;
  ceode::NlsMem nls;
  ceode::PcMem pc;
  ceode::GuardMem guard;
  ceode::ConstrMem con;
  ceode::IcMem ic;

  // Counters of the integrator itself
  long int nst = 0;
  long int nfe = 0;
  long int nfe_start = 0;

  // Error reporting
  CEodeErrHandlerFn ehfun = nullptr;
  void* eh_data = nullptr;
  FILE* errfp = nullptr;
  bool to_context = ceode::sun::kContextErrors;  // SUNDIALS 7: through the SUNContext
  std::string last_msg;

  // --- adapters (ceode_first_order.cpp, ceode_forcing.cpp, ceode_stepper.cpp) ---
  ceode::Adapters adapters;
};

namespace ceode {

// The single error path: formats the message, hands it to the handler, returns flag.
int ProcessError(CEodeMemRec* ce, int flag, const char* func, const char* fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;
// The restart rule: after a change of the method, the problem or a solver, the next CEodeEvolve
// rebuilds the solvers and the history at the current time.
void Restart(CEodeMemRec* ce);
// Access's report (ceode.cpp), out of line: CE_MEM_NULL or CE_NO_MALLOC.
__attribute__((noinline, cold)) int AccessFailed(CEodeMemRec* ce, const char* func);
// The access guard every exported function starts with: two tests, inline, so that each caller's
// compiler sees that a refusal's flag is never CE_SUCCESS; a caller that returns it makes the
// report its tail call and keeps no frame for it (CEodeEvolve's entry is then the two tests).
__attribute__((always_inline)) inline int Access(void* mem, const char* func, CEodeMemRec** ce,
                                                 bool need_init = false) {
  *ce = static_cast<CEodeMemRec*>(mem);
  if (*ce != nullptr && (!need_init || (*ce)->initialized)) return CE_SUCCESS;
  const int flag = AccessFailed(*ce, func);
  if (flag == CE_SUCCESS) __builtin_unreachable();
  return flag;
}
// The single exit of a successful CEodeEvolve: the step checks the positions' growth at no extra
// cost, so a velocity that overflowed with finite positions (a set whose velocity weights are
// extreme for this h) is caught here, once per call, and never returned with success. finite:
// whether xout and vout are finite, as the output (OutputState) found while writing them.
// ReportNotFinite: its report, out of line.
int ReportNotFinite(CEodeMemRec* ce, const char* func, N_Vector xout);
inline int CheckReturned(CEodeMemRec* ce, const char* func, bool finite, N_Vector xout, int flag) {
  if (flag < 0 || finite) return flag;
  return ReportNotFinite(ce, func, xout);
}

// ceode_adapt.cpp: whether the run chooses its steps from tolerances (error control). Inline on
// the record's pointer: a run that never set tolerances pays one test per call.
bool AdaptEnabled(const CEodeMemRec* ce);
inline bool AdaptOn(const CEodeMemRec* ce) { return ce->adapt != nullptr && AdaptEnabled(ce); }

// ceode_step.cpp
int TakeStep(CEodeMemRec* ce);
// Two times closer than this are the same point of the step grid: 1e-8 h, or the round-off of the
// grid's times (t_start_h + k h, a few units in the last place of t) where that is larger, as it is
// once h < 1e-7 |t|. Without the second term a target one rounding short of tcur + h leaves the
// step untaken and the output is interpolated over the whole step.
inline sunrealtype GridTolerance(const CEodeMemRec* ce, sunrealtype h) {
  const sunrealtype tr = 64 * SUN_UNIT_ROUNDOFF * std::fabs(ce->tcur);
  const sunrealtype th = SUN_RCONST(1e-8) * h;
  return tr > th ? tr : th;
}
inline bool OnGrid(const CEodeMemRec* ce, sunrealtype t) {
  return std::fabs(t - ce->tcur) <= GridTolerance(ce, ce->h);
}
// How far beyond tcur a target lies when a step remains before it: h less the grid's tolerance,
// and at least half a step, so that with h below the round-off of t (a tolerance above h) a
// target one step ahead takes one step, not as many as the tolerance spans.
inline sunrealtype StepReach(const CEodeMemRec* ce) {
  const sunrealtype reach = ce->h - GridTolerance(ce, ce->h);
  const sunrealtype half = SUN_RCONST(0.5) * ce->h;
  return reach > half ? reach : half;
}
// Whether the step interval [tcur, tcur + h] ends before target (CEodeEvolve steps while it does).
inline bool StepsRemain(const CEodeMemRec* ce, sunrealtype target) {
  return target - ce->tcur > StepReach(ce);
}
// Steps towards target, at most max_steps (>= 1) and at least one; *taken: how many succeeded.
int TakeSteps(CEodeMemRec* ce, sunrealtype target, long int max_steps, long int* taken);
// One step of the run's configuration (chosen by ChooseStep: the lean loop's explicit step
// without its dispatch, TakeStep on the others): its effect and flag (*flag). false: the run
// has not started, nothing done.
bool TakeDirectStep(CEodeMemRec* ce, int* flag);
// CEodeEvolve's CE_ONE_STEP call after the access guard. Where the run is on serial vectors
// within the span of times where the grid needs no test, with no option set that needs the
// general path, the first call opens a fast path for the steps up to the span's end, the stop
// time's margin or the guard's next check (closed by a restart and StepOptionsChanged); on it a
// call with serial outputs is the step (the lean configuration's inlined, the others' TakeStep)
// and x, x' at its end copied into xout, vout, tested as they are written; otherwise
// EvolveOneStepGeneral, and after a failed step or outputs that are not finite, OneStepRest.
// Hidden: CEodeEvolve reaches it by a jump, not through the library's symbol table.
__attribute__((visibility("hidden"))) int OneStepEvolve(CEodeMemRec* ce, sunrealtype tout,
                                                        N_Vector xout, N_Vector vout,
                                                        sunrealtype* tret);
// CEodeEvolve's other calls (CE_NORMAL, or an itask the general path refuses) after the access
// guard. A CE_NORMAL call a few steps ahead (no more than the lean loop's minimum) on the same
// direct path as OneStepEvolve's, with tout also in its span: the steps (TakeDirectStep's), then
// the outputs at tout (the method's values on the grid, else the dense output), tested as they are
// written; otherwise EvolveNormalGeneral, and after a failed step or outputs that are not finite,
// OneStepRest.
__attribute__((visibility("hidden"))) int NormalEvolve(CEodeMemRec* ce, sunrealtype tout,
                                                       N_Vector xout, N_Vector vout,
                                                       sunrealtype* tret, int itask);
// The step of the run, once: its solve (the implicit one as ceode_pc.cpp chose it), the update
// plans from the current vectors with their kernel, and the many-step loop. At the end of every
// start (restart: the vectors are in their first configuration) and after an update option
// changes (the run goes on from the current vectors).
void ChooseStep(CEodeMemRec* ce, bool restart);
// The step module's part of a restart (Restart): the direct paths close until the next start's
// ChooseStep, so that direct_tmax alone says whether the run is started.
void StepRestart(CEodeMemRec* ce);
// Closes the one-step fast span (StepMem::fast_until) until the next checked call:
// called by whatever sets an option the path depends on (the stop time, root functions, error
// control, the guard's mode, period or pending check).
void StepOptionsChanged(CEodeMemRec* ce);
// ceode_pc.cpp's choice of the implicit solve (kNewton, kPC or kAuto), read by ChooseStep.
void SetImplicitSolve(CEodeMemRec* ce, SolveKind kind);
// The solve the last start chose (ChooseStep), on a started run.
SolveKind ChosenSolve(const CEodeMemRec* ce);
// f's failure (its return value rv at t) reported as CE_RHSFUNC_FAIL.
int RhsFailed(CEodeMemRec* ce, int rv, sunrealtype t, const char* func);
int EvalAccel(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector v, N_Vector a,
              const char* func);  // a = M^{-1} f(t, x, v)
// The explicit solve: a = M^{-1} f(t, x, D_1(t - h)).
int SolveExplicit(CEodeMemRec* ce, sunrealtype t, sunrealtype tnext, N_Vector x, N_Vector a,
                  const char* func);

// ceode_step_plans.cpp: the step module's record and options
bool AllocStepRecord(CEodeMemRec* ce);                             // false: out of memory
int SetFusedKernel(CEodeMemRec* ce, bool on, const char* func);    // CEodeSetFusedKernel
int SetInPlaceUpdate(CEodeMemRec* ce, bool on, const char* func);  // CEodeSetInPlaceUpdate
bool FusedKernelOn(const CEodeMemRec* ce);
// The step's vectors are all NVECTOR_SERIAL and its update runs on their raw arrays (the serial
// backend of ceode_kernels.hpp), as set by the last ChooseStep.
bool SerialBackend(const CEodeMemRec* ce);

// ceode_method.cpp
sunrealtype Factorial(int n);
// w[i] = s^i / i!, i = 0 .. m-1 (pow(s, i) / i!).
void TaylorWeights(sunrealtype s, int m, sunrealtype* w);
// The same by products, w[i] = w[i-1] s / i: no pow call, other rounding.
void TaylorWeightsByProducts(sunrealtype s, int m, sunrealtype* w);
// The predicted acceleration at t: the Taylor polynomial of the history from t - h.
void PredictAccel(const CEodeMemRec* ce, N_Vector a);
// V0 of v(a) = V0 + kappa a: the part of the velocity at t the history fixes.
void VelocityOffset(int d, const StepCoeffs& co, N_Vector* D, N_Vector V0);
// The step's update after the solve, for the history D, the new derivatives Dn (the acceleration
// in Dn[2]), x(t + h) in xnext and x(t + 2h) into xnew: the integrator's plans and the
// stability analysis's step map are built by this one routine.
void BuildUpdatePlan(int d, const StepCoeffs& co, N_Vector* D, N_Vector* Dn, N_Vector xnext,
                     N_Vector xnew, UpdatePlan* plan);

// ceode_vectors.cpp
// A new vector like tmpl, for the memory's own use: N_VClone's, or for NVECTOR_SERIAL the same
// vector in one allocation (N_VDestroy frees it; its clones are made the same way).
N_Vector CloneVector(N_Vector tmpl);
// *v = CloneVector(tmpl) unless *v exists; false: out of memory.
bool CloneMissing(N_Vector* v, N_Vector tmpl);

// ceode_start.cpp
int StartMethod(CEodeMemRec* ce);  // consistent or zero start at tcur, then ChooseStep
// Higher derivatives D_3..D_{d-1} at t0 = tcur from x = xcur, D_1, D_2: central differences of
// the acceleration accel(t, x, v, a) along the Taylor curve of the derivatives already known
// (the symmetric stencil cancels the curve's own error); from kHighStartDegree on, Picard sweeps
// of central stencils to the order of the high-degree sets. xs, vs, as: scratch vectors.
constexpr int kHighStartDegree = 6;
int StartDerivatives(CEodeMemRec* ce, sunrealtype t0, N_Vector xs, N_Vector vs, N_Vector as,
                     const std::function<int(sunrealtype, N_Vector, N_Vector, N_Vector)>& accel);
int AllocVectors(CEodeMemRec* ce, N_Vector tmpl);
// The work vectors of the linear, nonlinear and constraint solvers and the mass solve, cloned
// when a (re)start first needs them (Prepare).
bool NeedsSolverWork(const CEodeMemRec* ce);
int AllocSolverWork(CEodeMemRec* ce, const char* func);
void FreeVectors(CEodeMemRec* ce);

// ceode_dense.cpp
void Interpolate(CEodeMemRec* ce, sunrealtype s, int k, N_Vector out);
// xout = x(tcur + s), vout = x'(tcur + s) as Interpolate gives them; returns whether both are
// finite (CEodeEvolve's outputs, tested where they are written).
bool OutputState(CEodeMemRec* ce, sunrealtype s, N_Vector xout, N_Vector vout);

// ceode_root.cpp (called only while ce->root is set, except the two resets)
// Checks the roots of g over [tlo, tend], tend inside the dense output's interval: CE_SUCCESS
// (none; checked up to tend), CE_ROOT_RETURN (at RootTime, checked up to there) or the failure
// flag of g, reported.
int RootCheck(CEodeMemRec* ce, sunrealtype tend, const char* func);
sunrealtype RootTime(const CEodeMemRec* ce);
long int RootNumGEvals(const CEodeMemRec* ce);  // 0 without root functions
// A new state (init, restart): g is evaluated afresh at the next check; with counters, the
// count of g evaluations is zeroed (CEodeReInit).
void RootRestart(CEodeMemRec* ce, bool counters);
void RootFreeVectors(CEodeMemRec* ce);  // the problem's size changes (a second CEodeInit)

// ceode_ls.cpp
int MassUpdate(CEodeMemRec* ce, sunrealtype t, N_Vector x, const char* func);
int MassSolve(CEodeMemRec* ce, N_Vector b, const char* func);  // b <- M^{-1} b
// Forms and factors M - kappa df/dv; reports a failure and returns its flag.
int NewtonSetup(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector v, N_Vector fv,
                sunrealtype kappa, const char* func);
// The serial direct Newton iteration factors the Newton matrix with its own pivots when the
// attached solver is SUNLinSol_Dense on a dense A of at most 64 unknowns (returns whether it
// does); then x <- A^{-1} x on the raw array of x.
bool LsUseOwnLu(CEodeMemRec* ce, bool use);
void LsSolveOwnLu(CEodeMemRec* ce, sunrealtype* x);
// Forgets what A holds; with counters, zeroes the module's counters too (CEodeReInit).
void LsReset(CEodeMemRec* ce, bool counters);
// Whether the factored Newton matrix must be formed again for this kappa.
bool NewtonMatrixStale(const CEodeMemRec* ce, sunrealtype kappa);
int NewtonSolve(CEodeMemRec* ce, N_Vector b, const char* func);
// df/dv at (t, x, v) with f(t, x, v) = fv into J: the user's CEodeVelJacFn, or difference
// quotients (dense or band J, local data). Counted in nje; failures reported.
int VelJacobian(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector v, N_Vector fv, SUNMatrix J,
                const char* func);
int LsInitialize(CEodeMemRec* ce, const char* func);
// Whether M is not the identity (a mass function or a constant M attached; set before a start).
inline bool HasMassMatrix(const CEodeMemRec* ce) {
  return ce->ls.mfn != nullptr || ce->ls.M != nullptr;
}
int InitLinearSolver(CEodeMemRec* ce, SUNLinearSolver LS, const char* func);  // reports failure
void LsFree(CEodeMemRec* ce);

// ceode_nls.cpp
int NlsInitialize(CEodeMemRec* ce, const char* func);
int SolveImplicit(CEodeMemRec* ce, sunrealtype t, sunrealtype tnext, N_Vector x, N_Vector a,
                  const char* func);
void NlsFree(CEodeMemRec* ce);
void NlsReset(CEodeMemRec* ce, bool counters);  // with counters: zeroes them (CEodeReInit)
// The velocity and f(t, x, v) of the last residual evaluation of the solve (its vtmp, ftmp).
void NlsLastResidual(const CEodeMemRec* ce, N_Vector* v, N_Vector* fv);
// Pieces of the iteration its serial backend shares: f inside the solve (counted, failures
// recorded), the Newton matrix setup and solve as the SUNNonlinearSolver calls them, the test.
int NlsRhs(CEodeMemRec* ce);
int NlsLinearSetup(sunbooleantype jbad, sunbooleantype* jcur, void* mem);
int NlsLinearSolve(N_Vector b, void* mem);
int NlsConvTest(CEodeMemRec* ce, int m, sunrealtype delnrm, sunrealtype tol);

// ceode_nls_direct.cpp: the iteration on raw arrays (serial vectors, a direct linear solver,
// n small), chosen by NlsInitialize: offset, predictor and weights; one Newton solve from a zero
// correction; the corrected acceleration.
bool DirectNewtonApplies(const CEodeMemRec* ce);
void DirectArrays(CEodeMemRec* ce);  // the arrays, once the work vectors exist
void DirectPrepare(CEodeMemRec* ce);
int DirectSolve(CEodeMemRec* ce, bool setup);
void DirectAccel(CEodeMemRec* ce, N_Vector a);

// ceode_pc.cpp: after the unconstrained start, the velocity-dependence check and the choice of
// the implicit solve (prediction-correction or the nonlinear solver); the PC solve itself.
int ChooseImplicitSolve(CEodeMemRec* ce, const char* func);
int SolvePC(CEodeMemRec* ce, sunrealtype t, sunrealtype tnext, N_Vector x, N_Vector a,
            const char* func);
void PcReset(CEodeMemRec* ce, bool counters);  // its estimates; with counters, those too
void PcFree(CEodeMemRec* ce);
void PcMethodChanged(CEodeMemRec* ce);  // the default number of corrections of the new set
void PcSetVelocityRequest(CEodeMemRec* ce, int request);  // CEodeSetVelocityDependence
// Before the solvers are set up (Prepare): the start's probe of f in x' when no dependence was
// declared; a detected one sets vel_dependent, as a declaration does.
int DetectVelocityDependence(CEodeMemRec* ce);
// Whether f is known not to read its velocity argument: the start's probe ran on this f and
// found no dependence (a declared independence may want the lagged velocity).
bool VelocityUnread(const CEodeMemRec* ce);
// How the dependence was decided, for the statistics: declared, none (declared), detected, none.
const char* VelocityDependenceName(const CEodeMemRec* ce);
const char* AccelSolveName(const CEodeMemRec* ce);  // PrintAllStats: the solve the start chose
int SolveAuto(CEodeMemRec* ce, sunrealtype t, sunrealtype tnext, N_Vector x, N_Vector a,
              const char* func);  // CE_IMPLICIT_AUTO: PC or the nonlinear solver, refreshed
// With CEodeSetVelJacDiagonal: a = f(t, x, V0) / (1 - kappa c), exact for f affine in x'.
int SolveDiagonal(CEodeMemRec* ce, sunrealtype t, sunrealtype tnext, N_Vector x, N_Vector a,
                  const char* func);

// ceode_constraints.cpp
bool HasConstraints(const CEodeMemRec* ce);
int ConstrInitialize(CEodeMemRec* ce, const char* func);
int ConstrStart(CEodeMemRec* ce, const char* func);  // a0, lambda0 at t0, constrained x(t0+h)
int ConstrSolveStep(CEodeMemRec* ce, sunrealtype t, sunrealtype tnext, N_Vector x, N_Vector a,
                    const char* func);
void ConstrFree(CEodeMemRec* ce);
void ConstrReset(CEodeMemRec* ce);  // zeroes its counters (CEodeReInit)
// Error control: x(t + h_next; a) = xoff[0] x(t) + sum_j xoff[j] D_j + mu a for the step's own
// pair of steps (kMaxDegree weights), until the next start.
void ConstrSetStepPosition(CEodeMemRec* ce, const sunrealtype* xoff, sunrealtype mu);

// ceode_ic.cpp: the consistency check of x0, v0 at the first start after CEodeInit/CEodeReInit
// (requested by them), CE_INCONSISTENT_IC with the constraint that is off.
void IcRequestCheck(CEodeMemRec* ce);
int IcCheck(CEodeMemRec* ce, const char* func);

// ceode_guard.cpp: the runtime check, without side effects on the integration
int GuardCheck(CEodeMemRec* ce, const char* func);
void GuardFree(CEodeMemRec* ce);  // its workspace (at CEodeInit and CEodeFree)
// Its copy of M is re-evaluated; with counters (CEodeReInit), its warning may be given again and
// its counters are zeroed (a Reset keeps both: one warning per run, not per restart).
void GuardReset(CEodeMemRec* ce, bool counters);
void GuardMethodChanged(CEodeMemRec* ce);  // Omega_max is looked up again
void GuardRequestCheck(CEodeMemRec* ce);   // at the next CEodeEvolve (a start)
void GuardStartAccel(CEodeMemRec* ce);     // the start left f(tcur, xcur, D_1) in D_2: f0 for free
int GuardCheckPending(CEodeMemRec* ce, const char* func);  // the requested check, once
// safety * Omega_max / omega_max from the last estimate; SUN_BIG_REAL when none is known.
sunrealtype GuardStableStep(CEodeMemRec* ce, sunrealtype safety);
// Whether the guard is on, so that GuardStableStep can know a step: callers on a step's path test
// it before the call.
inline bool GuardOn(const CEodeMemRec* ce) { return ce->guard.mode != CE_GUARD_OFF; }
// The inputs GuardStableStep's value follows besides the safety: the estimate and the method's
// limit (0 until it is first needed). A caller keeps the value while both stay.
inline bool GuardStableStepInputsAre(const CEodeMemRec* ce, sunrealtype omega, sunrealtype limit) {
  return ce->guard.omega_est == omega && ce->guard.omega_limit == limit;
}

// ceode_stability.cpp
int MethodStabilityLimit(int degree, const sunrealtype* params, sunrealtype* Omega_max);

// ceode_validate.cpp: one validation point per attached object, called by its setter and again
// at the first CEodeEvolve after a configuration change (the problem size may have changed).
int ValidateMethodParams(int degree, const sunrealtype* params, char* why, size_t len);  // pure
// The k of P(EC)^k that keeps the set's order when the user did not choose (ceode_pc.cpp).
int DefaultPCCorrections(int degree, const sunrealtype* params);
// Orders in x and x' of a set from its order conditions (ceode_order.cpp; may throw bad_alloc).
int MethodOrders(int d, const sunrealtype* p, int* order_x, int* order_v, long double* const_x,
                 long double* const_v);
int ValidateNonlinTolerances(CEodeMemRec* ce, const char* func, sunrealtype reltol,
                             sunrealtype abstol);
int ValidateStep(CEodeMemRec* ce, const char* func);  // h against t and the method
// A time argument (t0, tout, tstop): finite, or CE_ILL_INPUT naming the argument.
int ValidateTime(CEodeMemRec* ce, const char* func, const char* name, sunrealtype t);
int ValidateMassMatrix(CEodeMemRec* ce, const char* func, SUNMatrix M);
int ValidateLinearSolver(CEodeMemRec* ce, const char* func, SUNLinearSolver LS, SUNMatrix A,
                         bool at_start);
int ValidateMassAgainstSolver(CEodeMemRec* ce, const char* func);  // M and A: same type, size
int ValidateNonlinearSolver(CEodeMemRec* ce, const char* func, SUNNonlinearSolver NLS);
int ValidateConstraintTemplate(CEodeMemRec* ce, const char* func);  // one Phi call
int ValidateConfiguration(CEodeMemRec* ce, const char* func);  // all of the above, at the start
int ValidateStart(CEodeMemRec* ce, const char* func);          // the start's history is finite
sunrealtype MaxNormOrNaN(N_Vector v);  // N_VMaxNorm skips NaN; this returns NaN for them

// ceode_long_run.cpp: the long-run energy behaviour of each named set, measured by the long-run
// study (data in docs/data/long_run_*.csv, docs/stability.md), and the advice that follows from
// it; pure, for the stability guard.
// kLongRunRoundOff: no drift resolved above round-off over 10^7 steps (the fitted rate is noise).
enum LongRunKind { kLongRunBounded, kLongRunLinearDrift, kLongRunGrowing, kLongRunRoundOff };
struct LongRunBehaviour {
  const char* name;
  LongRunKind kind;        // bounded; linear drift; growing (rho > 1 for every h)
  sunrealtype drift_rate;  // |dE/dt| measured on the pendulum at h = 1e-3 (0: bounded)
  int drift_order;         // the drift rate scales as h^drift_order (0: growing, no fit)
  sunrealtype omega_max;   // stability limit Omega_max (0: weakly unstable for every h)
};
const LongRunBehaviour* FindLongRunBehaviour(const char* name);  // nullptr: not a named set
// One clause of advice for a long run of `current` at Omega = h * omega_max, written into buf
// (empty when `current` is already the right choice); returns buf.
const char* LongRunAdvice(const char* current, sunrealtype Omega, char* buf, size_t len);

// --- adapters ---
// ceode_first_order.cpp: F's acceleration (data: the memory); the adapter's record, dropped by a
// native CEodeInit and by CEodeFree.
int FirstOrderRhs(sunrealtype t, N_Vector x, N_Vector v, N_Vector a, void* mem);
void FirstOrderFree(CEodeMemRec* ce);
// The right-hand side as CEODE evaluates it: the user's f, or the adapters' in its place.
__attribute__((always_inline)) inline int CallRhs(CEodeMemRec* ce, sunrealtype t, N_Vector x,
                                                  N_Vector v, N_Vector f) {
  return ce->adapters.rhs(t, x, v, f, ce->adapters.rhs_data);
}
// f(t, x, v), counted, failures reported (inline: the implicit steps call it once or twice a
// step, at n of a few as costly as the step's arithmetic).
inline int EvalRhs(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector v, N_Vector f,
                   const char* func) {
  const int rv = CallRhs(ce, t, x, v, f);
  ++ce->nfe;
  return rv == 0 ? CE_SUCCESS : RhsFailed(ce, rv, t, func);
}
// The same without the forcing: the user's f, or F of the first-order form.
int BaseRhs(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector v, N_Vector f);
// The identity of the problem's right-hand side (f, or the first-order adapter's), forced or not.
inline CEodeRhsFn RhsIdentity(const CEodeMemRec* ce) {
  return ce->f != nullptr ? ce->f : FirstOrderRhs;
}
// Sets adapters.rhs and rhs_data from f, user_data and the attached adapters (ceode_forcing.cpp).
void SelectRhs(CEodeMemRec* ce);
// x and v of a first-order vector y = [x; v] with halves of length n: a ManyVector's two parts,
// or windows on a serial y's array through view[0], view[1] (empty serial vectors, made when
// first needed). False: out of memory.
bool SplitHalves(N_Vector y, sunindextype n, SUNContext ctx, N_Vector* view, N_Vector* x,
                 N_Vector* v);
// The same for a y of the memory's own vectors (the inner stepper's state, forcing and output):
// halves of CEODE's length and vector type, else an error reported as from func.
int SplitFirstOrder(CEodeMemRec* ce, N_Vector y, N_Vector* view, N_Vector* x, N_Vector* v,
                    const char* func);

// ceode.cpp: a new problem (f, or nullptr for the first-order form) at t0; CEodeInit without the
// adapter bookkeeping.
int InitProblem(CEodeMemRec* ce, const char* func, CEodeRhsFn f, sunrealtype t0, N_Vector x0,
                N_Vector v0);
// A restart at (t0, x0, v0) that keeps the counters and the guard's warning state (CEodeReInit
// zeroes them): for an adapter that integrates in pieces.
struct ResetOptions {
  // Fills D_2..D_{d-1} at t0 for the degree of the last start; the next start then evaluates
  // nothing. Empty: the start computes them.
  std::function<int()> history;
  // The guard's estimate of the last run, if there is one and no frequency is set, becomes the
  // set frequency: later starts check h against it without estimating it again.
  bool keep_frequency = false;
};
int Reset(CEodeMemRec* ce, const char* func, sunrealtype t0, N_Vector x0, N_Vector v0,
          const ResetOptions& opt);

// CEodeEvolve with error control: straight to its steps where the general path would only check
// the arguments (serial outputs of the problem's length, tret, a finite tout, a known itask) and
// find the run started with no guard check pending; the general path otherwise, which reports what
// it refuses.
int AdaptCall(CEodeMemRec* ce, sunrealtype tout, N_Vector xout, N_Vector vout, sunrealtype* tret,
              int itask);
// CEodeEvolve's CE_ONE_STEP call on the general path (the checks, the start, the step through
// TakeSteps or TakeDirectStep, the outputs): where OneStepEvolve has no direct form.
int EvolveOneStepGeneral(CEodeMemRec* ce, sunrealtype tout, N_Vector xout, N_Vector vout,
                         sunrealtype* tret);
// CEodeEvolve's call that NormalEvolve does not take directly (ceode.cpp).
int EvolveNormalGeneral(CEodeMemRec* ce, sunrealtype tout, N_Vector xout, N_Vector vout,
                        sunrealtype* tret, int itask);
// The end of a fixed-step call after the direct paths' steps towards target (OneStepEvolve,
// NormalEvolve), flag their result: a failed step's last good state, or the steps left and the
// outputs at target (ReturnAtTarget).
int OneStepRest(CEodeMemRec* ce, int flag, sunrealtype target, N_Vector xout, N_Vector vout,
                sunrealtype* tret);

// Name of a flag, static storage (CEodeGetReturnFlagName returns a malloc'd copy).
const char* FlagName(long int flag);

// Finiteness test that works on every N_Vector (NaN propagates through the L1 norm).
bool IsFinite(N_Vector v);

}  // namespace ceode

#endif  // CEODE_SRC_CEODE_IMPL_HPP_
