// -----------------------------------------------------------------------------
// wp_events: work-precision scene of event location (root finding) on SUNDIALS' Kepler problem
// (kepler_model.h): CEODE's root finding on its dense output against ARKODE ERKStep's and
// CVODE's, every solver timed side by side on the harness of wp_common.h.
//
// Problem: Kepler e = 0.6 from the pericentre, t in [0, 20 pi + 1] (10 orbits and a bit), one
// root function g = q2 in both directions. The orbit is symmetric about the q1 axis: q2 = 0
// exactly at the pericentre and the apocentre, t = k pi, k = 1 ... 20 (the zero at t = 0 is the
// start, inactive in all three solvers). Error = max_k |t_k - k pi| over the 20 events; a run
// that does not return exactly those 20 events, alternating in direction (-1 at the apocentres,
// +1 at the pericentres), is a failure row.
//
// Curves (CSV: the common schema; the drift column holds the g evaluations, this scene has no
// drift):
//  * CEODE fixed step h = t_e / N (G5_O4, G6_O5, G7_O7, G8_O8; --quick: G5_O4, G8_O8) and
//    adaptive rtol = atol = tol (G4_A34, G5_O4, G8_O8), CEodeEvolve in CE_NORMAL to t_e,
//    returning at every root.
//  * ARKODE ERKStep adaptive (default table, order 4) with ERKStepRootInit and CVODE Adams
//    (fixed-point iteration) with CVodeRootInit, both on y = (q, q'), in their normal mode.
// f evaluations are counted in f itself for every solver.
//
// Summary: at event-time errors 1e-6 and 1e-8, the CPU seconds of each curve (wp::TimeAtError)
// and the best CEODE curve's time ratio to ARKODE ERK and to CVODE Adams (< 1: CEODE faster).
//
// Usage: wp_events [--csv FILE] [--quick]
// --quick: three tolerances and two fixed steps per curve (the ctest).
// -----------------------------------------------------------------------------
#include <arkode/arkode_erkstep.h>
#include <cvode/cvode.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "kepler_model.h"
#include "wp_common.h"

