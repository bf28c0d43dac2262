// The error-control module's record (CEodeMemRec::adapt), written only by ceode_adapt.cpp (the
// options, the method's error and remap coefficients, the controller), ceode_adapt_step.cpp (the
// adaptive step) and ceode_adapt_refresh.cpp (the history refresh); the others read it
// (docs/theory.md section 12).
#ifndef CEODE_SRC_CEODE_ADAPT_HPP_
#define CEODE_SRC_CEODE_ADAPT_HPP_

#include "ceode_kernels.hpp"
#include "ceode_testing.h"

namespace ceode {

// One term of the history's remap when the step changes from h to h' (docs/theory.md
// section 12.2): D_k += gamma (h'^j - h^j) Y, Y = D_{k+j} (k + j < d) or the top derivative's
// rate yd (k + j = d).
struct RemapTerm {
  int k;
  int j;
  sunrealtype gamma;
};

// Terms of the consistent history's series D_k = sum_l gamma_kl h^l y^(k+l) that the refresh uses.
constexpr int kGammaTerms = kMaxDegree + 1;

// What error control derives from a set's parameters alone: the order p, C_{p+1}, the remap and
// the consistent history's series coefficients gamma[k][l], k < d, l < kGammaTerms.
struct SetCoefficients {
  int order = 0;
  sunrealtype cerr = 0;
  int nremap = 0;
  RemapTerm remap[kMaxDegree * kMaxDegree] = {};
  sunrealtype gamma[kMaxDegree][kGammaTerms] = {};
};

struct AdaptMem {
  // Options
  bool on = false;   // tolerances given and no fixed step set after them
  int tol_kind = 0;  // 0 scalar, 1 vector abstol, 2 user weights
  sunrealtype rtol = 0;
  sunrealtype atol = 0;
  N_Vector atol_vec = nullptr;  // CEodeSVtolerances' copy
  sunrealtype atol_min = 0;     // its smallest entry
  CEodeEwtFn efun = nullptr;
  sunrealtype hin = 0;  // 0: chosen by the start
  sunrealtype hmin = 0;
  sunrealtype hmax = 0;  // 0: no limit
  int maxnef = 7;
  int controller = CE_ADAPT_PI;
  void* sun_controller = nullptr;          // SUNDIALS 7: the user's SUNAdaptController (not owned)
  CEodeStepScheduleFn schedule = nullptr;  // CEodeSetStepSchedule (tests)
  void* schedule_data = nullptr;
  sunrealtype tout_hint = 0;  // the first CEodeEvolve's tout: bounds the first step

  // The method's coefficients (with the method, at each start): p, C_{p+1} (the local error
  // C h^{p+1} y^{(p+1)}), the remap and the series; set_degree and set_params the set they
  // belong to (set_degree 0: none yet).
  SetCoefficients set;
  int set_degree = 0;
  sunrealtype set_params[kMaxDegree] = {};
  sunrealtype pfac = 0;  // (p - 1)!: y^{(p+1)} = (p - 1)! a[t_n, ..., t_{n-p+1}]
  // 1 / tol^(1/p): the local error is held to tol^((p+1)/p) in the weights, so that the global
  // error is proportional to tol (docs/theory.md section 12.3).
  sunrealtype err_scale = 1;
  // The history is refreshed instead of remapped when the step changes (degree 6 and more, no
  // constraints: the constrained solve's position weights follow the remap, 12.6).
  bool refresh = false;
  // The refresh's rows as polynomials in h (RefreshTables, with the coefficients): row r
  // (D_3 .. D_{d-1}, then yd) weighs the interpolant's power coefficient i by
  // refresh_k[i][r] h^(i - 1 - r) (zero for i <= r); by coefficient, so that one pass serves all
  // rows.
  static constexpr int kRefreshRows = kMaxDegree - 2;
  int refresh_rows = 0;
  sunrealtype refresh_k[kMaxDegree][kRefreshRows] = {};

