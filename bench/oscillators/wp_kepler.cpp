// -----------------------------------------------------------------------------
// wp_kepler: work-precision scene for SUNDIALS' Kepler problem (the ark_kepler example's
// orbit): CEODE's error control against the adaptive integrators users pick, every solver
// timed side by side in one run on the harness of wp_common.h.
//
// Problem: q'' = -q / |q|^3 in the plane, eccentricity e = 0.6, from the pericentre
// q = (1 - e, 0), q' = (0, sqrt((1 + e) / (1 - e))) (period 2 pi), 10 orbits: t_f = 20 pi.
// After whole orbits the exact state is the start, so error = |q(t_f) - q(0)|_2 and
// drift = |H(t_f) - H(0)|, H = |q'|^2 / 2 - 1 / |q|; both are taken at t_f only.
//
// Curves (rtol = atol = tol over 1e-4 ... 1e-14: the tolerances below 1e-12 are where the
// 8th-order curves reach the summary's 1e-10; fixed steps h = t_f / N):
//  * CEODE adaptive: CEodeSStolerances(tol, tol) for G4_A34, G5_O4, G6_O5, G7_O7, G8_O8, one
//    CEodeEvolve in CE_NORMAL to the stop time t_f, the rest at CEODE's defaults. f evaluations
//    are counted in f itself (the start's and the stability guard's included). A run that
//    returns a failure flag is a failure row with the flag's name, not a point of the curve,
//    and not a failure of the scene: it is one of the results. G8_O8 also with the narrow band
//    CEodeSetFixedStepBounds(0.99, 1.01) (G8_O8_adaptive_band0.99-1.01: h changes on most
//    steps, fewer f at equal error over ten orbits, more instructions a step, theory.md 12.3).
//  * CEODE fixed step (wp::CeodeRun, guard off, one CE_NORMAL call to t_f: Problem::end_only):
//    G5_O4, G6_O5, G7_O7, G8_O8 (--quick: G6_O5, G8_O8), for adaptive against fixed at equal f.
//    ARKODE's default table and CVODE Adams run in their normal mode to t_f as well.
//  * The same G8_O8 steps written out by hand (wp::HandG8Run, solver CEODE-hand): the method's
//    floor, with the errors of CEODE's fixed-step curve (checked).
//  * ARKODE ERKStep adaptive with the default table (order 4) and CVODE Adams (fixed-point
//    iteration) through wp::SundialsRun; ERKStep with Verner 8-5-6 (order 6) and Fehlberg 13-7-8
//    (order 8; SUNDIALS 6.4 has no Verner 16-8-9) through ErkTableRun, the same one-step loop
//    with ERKStepSetTable, on copies that keep SUNDIALS 6.4 from reusing the last stage
//    (ErkTable).
//  * The peers (bench/peers.h): GSL rk8pd (the DOP853-class reference of the ratios), odeint
//    runge_kutta_fehlberg78, runge_kutta_dopri5 (controlled) and bulirsch_stoer.
//  * DPRKN6 (dprkn6.h), the Dormand-Prince Runge-Kutta-Nystrom 6(4) pair, adaptive (5 f per
//    step, the Nystrom form that uses f's independence of q').
//
// Checks (exit code 1 when one fails; never on a timing): DPRKN6's local error falls like h^7
// and its error estimate like h^5 from the pericentre, its global error at fixed steps from the
// pericentre to the apocentre like h^6; the two ERKStep tables satisfy their order conditions
// and their copies evaluate f at every stage; every SUNDIALS, peer and DPRKN6 run succeeds and
// every peer converges at its order (peers::CheckPeerOrders).
// Summary: at final-position errors 1e-6, 1e-8, 1e-10, every curve's f evaluations and CPU
// seconds (wp::TimeAtError's rule, the same rule for both), the best CEODE adaptive curve's
// ratio to GSL rk8pd and its time ratio to every other curve, adaptive against fixed steps of
// the same set, and every curve's time per run fitted as a cost per run plus a cost per step.
//
// Usage: wp_kepler [--csv FILE] [--quick]
// --quick: tolerances 1e-7, 1e-9, 1e-11, the sets G6_O5 and G8_O8, two fixed steps (the ctest).
// -----------------------------------------------------------------------------
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "dprkn6.h"
#include "kepler_model.h"
#include "wp_common.h"
#ifdef CEODE_BENCH_PEERS
#include "peers.h"
#endif