namespace {

constexpr int kEvents = 20;
const double kTend = 20 * M_PI + 1;

// The events' time error, or -1 when they are not the 20 expected (times and directions).
struct EventLog {
  std::vector<double> t;
  std::vector<int> dir;
  double Error() const {
    if (t.size() != static_cast<size_t>(kEvents)) return -1;
    double e = 0;
    for (int k = 1; k <= kEvents; ++k) {
      if (dir[k - 1] != (k % 2 == 1 ? -1 : 1)) return -1;
      e = std::max(e, std::fabs(t[k - 1] - k * M_PI));
    }
    return e;
  }
};

long& Evals(const wp::Problem& p) { return static_cast<kepler::Kepler*>(p.user)->evals; }

// g = q2 on CEODE's (x, v) and on the first-order y = (q, q').
int GCeode(sunrealtype, N_Vector x, N_Vector, sunrealtype* g, void*) {
  g[0] = N_VGetArrayPointer(x)[1];
  return 0;
}
int GFirstOrder(sunrealtype, N_Vector y, sunrealtype* g, void*) {
  g[0] = N_VGetArrayPointer(y)[1];
  return 0;
}

// The outcome of a run from its events: error, f and g evaluations, steps; 1 on failure.
int Finish(bool bad, const EventLog& log, long steps, long fe, long ge, wp::Outcome* out) {
  out->error = log.Error();
  out->steps = steps;
  out->rhs_evals = fe;
  out->drift = static_cast<double>(ge);
  return bad || out->error < 0 ? 1 : 0;
}

// ---- CEODE: h > 0 a fixed step, else error control at rtol = atol = tol --------------------
int CeodeRun(SUNContext ctx, const wp::Problem& p, const char* set, double h, double tol,
             wp::Outcome* out) {
  const long f0 = Evals(p);
  wp::CeodeObjects o;
  if (!o.Create(ctx, p)) return 1;
  void* mem = o.mem;
  bool bad = wp::Failed(CEodeInit(mem, p.f2, p.t0, o.x, o.v), "CEodeInit") ||
             wp::Failed(CEodeSetUserData(mem, p.user), "CEodeSetUserData") ||
             wp::Failed(CEodeSetMethodByName(mem, set), "CEodeSetMethodByName") ||
             wp::Failed(h > 0 ? CEodeSetFixedStep(mem, h) : CEodeSStolerances(mem, tol, tol),
                        "CEodeSetFixedStep/CEodeSStolerances") ||
             wp::Failed(CEodeSetMaxNumSteps(mem, 100000000L), "CEodeSetMaxNumSteps") ||
             wp::Failed(CEodeRootInit(mem, 1, GCeode), "CEodeRootInit");
  EventLog log;
  double t = p.t0;
  int flag = CE_ROOT_RETURN;
  while (!bad && flag == CE_ROOT_RETURN) {
    flag = CEodeEvolve(mem, p.tend, o.x, o.v, &t, CE_NORMAL);
    bad = wp::Failed(flag, "CEodeEvolve");
    int info = 0;
    if (!bad && flag == CE_ROOT_RETURN && CEodeGetRootInfo(mem, &info) == CE_SUCCESS) {
      log.t.push_back(t);
      log.dir.push_back(info);
    }
  }
  long nst = 0, nge = 0;
  CEodeGetNumSteps(mem, &nst);
  CEodeGetNumGEvals(mem, &nge);
  return Finish(bad, log, nst, Evals(p) - f0, nge, out);
}

// ---- SUNDIALS: ERKStep (default table) or CVODE Adams, root finding on, normal mode ----------
template <class Evolve, class Info>
bool SunEvents(double tend, N_Vector y, Evolve evolve, Info info, int root_return, EventLog* log) {
  double t = 0;
  int flag = root_return;
  while (flag == root_return) {
    flag = evolve(tend, y, &t);
    if (flag < 0) return false;
    int dir = 0;
    if (flag == root_return && info(&dir) == 0) {
      log->t.push_back(t);
      log->dir.push_back(dir);
    }
  }
  return true;
}

N_Vector StartVector(SUNContext ctx, const wp::Problem& p) {
  N_Vector y = N_VNew_Serial(2 * p.n, ctx);
  if (y == nullptr) return nullptr;
  const std::vector<double> y0 = p.FirstOrderStart();
  std::copy(y0.begin(), y0.end(), N_VGetArrayPointer(y));
  return y;
}

int ErkRun(SUNContext ctx, const wp::Problem& p, double tol, wp::Outcome* out) {
  const long f0 = Evals(p);
  N_Vector y = StartVector(ctx, p);
  if (y == nullptr) return 1;
  void* mem = ERKStepCreate(p.f1, p.t0, y, ctx);
  bool bad = mem == nullptr || wp::Failed(ERKStepSetUserData(mem, p.user), "ERKStepSetUserData") ||
             wp::Failed(ERKStepSStolerances(mem, tol, tol), "ERKStepSStolerances") ||
             wp::Failed(ERKStepSetMaxNumSteps(mem, 100000000L), "ERKStepSetMaxNumSteps") ||
             wp::Failed(ERKStepRootInit(mem, 1, GFirstOrder), "ERKStepRootInit");
  EventLog log;
  bad = bad || !SunEvents(
                   p.tend, y,
                   [&](double tout, N_Vector yy, double* t) {
                     return ERKStepEvolve(mem, tout, yy, t, ARK_NORMAL);
                   },
                   [&](int* dir) { return ERKStepGetRootInfo(mem, dir); }, ARK_ROOT_RETURN, &log);
  long nst = 0, nge = 0;
  ERKStepGetNumSteps(mem, &nst);
  ERKStepGetNumGEvals(mem, &nge);
  ERKStepFree(&mem);
  N_VDestroy(y);
  return Finish(bad, log, nst, Evals(p) - f0, nge, out);
}

int CvodeRun(SUNContext ctx, const wp::Problem& p, double tol, wp::Outcome* out) {
  const long f0 = Evals(p);
  N_Vector y = StartVector(ctx, p);
  if (y == nullptr) return 1;
  void* mem = CVodeCreate(CV_ADAMS, ctx);
  SUNNonlinearSolver nls = SUNNonlinSol_FixedPoint(y, 0, ctx);
  bool bad = mem == nullptr || nls == nullptr ||
             wp::Failed(CVodeInit(mem, p.f1, p.t0, y), "CVodeInit") ||
             wp::Failed(CVodeSetUserData(mem, p.user), "CVodeSetUserData") ||
             wp::Failed(CVodeSStolerances(mem, tol, tol), "CVodeSStolerances") ||
             wp::Failed(CVodeSetNonlinearSolver(mem, nls), "CVodeSetNonlinearSolver") ||
             wp::Failed(CVodeSetMaxNumSteps(mem, 100000000L), "CVodeSetMaxNumSteps") ||
             wp::Failed(CVodeRootInit(mem, 1, GFirstOrder), "CVodeRootInit");
  EventLog log;
  bad = bad ||
        !SunEvents(
            p.tend, y,
            [&](double tout, N_Vector yy, double* t) { return CVode(mem, tout, yy, t, CV_NORMAL); },
            [&](int* dir) { return CVodeGetRootInfo(mem, dir); }, CV_ROOT_RETURN, &log);
  long nst = 0, nge = 0;
  CVodeGetNumSteps(mem, &nst);
  CVodeGetNumGEvals(mem, &nge);
  CVodeFree(&mem);
  if (nls != nullptr) SUNNonlinSolFree(nls);
  N_VDestroy(y);
  return Finish(bad, log, nst, Evals(p) - f0, nge, out);
}

// ---- the summary -----------------------------------------------------------------------------
struct Curve {
  std::string solver, config;
};

void PrintSummary(const wp::Table& table, const std::vector<Curve>& curves,
                  const std::vector<double>& levels) {
  const std::vector<wp::Row>& rows = table.rows();
  std::printf(
      "\nequal event-time error: CPU seconds per run (wp::TimeAtError; '-': not reached)\n");
  for (const Curve& c : curves) {
    std::printf("  %-12s %-16s", c.solver.c_str(), c.config.c_str());
    for (double e : levels) {
      const double s = wp::TimeAtError(rows, c.solver, c.config, e);
      if (s > 0) {
        std::printf("  %.0e: %.3e s", e, s);
      } else {
        std::printf("  %.0e: -", e);
      }
    }
    std::printf("\n");
  }
  for (double e : levels) {
    const Curve* best = nullptr;
    double tb = -1;
    for (const Curve& c : curves) {
      const double t = wp::TimeAtError(rows, c.solver, c.config, e);
      if (c.solver == "CEODE" && t > 0 && (tb < 0 || t < tb)) tb = t, best = &c;
    }
    std::printf("event-time error %.0e: ", e);
    if (best == nullptr) {
      std::printf("no CEODE curve reaches it\n");
      continue;
    }
    std::printf("CEODE-best %s", best->config.c_str());
    for (const Curve& c : curves) {
      if (c.solver == "CEODE") continue;
      const double t = wp::TimeAtError(rows, c.solver, c.config, e);
      if (t > 0) {
        std::printf(", time / %s %s = %.3f", c.solver.c_str(), c.config.c_str(), tb / t);
      } else {
        std::printf(", %s %s: -", c.solver.c_str(), c.config.c_str());
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
      "Kepler e = %.1f to t = 20 pi + 1, g = q2 (both directions): %d events at t = k pi; "
      "error = max |t_k - k pi|, drift column = g evaluations\n",
      kepler::kEcc, kEvents);
  wp::Table table("events", args.csv);

  kepler::Kepler model;
  wp::Problem p;
  p.n = 2;
  p.Lift<kepler::Acc>();
  p.user = &model;
  p.tend = kTend;
  p.x0 = {1 - kepler::kEcc, 0};
  p.v0 = {0, std::sqrt((1 + kepler::kEcc) / (1 - kepler::kEcc))};

  // From 1e-5: at 1e-4 the phase error of 10 orbits is of order 1 and some solvers (CEODE G5_O4,
  // CVODE Adams) no longer return the 20 events.
  std::vector<double> tols = {1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12};
  std::vector<long> fixed_n = {2000, 4000, 8000, 16000, 32000, 64000};
  std::vector<const char*> fixed_sets = {"G5_O4", "G6_O5", "G7_O7", "G8_O8"};
  if (args.quick) {
    tols = {1e-7, 1e-9, 1e-11};
    fixed_n = {4000, 16000};
    fixed_sets = {"G5_O4", "G8_O8"};
  }
  std::vector<Curve> curves;
  for (const char* set : fixed_sets) {
    const std::string config = std::string(set) + "_fixed";
    curves.push_back({"CEODE", config});
    for (long n : fixed_n) {
      const double h = kTend / static_cast<double>(n);
      wp::Measure(&table, "CEODE", config, h,
                  [&](wp::Outcome* o) { return CeodeRun(ctx, p, set, h, 0, o); });
    }
  }
  for (const char* set : {"G4_A34", "G5_O4", "G8_O8"}) {
    const std::string config = std::string(set) + "_adaptive";
    curves.push_back({"CEODE", config});
    for (double tol : tols) {
      wp::Measure(&table, "CEODE", config, tol,
                  [&](wp::Outcome* o) { return CeodeRun(ctx, p, set, 0, tol, o); });
    }
  }
  curves.push_back({"ARKODE-ERK", "adaptive"});
  for (double tol : tols) {
    wp::Measure(&table, "ARKODE-ERK", "adaptive", tol,
                [&](wp::Outcome* o) { return ErkRun(ctx, p, tol, o); });
  }
  curves.push_back({"CVODE-Adams", "adaptive"});
  for (double tol : tols) {
    wp::Measure(&table, "CVODE-Adams", "adaptive", tol,
                [&](wp::Outcome* o) { return CvodeRun(ctx, p, tol, o); });
  }
  PrintSummary(table, curves, {1e-6, 1e-8});
  std::printf("%d run(s) failed or missed events\n", table.failures());
  SUNContext_Free(&ctx);
  return table.failures() == 0 ? 0 : 1;
}