  // The run
  AdaptKernels kernels;         // the backend of its vector work, chosen at the start
  N_Vector ewt = nullptr;       // the node's weights: the test of the step from it
  N_Vector ewt_next = nullptr;  // those of the step's end, formed with its estimate
  N_Vector ewt_spec = nullptr;  // those of the next position formed with the estimate (spec_*)
  N_Vector xspec = nullptr;     // that position (serial passes only, as ewt_spec)
  N_Vector ele = nullptr;       // the last accepted step's local error estimate
  N_Vector est = nullptr;       // the estimate of the step under test
  N_Vector yd = nullptr;        // (z_n - z_{n-1}) / h_{n-1}: the top derivative's rate at the node
  N_Vector yd_next = nullptr;   // the same at the step's end
  N_Vector dd[2][kMaxDegree] = {};  // divided differences a[t_n .. t_{n-j}], j = 1 .. p - 2
  int cur = 0;                      // dd[cur] belongs to the node
  sunrealtype* dd_data[2][kMaxDegree] = {};  // their data on the serial pass (ClearRun)
  sunrealtype tnode[kMaxDegree + 1] = {};    // t_n, t_{n-1}, ... (with the start's multiplicity)
  int ndata = 0;          // accelerations and start derivatives behind the divided differences
  sunrealtype hprev = 0;  // t_n - t_{n-1} (0 at the start)
  sunrealtype hmap = 0;   // the step the node's history is remapped for
  sunrealtype hlast = 0;  // the last accepted step
  sunrealtype h0 = 0;     // the first step of the run
  sunrealtype err = 0;    // the last accepted step's error norm (0: none estimated)
  sunrealtype err_prev = 0;
  sunrealtype lerr_prev = 0;   // log(err_prev / the controller's target), when lerr_prev_exact
  sunrealtype eta_prev = 1;    // the last accepted ratio (the filter's memory)
  sunrealtype eta_grow = 2;    // the largest growth of a step the remap's coupling admits
  sunrealtype hold_lb = 0;     // CEodeSetFixedStepBounds: a ratio in [hold_lb, hold_ub] keeps h
  sunrealtype hold_ub = 0;     // (0: the default for the set's degree)
  sunrealtype hold_lo = 0.97;  // the band's bottom and top for the run (ceode_adapt.cpp,
  sunrealtype hold_hi = 1.5;   // HoldBand)
  sunrealtype xhold[4] = {};   // the band's exponents for the PI controller and for H211b
  sunrealtype xkeep[4] = {};   // the same less the fast path's margin (BandKeepsStep)
  bool first = true;           // no step has passed an error test since the start
  bool capped_last = false;    // the stable step decided the last step
  // AdaptStableStep's value and the guard's inputs it came from (GuardStableStepInputsAre): the
  // estimate changes only at the guard's checks, so most steps take the value without the call.
  bool hs_kept = false;
  sunrealtype hs_value = 0;
  sunrealtype hs_omega = 0;
  sunrealtype hs_limit = 0;
  long int nst_refresh = 0;  // nst at the last estimate of the frequency behind the cap
  sunrealtype h_restart = 0;
  bool fail_restart = false;  // the start again comes after failed error tests
  // A step that keeps h takes no log (ceode_adapt.cpp, BandKeepsStep): whether lerr_prev is
  // set, and log(err_prev / the target) within 1e-4 (ApproxLog).
  bool lerr_prev_exact = false;
  sunrealtype lerr_prev_approx = 0;
  // With constraints the solve at a node imposes the constraint one step ahead, so the step
  // after the next one is planned at each acceptance (docs/theory.md 12.6).
  sunrealtype h_plan = 0;  // the first step failed its test: the next start's step
  int start_fails = 0;     // failed first steps of this CEodeEvolve

  // What a step keeps while h stays: the derivative update's plans of the two history
  // configurations (keyed by D_1's buffer).
  KernelPlan plans[2];
  sunrealtype plan_h[2] = {};
  N_Vector plan_key[2] = {};
  int plan_last = 1;  // the slot the last step ran
  // The serial pass's data of D and Dnew (AdaptAfterF::hist_data) for the two configurations of
  // the buffers, keyed by D_1's buffer as the plans.
  sunrealtype* hist_data[2][2][kMaxDegree] = {};
  N_Vector hist_key[2] = {};

  // The fused passes' descriptions (ceode_adapt_step.cpp), kept so that a step fills only what
  // changed: the derivatives' weights for cw_h, the estimate's scale for est_h, the position's
  // weights for (pos_h, pos_hprev, pos_hmap).
  AdaptAfterF after;
  AdaptPosition pos;
  sunrealtype shape_h = 0;   // the step after's shape belongs to (AfterFShape; 0: none yet)
  bool after_fused = false;  // that shape runs in one serial pass (AfterFIsFused)
  bool spec_pass = false;    // and forms the next position there (AdaptAfterF 7.)
  sunrealtype cw_h = 0;      // the step after.cw belongs to
  sunrealtype est_h = 0;
  sunrealtype est_scale = 0;
  sunrealtype pos_h = 0;
  sunrealtype pos_hprev = -1;
  sunrealtype pos_hmap = 0;
  sunrealtype dmin_next = 1;              // the smallest denominator of ewt_next's weights
  bool ewt_next_ready = false;            // ewt_next holds the weights of xnext (formed with it)
  int wkind = AdaptAfterF::kWeightsNone;  // the weights the tolerances give (AdaptAfterF)
  // The next position at an unchanged step, formed with the step's pass (AdaptAfterF 7.): its
  // terms for the step spec_h (in after.spec_c), whether the last pass formed it (in xspec and
  // ewt_spec) and its L1 norm.
  sunrealtype spec_h = 0;
  int spec_m = 0;
  bool spec_ready = false;
  sunrealtype spec_l1 = 0;