namespace {

using kepler::Acc;
using kepler::Energy;
using kepler::Exact;
using kepler::kEcc;
using kepler::Kepler;
constexpr int kOrbits = 10;
const double kTend = 2 * M_PI * kOrbits;

long& Evals(const wp::Problem& p) { return static_cast<Kepler*>(p.user)->evals; }

// Only the instant t_f counts (fixed steps reach it up to the rounding of N additions, adaptive
// ones exactly): the runners of wp_common.h observe it alone (Problem::end_only), the others
// after every step.
bool AtEnd(double t) { return t >= kTend * (1 - 1e-9); }

double EndError(double t, const double* x, const double*, void*) {
  return AtEnd(t) ? std::hypot(x[0] - (1 - kEcc), x[1]) : 0.0;
}

double EndDrift(double t, const double* x, const double* v, void*) {
  static const double x0[2] = {1 - kEcc, 0}, v0[2] = {0, std::sqrt((1 + kEcc) / (1 - kEcc))};
  return AtEnd(t) ? std::fabs(Energy(x, v) - Energy(x0, v0)) : 0.0;
}

// ---- CEODE adaptive ------------------------------------------------------------------------
struct AdaptStats {
  int flag = 0;
  long netf = 0, ncapped = 0, guard_fe = 0, solver_fe = 0;
};

// The band of step ratios that keep h (CEodeSetFixedStepBounds); lb = 0: CEODE's default.
struct Band {
  double lb = 0, ub = 0;
};
constexpr Band kNarrowBand{0.99, 1.01};

// One run at rtol = atol = tol: create, set up, CEodeEvolve(CE_NORMAL) to the stop time t_f,
// free. rhs_evals is the count of f itself. Returns 0 on success; st->flag is the flag.
int CeodeAdaptiveRun(SUNContext ctx, const wp::Problem& p, const char* set, double tol, Band band,
                     wp::Outcome* out, AdaptStats* st) {
  const long f0 = Evals(p);
  wp::CeodeObjects o;
  if (!o.Create(ctx, p)) return 1;
  void* mem = o.mem;
  st->flag = 0;
  bool bad = wp::Failed(CEodeInit(mem, p.f2, p.t0, o.x, o.v), "CEodeInit") ||
             wp::Failed(CEodeSetUserData(mem, p.user), "CEodeSetUserData") ||
             wp::Failed(CEodeSetMethodByName(mem, set), "CEodeSetMethodByName") ||
             wp::Failed(CEodeSStolerances(mem, tol, tol), "CEodeSStolerances") ||
             wp::Failed(CEodeSetMaxNumSteps(mem, 100000000L), "CEodeSetMaxNumSteps") ||
             wp::Failed(CEodeSetStopTime(mem, p.tend), "CEodeSetStopTime") ||
             (band.lb > 0 && wp::Failed(CEodeSetFixedStepBounds(mem, band.lb, band.ub),
                                        "CEodeSetFixedStepBounds"));
  double t = p.t0;
  if (!bad) {
    st->flag = CEodeEvolve(mem, p.tend, o.x, o.v, &t, CE_NORMAL);
    bad = st->flag < 0;
  }
  wp::Track tr(p);
  if (!bad) tr.Step(t, N_VGetArrayPointer(o.x), N_VGetArrayPointer(o.v));
  long nme = 0, nls = 0;
  CEodeGetNumSteps(mem, &out->steps);
  CEodeGetNumRhsEvals(mem, &st->solver_fe);
  CEodeGetNumErrTestFails(mem, &st->netf);
  CEodeGetNumStableStepLimited(mem, &st->ncapped);
  CEodeGetGuardStats(mem, &st->guard_fe, &nme, &nls);
  out->rhs_evals = Evals(p) - f0;
  return tr.Finish(bad || t < p.tend * (1 - 1e-9), out);
}

// The numbers run, then the timed runs (wp::TimeMedian); a failed numbers run is a failure row
// named by its flag. Returns true when the row was added.
bool MeasureCeodeAdaptive(wp::Table* table, SUNContext ctx, const wp::Problem& p, const char* set,
                          double tol, int* failures, Band band = {}) {
  char suffix[48] = "";
  if (band.lb > 0) std::snprintf(suffix, sizeof suffix, "_band%g-%g", band.lb, band.ub);
  const std::string config = std::string(set) + "_adaptive" + suffix;
  wp::Outcome o;
  AdaptStats st;
  if (CeodeAdaptiveRun(ctx, p, set, tol, band, &o, &st) != 0) {
    const std::string why =
        st.flag < 0 ? std::string("failed: ") + CEodeGetReturnFlagName(st.flag) : "failed";
    table->Fail("CEODE", config, tol, why.c_str());
    ++*failures;
    return false;
  }
  wp::Outcome scratch;
  AdaptStats scratch_st;
  const double secs = wp::TimeMedian(
      [&]() { return CeodeAdaptiveRun(ctx, p, set, tol, band, &scratch, &scratch_st); });
  if (secs < 0) {
    table->Fail("CEODE", config, tol, "failed while timing");
    ++*failures;
    return false;
  }
  table->Add(wp::OutcomeRow("CEODE", config, tol, o, secs));
  std::printf(
      "    %s tol %.0e: %ld failed error tests, %ld steps capped by the stable step, "
      "f: %ld by the step, %ld by the guard, %ld in all\n",
      config.c_str(), tol, st.netf, st.ncapped, st.solver_fe, st.guard_fe, o.rhs_evals);
  return true;
}

// Least-squares slope of log y against log x.
double Slope(const std::vector<double>& x, const std::vector<double>& y) {
  const double n = static_cast<double>(x.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t i = 0; i < x.size(); ++i) {
    const double lx = std::log(x[i]), ly = std::log(y[i]);
    sx += lx, sy += ly, sxx += lx * lx, sxy += lx * ly;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

// The cost of an adaptive run that is not its steps: the same job (create, set up, evolve, free)
// to t = 0.01, a few steps from the pericentre. Prints seconds and steps per set.
void PrintCeodeRunOverhead(SUNContext ctx, const wp::Problem& p,
                           const std::vector<const char*>& sets) {
  wp::Problem shortp = p;
  shortp.tend = 0.01;
  std::printf("CEODE adaptive, a run to t = 0.01 (tol 1e-10): the cost per run beside the steps\n");
  for (const char* set : sets) {
    wp::Outcome o;
    AdaptStats st;
    if (CeodeAdaptiveRun(ctx, shortp, set, 1e-10, {}, &o, &st) != 0) continue;
    const double secs =
        wp::TimeMedian([&]() { return CeodeAdaptiveRun(ctx, shortp, set, 1e-10, {}, &o, &st); });
    std::printf("  %-7s %9.1f us, %ld steps, %ld f\n", set, 1e6 * secs, o.steps, o.rhs_evals);
  }
}

// ---- DPRKN6 --------------------------------------------------------------------------------
// One adaptive run at rtol = atol = tol, observed after every step as the peers.
int DprknRun(const wp::Problem& p, double tol, wp::Outcome* out) {
  std::vector<double> x(p.x0), v(p.v0);
  wp::Track tr(p);
  dprkn6::Stats st;
  dprkn6::Options o;
  o.rtol = o.atol = tol;
  auto acc = [&p](double t, const double* xx, double* a) {
    return p.acc(t, xx, nullptr, a, p.user);
  };
  auto obs = [&tr](double t, const double* xx, const double* vv) { tr.Step(t, xx, vv); };
  const int rc = dprkn6::Integrate(p.n, acc, p.t0, p.tend, x.data(), v.data(), o, obs, &st);
  out->steps = st.steps;
  out->rhs_evals = st.evals;
  return tr.Finish(rc != 0, out);
}

// One DPRKN6 step from the pericentre at h = 0.04, 0.02, 0.01 (a fifth of the pericentre's
// time scale r / |v| = 0.2 and below): the local errors of position and velocity against the
// exact orbit must fall like h^7 and the error estimate like h^5 (the embedded pair is of
// order 4). Prints the slopes; returns 1 when one is off.
int CheckDprknLocalOrders(const wp::Problem& p) {
  const double hs[] = {0.04, 0.02, 0.01};
  std::vector<double> h, ex, ev, est;
  dprkn6::Stepper s(p.n);
  dprkn6::Stats st;
  auto acc = [&p](double t, const double* xx, double* a) {
    return p.acc(t, xx, nullptr, a, p.user);
  };
  for (double hh : hs) {
    acc(p.t0, p.x0.data(), s.K(0));
    if (s.Trial(acc, p.t0, p.x0.data(), p.v0.data(), hh, &st) != 0) return 1;
    double xe[2], ve[2];
    Exact(p.t0 + hh, xe, ve);
    h.push_back(hh);
    ex.push_back(std::hypot(s.XNew()[0] - xe[0], s.XNew()[1] - xe[1]));
    ev.push_back(std::hypot(s.VNew()[0] - ve[0], s.VNew()[1] - ve[1]));
    est.push_back(std::hypot(s.ErrX()[0], s.ErrX()[1]));
  }
  const double px = Slope(h, ex), pv = Slope(h, ev);
  const double pe = Slope(h, est);
  const bool ok = px > 6.5 && px < 7.8 && pv > 6.5 && pv < 7.8 && pe > 4.5 && pe < 5.8;
  std::printf(
      "DPRKN6 one step from the pericentre, h = 0.04 ... 0.01: local error ~ h^%.2f "
      "(position), h^%.2f (velocity), estimate ~ h^%.2f (expected 7, 7, 5) %s\n",
      px, pv, pe, ok ? "ok" : "-- OFF");
  return ok ? 0 : 1;
}

// DPRKN6's global order at fixed steps: N steps from the pericentre to t, error |x - x_exact(t)|
// at t, for each N of `ns`; returns the log-log slope of the error against h.
double DprknGlobalOrder(const wp::Problem& p, double t, const std::vector<long>& ns) {
  std::vector<double> h, e;
  auto acc = [&p](double tt, const double* xx, double* a) {
    return p.acc(tt, xx, nullptr, a, p.user);
  };
  double xe[2], ve[2];
  Exact(t, xe, ve);
  for (long n : ns) {
    std::vector<double> x(p.x0), v(p.v0);
    dprkn6::Stats st;
    const double hh = t / static_cast<double>(n);
    if (dprkn6::IntegrateFixed(
            p.n, acc, 0.0, hh, n, x.data(), v.data(), [](double, const double*, const double*) {},
            &st) != 0) {
      return 0;
    }
    h.push_back(hh);
    e.push_back(std::hypot(x[0] - xe[0], x[1] - xe[1]));
  }
  return Slope(h, e);
}

// The order check at fixed steps: to the apocentre (half an orbit), where the error falls like
// h^6, and, printed only, over the scene's 10 orbits, where the state returns to the symmetric
// start and the error falls faster (about h^7 here: the leading term nearly cancels over whole
// orbits, so that instant cannot show the method's order).
int CheckDprknGlobalOrder(const wp::Problem& p) {
  const double half = DprknGlobalOrder(p, M_PI, {100, 141, 200, 283, 400});
  const double whole = DprknGlobalOrder(p, kTend, {2500, 3500, 5000, 7000, 10000});
  const bool ok = half > 5.5 && half < 6.7;
  std::printf(
      "DPRKN6 fixed steps to the apocentre (t = pi, N = 100 ... 400): error ~ h^%.2f "
      "(expected 6) %s\n",
      half, ok ? "ok" : "-- OFF");
  std::printf(
      "DPRKN6 fixed steps over the 10 orbits (N = 2500 ... 10000): error ~ h^%.2f "
      "(whole orbits, not checked)\n",
      whole);
  return ok ? 0 : 1;
}

// ---- ARKODE ERKStep with a named table ---------------------------------------------------------
// SUNDIALS before 6.7.0 reuses the last stage's f as the next step's first stage whenever a
// table's last node is c_s = 1 (wp::KuttaRk3 describes the trap), although Verner 8-5-6 and
// Fehlberg 13-7-8 have c_s = 1 with b different from the last row of A: ERKStep then runs another
// method with one f less per step. Their copies here have c_s = 1 - 1e-8; c only moves f's time
// argument and the Kepler force does not depend on t, so the copy is the published method.
ARKodeButcherTable ErkTable(ARKODE_ERKTableID id, bool move_last_node) {
  ARKodeButcherTable B = ARKodeButcherTable_LoadERK(id);
  if (B != nullptr && move_last_node && B->c[B->stages - 1] == 1.0) B->c[B->stages - 1] = 1 - 1e-8;
  return B;
}

// One adaptive ERKStep run with table B at rtol = atol = tol, one step at a time to the stop time
// t_f, observed after every step: wp::SundialsRun's one-step mode with ERKStepSetTable.
int ErkTableRun(SUNContext ctx, const wp::Problem& p, ARKodeButcherTable B, double tol,
                wp::Outcome* out) {
  N_Vector y = N_VNew_Serial(2 * p.n, ctx);
  if (y == nullptr) return 1;
  const std::vector<double> y0 = p.FirstOrderStart();
  double* Y = N_VGetArrayPointer(y);
  std::copy(y0.begin(), y0.end(), Y);
  void* mem = ERKStepCreate(p.f1, p.t0, y, ctx);
  bool bad = mem == nullptr || wp::Failed(ERKStepSetUserData(mem, p.user), "ERKStepSetUserData") ||
             wp::Failed(ERKStepSetTable(mem, B), "ERKStepSetTable") ||
             wp::Failed(ERKStepSStolerances(mem, tol, tol), "ERKStepSStolerances") ||
             wp::Failed(ERKStepSetMaxNumSteps(mem, 100000000L), "ERKStepSetMaxNumSteps") ||
             wp::Failed(ERKStepSetStopTime(mem, p.tend), "ERKStepSetStopTime");
  wp::Track tr(p);
  double t = p.t0;
  while (!bad && t < p.tend - 1e-12 * std::max(1.0, std::fabs(p.tend))) {
    bad = wp::Failed(ERKStepEvolve(mem, p.tend, y, &t, ARK_ONE_STEP), "ERKStepEvolve");
    if (!bad) tr.Step(t, Y, Y + p.n);
  }
  bad = bad || wp::Failed(ERKStepGetNumSteps(mem, &out->steps), "ERKStepGetNumSteps") ||
        wp::Failed(ERKStepGetNumRhsEvals(mem, &out->rhs_evals), "ERKStepGetNumRhsEvals");
  ERKStepFree(&mem);
  N_VDestroy(y);
  return tr.Finish(bad, out);
}

// The table's order conditions (ARKodeButcherTable_CheckOrder, which checks up to order 6), and
// the run at tol = 1e-10 as loaded and with the moved last node: the moved one must evaluate f
// at every stage (f per step >= stages). Prints both; returns 1 when the check fails.
int CheckErkTable(SUNContext ctx, const wp::Problem& p, ARKODE_ERKTableID id, const char* name) {
  ARKodeButcherTable as_is = ErkTable(id, false), moved = ErkTable(id, true);
  if (as_is == nullptr || moved == nullptr) return 1;
  int q = 0, pe = 0;
  const int conds = ARKodeButcherTable_CheckOrder(as_is, &q, &pe, nullptr);
  wp::Outcome a, m;
  const bool ran =
      ErkTableRun(ctx, p, as_is, 1e-10, &a) == 0 && ErkTableRun(ctx, p, moved, 1e-10, &m) == 0;
  const double fa = a.steps > 0 ? static_cast<double>(a.rhs_evals) / a.steps : 0;
  const double fm = m.steps > 0 ? static_cast<double>(m.rhs_evals) / m.steps : 0;
  const bool ok = ran && conds >= 0 && fm >= moved->stages;
  std::printf(
      "ARKODE %s: %d stages, order conditions hold to %d(%d)%s; at tol 1e-10 as loaded "
      "%.2f f/step, error %.3e; with c_s = 1 - 1e-8 %.2f f/step, error %.3e %s\n",
      name, as_is->stages, q, pe, conds > 0 ? " (checked up to 6)" : "", fa, a.error, fm, m.error,
      ok ? "ok" : "-- OFF");
  ARKodeButcherTable_Free(as_is);
  ARKodeButcherTable_Free(moved);
  return ok ? 0 : 1;
}

// ---- the summary ---------------------------------------------------------------------------
struct Curve {
  std::string solver, config;
  std::string Name() const { return solver + " " + config; }
};

// f evaluations at error e by the harness's rule; < 0 when the curve never reaches e.
double EvalsAtError(const std::vector<wp::Row>& rows, const Curve& c, double e) {
  return wp::EvalsAtError(rows, c.solver, c.config, e);
}

std::vector<Curve> CurvesOf(const wp::Table& table) {
  std::vector<Curve> cs;
  for (const wp::Row& r : table.rows()) {
    bool seen = false;
    for (const Curve& c : cs) seen = seen || (c.solver == r.solver && c.config == r.config);
    if (!seen) cs.push_back({r.solver, r.config});
  }
  return cs;
}

bool IsCeodeAdaptive(const Curve& c) { return wp::IsCeodeAdaptive(c.solver, c.config); }

// seconds = a + b steps by least squares on the relative residuals (weights 1 / seconds^2, so
// that the long runs do not decide the intercept): the cost per run (create, set up, free) and
// per step; false with fewer than 3 rows.
bool CostFit(const std::vector<wp::Row>& rows, const Curve& c, double* a, double* b) {
  double n = 0, sw = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (const wp::Row& r : rows) {
    if (r.solver != c.solver || r.config != c.config || !(r.seconds > 0)) continue;
    const double w = 1 / (r.seconds * r.seconds), x = static_cast<double>(r.steps);
    n += 1, sw += w, sx += w * x, sy += w * r.seconds, sxx += w * x * x, sxy += w * x * r.seconds;
  }
  const double det = sw * sxx - sx * sx;
  if (n < 3 || !(std::fabs(det) > 0)) return false;
  *b = (sw * sxy - sx * sy) / det;
  *a = (sy - *b * sx) / sw;
  return true;
}

void PrintSummary(const wp::Table& table, const std::vector<double>& levels) {
  const std::vector<wp::Row>& rows = table.rows();
  const std::vector<Curve> cs = CurvesOf(table);
  std::printf(
      "\nequal final-position error (f evaluations and CPU seconds per run, "
      "wp::TimeAtError's rule; '-': not reached)\n%-30s",
      "curve");
  for (double e : levels) std::printf(" %10s@%-5.0e %10s", "f", e, "seconds");
  std::printf("\n");
  for (const Curve& c : cs) {
    std::printf("%-30s", c.Name().c_str());
    for (double e : levels) {
      const double f = EvalsAtError(rows, c, e), s = wp::TimeAtError(rows, c.solver, c.config, e);
      if (f > 0) {
        std::printf(" %16.0f %10.3e", f, s);
      } else {
        std::printf(" %16s %10s", "-", "-");
      }
    }
    std::printf("\n");
  }
  for (double e : levels) {
    const Curve* best = nullptr;
    double tb = -1;
    for (const Curve& c : cs) {
      const double t = wp::TimeAtError(rows, c.solver, c.config, e);
      if (IsCeodeAdaptive(c) && t > 0 && (tb < 0 || t < tb)) tb = t, best = &c;
    }
    std::printf("\nerror %.0e: ", e);
    if (best == nullptr) {
      std::printf("no CEODE adaptive curve reaches it\n");
      continue;
    }
    const double fb = EvalsAtError(rows, *best, e);
    std::printf("CEODE-best (adaptive) %s: %.0f f, %.3e s\n", best->config.c_str(), fb, tb);
    const Curve rk8pd{"GSL", "rk8pd"};
    const double fg = EvalsAtError(rows, rk8pd, e);
    const double tg = wp::TimeAtError(rows, rk8pd.solver, rk8pd.config, e);
    if (tg > 0) {
      std::printf("  CEODE-best / GSL rk8pd (DOP853 class): time %.3f, f %.3f\n", tb / tg, fb / fg);
    } else {
      std::printf("  GSL rk8pd does not reach it\n");
    }
    std::printf("  CEODE-best time / each curve's (< 1: CEODE-best faster):\n");
    for (const Curve& c : cs) {
      if (&c == best) continue;
      const double t = wp::TimeAtError(rows, c.solver, c.config, e);
      if (t > 0) {
        std::printf("    %-30s %8.3f  %s\n", c.Name().c_str(), tb / t,
                    tb < t ? "CEODE-best faster" : "CEODE-best slower");
      } else {
        std::printf("    %-30s %8s\n", c.Name().c_str(), "-");
      }
    }
  }
  std::printf("\ntime per run fitted as a + b steps over each curve (relative least squares):\n");
  for (const Curve& c : cs) {
    double a = 0, b = 0;
    if (CostFit(rows, c, &a, &b)) {
      std::printf("  %-30s a = %9.1f us per run, b = %7.1f ns per step\n", c.Name().c_str(),
                  1e6 * a, 1e9 * b);
    }
  }
  // Adaptive against fixed steps of the same set at equal error: f and time.
  std::printf("\nadaptive / fixed step of the same set at equal error (f ratio, time ratio)\n");
  for (const char* set : {"G5_O4", "G6_O5", "G7_O7", "G8_O8"}) {
    const Curve a{"CEODE", std::string(set) + "_adaptive"}, f{"CEODE", std::string(set) + "_fixed"};
    std::printf("  %-6s", set);
    for (double e : levels) {
      const double fa = EvalsAtError(rows, a, e), ff = EvalsAtError(rows, f, e);
      const double ta = wp::TimeAtError(rows, a.solver, a.config, e);
      const double tf = wp::TimeAtError(rows, f.solver, f.config, e);
      if (fa > 0 && ff > 0) {
        std::printf("  %.0e: f %.3f, time %.3f", e, fa / ff, ta / tf);
      } else {
        std::printf("  %.0e: -", e);
      }
    }
    std::printf("\n");
  }
}

}  // namespace

int main(int argc, char** argv) {
  const wp::Args args = wp::ParseArgs(argc, argv);
  SUNContext ctx = nullptr;
  if (wp::Failed(SUNContext_Create(SUN_COMM_NULL, &ctx), "SUNContext_Create")) return 1;
  std::printf(
      "Kepler e = %.1f, %d orbits (t_f = 20 pi), error = |q(t_f) - q(0)|, "
      "drift = |H(t_f) - H(0)|\n",
      kEcc, kOrbits);
  wp::Table table("kepler", args.csv);

  Kepler kepler;
  wp::Problem p;
  p.n = 2;
  p.Lift<Acc>();
  p.user = &kepler;
  p.tend = kTend;
  p.x0 = {1 - kEcc, 0};
  p.v0 = {0, std::sqrt((1 + kEcc) / (1 - kEcc))};
  p.err = EndError;
  p.drift = EndDrift;
  p.separable = true;
  p.end_only = true;

  std::vector<double> tols = {1e-4,  1e-5,  1e-6,  1e-7,  1e-8, 1e-9,
                              1e-10, 1e-11, 1e-12, 1e-13, 1e-14};
  std::vector<const char*> sets = {"G4_A34", "G5_O4", "G6_O5", "G7_O7", "G8_O8"};
  std::vector<const char*> fixed_sets = {"G5_O4", "G6_O5", "G7_O7", "G8_O8"};
  std::vector<long> fixed_n = {2000,  2800,  4000,  5600,  8000,  11300,
                               16000, 22600, 32000, 45000, 64000, 90000};
  if (args.quick) {
    tols = {1e-7, 1e-9, 1e-11};
    sets = fixed_sets = {"G6_O5", "G8_O8"};
    fixed_n = {4000, 16000};
  }
  int bad = 0, ceode_failures = 0;

  for (const char* set : sets) {
    for (double tol : tols) MeasureCeodeAdaptive(&table, ctx, p, set, tol, &ceode_failures);
  }
  for (double tol : tols) {
    MeasureCeodeAdaptive(&table, ctx, p, "G8_O8", tol, &ceode_failures, kNarrowBand);
  }
  for (const char* set : fixed_sets) {
    for (long n : fixed_n) {
      wp::MeasureCeode(&table, ctx, p, set, kTend / static_cast<double>(n), false,
                       std::string(set) + "_fixed");
    }
  }
  // The same G8_O8 steps by hand: the method's floor (wp::MeasureHandG8 checks its errors, to
  // 1e-11 where ten orbits' round-off leaves the fixed steps' errors, 5e-13 .. 4e-12; a failure
  // row counts as a problem).
  for (long n : fixed_n) {
    wp::MeasureHandG8(&table, ctx, p, kTend / static_cast<double>(n), 1e-11);
  }

  bad += CheckErkTable(ctx, p, ARKODE_VERNER_8_5_6, "ARKODE_VERNER_8_5_6");
  bad += CheckErkTable(ctx, p, ARKODE_FEHLBERG_13_7_8, "ARKODE_FEHLBERG_13_7_8");
  for (double tol : tols) wp::MeasureSundials(&table, ctx, p, {wp::Sun::kErk}, tol, "default");
  const std::pair<ARKODE_ERKTableID, const char*> erk_tables[] = {
      {ARKODE_VERNER_8_5_6, "Verner_8_5_6"}, {ARKODE_FEHLBERG_13_7_8, "Fehlberg_13_7_8"}};
  for (const auto& et : erk_tables) {
    ARKodeButcherTable B = ErkTable(et.first, true);
    if (B == nullptr) {
      ++bad;
      continue;
    }
    for (double tol : tols) {
      wp::Measure(&table, "ARKODE-ERK", et.second, tol,
                  [&](wp::Outcome* o) { return ErkTableRun(ctx, p, B, tol, o); });
    }
    ARKodeButcherTable_Free(B);
  }
  for (double tol : tols) {
    wp::MeasureSundials(&table, ctx, p, {wp::Sun::kCvodeAdams}, tol, "adaptive");
  }

#ifdef CEODE_BENCH_PEERS
  peers::Setup();
  for (peers::Kind k : {peers::Kind::kRk8pd, peers::Kind::kRkf78, peers::Kind::kDopri5,
                        peers::Kind::kBulirschStoer}) {
    const peers::Info& info = peers::InfoOf(k);
    for (double tol : tols) {
      wp::Measure(&table, info.solver, info.config, tol,
                  [&](wp::Outcome* o) { return peers::PeerOnce<2>(p, info, tol, 1.0, o); });
    }
  }
#else
  std::printf("(built without GSL/Boost: no odeint/GSL peer curves)\n");
#endif

  for (double tol : tols) {
    wp::Measure(&table, "DPRKN6", "adaptive", tol,
                [&](wp::Outcome* o) { return DprknRun(p, tol, o); });
  }

  std::printf("\n");
  PrintCeodeRunOverhead(ctx, p, sets);
  bad += CheckDprknLocalOrders(p);
  bad += CheckDprknGlobalOrder(p);
#ifdef CEODE_BENCH_PEERS
  bad += peers::CheckPeerOrders(table, 1e-11, 1e-2);
#endif
  PrintSummary(table, {1e-6, 1e-8, 1e-10});
  std::printf("\nCEODE adaptive runs that returned a failure flag: %d (results, not problems)\n",
              ceode_failures);
  bad += table.failures() - ceode_failures;
  std::printf("%d problem(s)\n", bad);
  SUNContext_Free(&ctx);
  return bad == 0 ? 0 : 1;
}