  // Counters
  long int netf = 0;
  long int ncapped = 0;
};

// Whether the last step's error was estimated (then its norm may be exactly 0: a solution the
// method integrates exactly); false while the history is too short for an estimate.
// The remap terms' weights gamma (h^j - hmap^j), the powers by repeated multiplication (IntPow's
// values), into rc[0 .. nremap - 1].
inline void RemapWeights(const AdaptMem& am, int d, sunrealtype h, sunrealtype* rc) {
  sunrealtype hp[kMaxDegree + 1];
  sunrealtype mp[kMaxDegree + 1];
  hp[0] = mp[0] = 1;
  for (int j = 1; j <= d; ++j) {
    hp[j] = hp[j - 1] * h;
    mp[j] = mp[j - 1] * am.hmap;
  }
  for (int i = 0; i < am.set.nremap; ++i) {
    rc[i] = am.set.remap[i].gamma * (hp[am.set.remap[i].j] - mp[am.set.remap[i].j]);
  }
}

inline bool AdaptEstimated(const AdaptMem& am) {
  return am.after.est_kind != AdaptAfterF::kEstNone;
}

// ceode_adapt.cpp
// At the start: the method's coefficients, the vectors, and the first step (the user's or
// one from the initial data, which costs one f); clears the run's state. *accel: D_2 holds
// M^{-1} f(t0, x0, v0) from that f, which the start then does not evaluate again.
int AdaptStart(CEodeMemRec* ce, const char* func, bool* accel);
// With constraints: CE_ERR_FAILURE when the step h leaves the velocity (a difference quotient of
// solved positions) with round-off far above its tolerance scale.
int AdaptCheckVelocityRoundOff(CEodeMemRec* ce, sunrealtype h, const char* func);
// After the start's history exists: the divided differences at t0 from the start's derivatives.
void AdaptStartHistory(CEodeMemRec* ce);
// The error weights from x (the tolerances or the user's function).
int AdaptWeights(CEodeMemRec* ce, N_Vector x, const char* func);
// CE_SUCCESS when dmin, the smallest denominator of weights from the tolerances, is positive;
// otherwise the error that names the cause.
int AdaptWeightsDefined(CEodeMemRec* ce, sunrealtype dmin, const char* func);
// The step after hbase (starting at tfrom) from the error norm err of the last accepted step
// (AdaptEstimated says whether it has one; an estimate of exactly 0 grows the step by the largest
// ratio): the controller's ratio applied to hbase, then hmax, the stable step and the stop time
// limit_t.
sunrealtype AdaptNextStep(CEodeMemRec* ce, sunrealtype err, sunrealtype hbase, sunrealtype tfrom,
                          sunrealtype limit_t, bool* capped);
// AdaptNextStep's verdict where the node has an estimate, no schedule decides and hbase lies
// within the bounds of h: true when the controller keeps hbase (the record then follows the step,
// as AdaptNextStep's); false leaves the record as it was.
bool AdaptKeepsStep(CEodeMemRec* ce, sunrealtype err);
// The step to retry with after a failed error test.
sunrealtype AdaptRetryStep(const CEodeMemRec* ce, sunrealtype err);
// The largest step the guard's estimate admits (SUN_BIG_REAL: none known).
sunrealtype AdaptStableStep(CEodeMemRec* ce);
void AdaptFree(CEodeMemRec* ce);                         // its vectors (the problem's size changes)
void AdaptSetTarget(CEodeMemRec* ce, sunrealtype tout);  // CEodeEvolve's tout
// CEodeReset: the next start begins with the controller's next step (no effect before a step).
void AdaptKeepStep(CEodeMemRec* ce);
void AdaptDisable(CEodeMemRec* ce);  // CEodeSetFixedStep
void AdaptReset(CEodeMemRec* ce, bool counters);
// Those of an arbitrary set, computed (series in long double: some 40 000 instructions at degree
// 7).
void ComputeSetCoefficients(int d, const sunrealtype* params, SetCoefficients* sc);

// ceode_adapt_refresh.cpp
// The node's history for a next step of h, rebuilt from the interpolant of the last p
// accelerations (docs/theory.md 12.5); false (nothing changed) while fewer are known or the
// refresh is off, when the remap applies instead.
bool RefreshHistory(CEodeMemRec* ce, AdaptMem* am, sunrealtype h);
// The refresh's rows from gamma and the order, once per method (none when the refresh is off).
void RefreshTables(AdaptMem* am, int d);

// AdaptOn where the record's type is known, without the call: CEodeEvolve's entry then needs no
// frame of its own.
inline bool AdaptOnInline(const CEodeMemRec* ce) { return ce->adapt != nullptr && ce->adapt->on; }

// ceode_adapt_step.cpp: CEodeEvolve with error control: steps until the last accepted one
// covers tout (CE_NORMAL; the output by its dense output) or one step (CE_ONE_STEP), never past
// the stop time; a success with outputs that are not finite is reported (CheckReturned).
int AdaptEvolve(CEodeMemRec* ce, const char* func, sunrealtype tout, N_Vector xout, N_Vector vout,
                sunrealtype* tret, int itask);

}  // namespace ceode

#endif  // CEODE_SRC_CEODE_ADAPT_HPP_
