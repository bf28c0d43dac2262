// -----------------------------------------------------------------------------
// wp_common.h: shared pieces of the work-precision scenes (bench/wp_*.cpp).
//
//  * Timing: every configuration is run back to back until one repetition has
//    lasted >= 50 ms, and the per-run time is the median of 5 repetitions (3 for
//    runs of >= 0.5 s, one run of >= 2 s is its own measurement). The FE scenes
//    (issue 11) time the same repetitions in interleaved rounds (Rounds).
//    Each timed run is the whole user-visible cost: create, init, integrate in
//    one-step mode with the error measured after every step, free. The clock
//    is the process CPU time (see Now).
//  * Rows in the common CSV schema
//      scene,solver,config,h_or_tol,error,drift,steps,rhs_evals,seconds
//    printed as a table while the scene runs.
//  * Runners for CEODE (second-order form, optionally with a mass matrix and
//    index-3 constraints), for ARKODE ERKStep (fixed Butcher table or
//    adaptive, optionally with a projection after every step), ARKODE ARKStep
//    DIRK and CVODE (Adams / BDF) on the equivalent first-order system, and
//    for IDA on a residual form, so that every solver of a scene is driven,
//    observed and timed the same way in the same process.
//  * One RK3 (Kutta's, with the one workaround for SUNDIALS 6.4's FSAL rule)
//    and one equal-error rule (TimeAtError, the cheapest time at which a curve
//    reaches a given error, as scripts/wp_curves.py computes it).
// -----------------------------------------------------------------------------
#ifndef CEODE_BENCH_WP_COMMON_H_
#define CEODE_BENCH_WP_COMMON_H_

#include <arkode/arkode_arkstep.h>
#include <arkode/arkode_butcher.h>
#include <arkode/arkode_erkstep.h>
#include <ceode/ceode.h>
#include <cvode/cvode.h>
#include <ida/ida.h>
#include <ida/ida_ls.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "ceode_sundials_compat.h"  // SUN_COMM_NULL on SUNDIALS 6.4

namespace wp {

// ---------------------------------------------------------------- arguments
struct Args {
  std::string csv;     // --csv FILE: where the rows go (none: table only)
  bool quick = false;  // --quick: fewer configurations, for smoke tests
  bool full = false;   // --full: the scene's extra (long) configurations
};

inline Args ParseArgs(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--csv") == 0 && i + 1 < argc) {
      a.csv = argv[++i];
    } else if (std::strcmp(argv[i], "--quick") == 0) {
      a.quick = true;
    } else if (std::strcmp(argv[i], "--full") == 0) {
      a.full = true;
    } else {
      std::fprintf(stderr, "usage: %s [--csv FILE] [--quick] [--full]\n", argv[0]);
      std::exit(2);
    }
  }
  return a;
}

// Reports a failed SUNDIALS/CEODE call; returns true when the flag is an error.
inline bool Failed(int flag, const char* call) {
  if (flag < 0) {
    std::fprintf(stderr, "ERROR: %s returned %d\n", call, flag);
    return true;
  }
  return false;
}

// ------------------------------------------------------------------- timing
// CPU time of this (single-threaded) process: on an idle machine it equals the
// wall time; on a shared one (the 2 cores of the development box were shared
// with other builds) it is not inflated by waiting for a core, so solvers timed
// minutes apart stay comparable.
inline double Now() {
  timespec ts;
  if (clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts) != 0) {
    using Clock = std::chrono::steady_clock;
    return std::chrono::duration<double>(Clock::now().time_since_epoch()).count();
  }
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

constexpr double kMinRepSeconds = 0.05;
constexpr int kReps = 5;
// Runs this long are far past every equal-error comparison (the FE scenes' implicit SUNDIALS
// curves take 5-17 s a point); six of each made wp_fe_damped_mass last 9 minutes. A run of
// >= kFewRepSeconds is repeated 3 times, one of >= kOneRunSeconds is measured once.
constexpr double kFewRepSeconds = 0.5;
constexpr double kOneRunSeconds = 2.0;

// How one configuration is timed, from its first (warming) call: `calls` calls back to back
// fill one repetition of >= kMinRepSeconds, over `reps` repetitions; reps = 0 when the first
// call (>= kOneRunSeconds) is its own measurement.
struct RepPlan {
  long calls = 1;
  int reps = 0;
};

inline RepPlan PlanReps(double first) {
  RepPlan p;
  if (first >= kOneRunSeconds) return p;
  p.calls = first >= kMinRepSeconds ? 1 : static_cast<long>(std::ceil(kMinRepSeconds / first));
  p.reps = first >= kFewRepSeconds ? 3 : kReps;
  return p;
}

// Seconds per call of one repetition of `calls` calls; < 0 if a call failed.
template <class F>
double TimeRep(F&& run, long calls) {
  const double t0 = Now();
  for (long c = 0; c < calls; ++c) {
    if (run() != 0) return -1;
  }
  return (Now() - t0) / static_cast<double>(calls);
}

// NaN when any value is NaN (a failed measurement stays visible).
inline double MedianOf(std::vector<double> v) {
  for (double x : v) {
    if (std::isnan(x)) return x;
  }
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// Median seconds of one call of run(), which returns 0 on success. The first
// call calibrates how many calls fill 50 ms (it also warms caches and the
// allocator, so it is not counted unless it is a run of >= kOneRunSeconds).
// Returns < 0 if any call failed.
template <class F>
double TimeMedian(F&& run) {
  const double t0 = Now();
  if (run() != 0) return -1;
  const double first = Now() - t0;
  const RepPlan plan = PlanReps(first);
  if (plan.reps == 0) return first;
  std::vector<double> per_call;
  for (int r = 0; r < plan.reps; ++r) {
    const double t = TimeRep(run, plan.calls);
    if (t < 0) return -1;
    per_call.push_back(t);
  }
  return MedianOf(per_call);
}

// --------------------------------------------------------------------- rows
struct Row {
  std::string solver, config;
  double h_or_tol = 0, error = 0, drift = 0;
  long steps = 0, rhs_evals = 0;
  double seconds = 0;
};

// The one CSV schema of every bench program and its row format.
constexpr const char* kCsvHeader =
    "scene,solver,config,h_or_tol,error,drift,steps,rhs_evals,seconds\n";

inline void WriteCsvRow(FILE* f, const std::string& scene, const Row& r) {
  std::fprintf(f, "%s,%s,%s,%.6g,%.6e,%.6e,%ld,%ld,%.6e\n", scene.c_str(), r.solver.c_str(),
               r.config.c_str(), r.h_or_tol, r.error, r.drift, r.steps, r.rhs_evals, r.seconds);
  std::fflush(f);
}

class Table {
 public:
  Table(const std::string& scene, const std::string& csv_path) : scene_(scene) {
    if (!csv_path.empty()) {
      csv_ = std::fopen(csv_path.c_str(), "w");
      if (csv_ == nullptr) {
        std::fprintf(stderr, "ERROR: cannot write %s\n", csv_path.c_str());
        std::exit(1);
      }
      std::fputs(kCsvHeader, csv_);
    }
    std::printf("%-16s %-14s %9s %12s %10s %10s %10s %11s %9s\n", "solver", "config", "h_or_tol",
                "error", "drift", "steps", "rhs_evals", "seconds", "ns/step");
  }
  ~Table() {
    if (csv_ != nullptr) std::fclose(csv_);
  }
  Table(const Table&) = delete;
  Table& operator=(const Table&) = delete;

  void Add(const Row& r) {
    const double ns = r.steps > 0 ? 1e9 * r.seconds / static_cast<double>(r.steps) : 0;
    std::printf("%-16s %-14s %9.2e %12.4e %10.2e %10ld %10ld %11.4e %9.1f\n", r.solver.c_str(),
                r.config.c_str(), r.h_or_tol, r.error, r.drift, r.steps, r.rhs_evals, r.seconds,
                ns);
    std::fflush(stdout);
    rows_.push_back(r);
    if (csv_ != nullptr) WriteCsvRow(csv_, scene_, r);
  }
  void Fail(const std::string& solver, const std::string& config, double h_or_tol,
            const char* why) {
    std::printf("%-16s %-14s %9.2e   (%s)\n", solver.c_str(), config.c_str(), h_or_tol, why);
    ++nfail_;
  }
  int failures() const { return nfail_; }
  const std::vector<Row>& rows() const { return rows_; }

 private:
  std::string scene_;
  std::vector<Row> rows_;
  FILE* csv_ = nullptr;
  int nfail_ = 0;
};

// --------------------------------------------------------------- equal error
// Cheapest time at which one curve (the rows of one solver and config, in run
// order) reaches error <= e: measured points at or below e, and log t
// interpolated linearly in log error on every segment that crosses e (as
// scripts/wp_curves.py). Returns < 0 when the curve never reaches e.
inline double TimeAtError(const std::vector<Row>& rows, const std::string& solver,
                          const std::string& config, double e) {
  std::vector<const Row*> c;
  for (const Row& r : rows) {
    if (r.solver == solver && r.config == config) c.push_back(&r);
  }
  double best = -1;
  auto take = [&best](double s) {
    if (best < 0 || s < best) best = s;
  };
  for (const Row* r : c) {
    if (r->error > 0 && r->error <= e) take(r->seconds);
  }
  for (size_t i = 0; i + 1 < c.size(); ++i) {
    const double e1 = c[i]->error, e2 = c[i + 1]->error;
    if (!(e1 > 0 && e2 > 0) || (e1 - e) * (e2 - e) >= 0 || e1 == e2) continue;
    const double w = (std::log(e) - std::log(e1)) / (std::log(e2) - std::log(e1));
    take(std::exp(std::log(c[i]->seconds) +
                  w * (std::log(c[i + 1]->seconds) - std::log(c[i]->seconds))));
  }
  return best;
}

// The integrators users pick outside SUNDIALS (bench/peers.h writes these
// solver names): a third side in PrintEqualError and scripts/ratios.py.
inline bool IsPeerSolver(const std::string& solver) {
  return solver == "odeint" || solver == "GSL";
}

// Best curve of one side at error e: its time (< 0: not reached) and name.
template <class Pick>
double BestAtError(const Table& table,
                   const std::vector<std::pair<std::string, std::string>>& curves, double e,
                   Pick pick, std::string* name) {
  double best = -1;
  *name = "not reached";
  for (const auto& k : curves) {
    if (!pick(k.first)) continue;
    const double t = TimeAtError(table.rows(), k.first, k.second, e);
    if (t > 0 && (best < 0 || t < best)) {
      best = t;
      *name = k.first + " " + k.second;
    }
  }
  return best;
}

// Prints, at each error level, the best CEODE curve and the best other curve of
// the table and their time ratio (< 1: CEODE faster). When the table has peer
// curves (IsPeerSolver), "other" is SUNDIALS only (no peer, no hand loop) and
// the best peer gets its own columns and ratio.
inline void PrintEqualError(const Table& table, const std::vector<double>& levels) {
  std::vector<std::pair<std::string, std::string>> curves;
  bool peers = false;
  for (const Row& r : table.rows()) {
    const auto key = std::make_pair(r.solver, r.config);
    if (std::find(curves.begin(), curves.end(), key) == curves.end()) curves.push_back(key);
    peers |= IsPeerSolver(r.solver);
  }
  std::printf("\ntime at equal error (best curve per side):\n%9s %-30s %11s %-30s %11s %8s",
              "error", "best CEODE", "seconds", peers ? "best SUNDIALS" : "best other", "seconds",
              "ratio");
  std::printf(peers ? " %-30s %11s %8s\n" : "\n", "best peer", "seconds", "ratio");
  for (double e : levels) {
    std::string nc, no, np;
    const double tc = BestAtError(
        table, curves, e, [](const std::string& s) { return s == "CEODE"; }, &nc);
    const double to = BestAtError(
        table, curves, e,
        [peers](const std::string& s) {
          return s != "CEODE" && !(peers && (IsPeerSolver(s) || s == "CEODE-hand"));
        },
        &no);
    const double tp = BestAtError(table, curves, e, IsPeerSolver, &np);
    if (tc < 0 && to < 0 && tp < 0) continue;
    std::printf("%9.0e %-30s %11.3e %-30s %11.3e %8.3f", e, nc.c_str(), tc, no.c_str(), to,
                tc > 0 && to > 0 ? tc / to : 0.0);
    if (peers) {
      std::printf(" %-30s %11.3e %8.3f", np.c_str(), tp, tc > 0 && tp > 0 ? tc / tp : 0.0);
    }
    std::printf("\n");
  }
}

// ------------------------------------------------------- problem descriptions
// Error of the state at one output instant; runners keep the maximum.
using ErrFn1 = double (*)(double t, const double* y, void* user);                   // first order
using ErrFn2 = double (*)(double t, const double* x, const double* v, void* user);  // second order

struct FirstOrder {
  int n = 0;  // length of y = (x, v)
  ARKRhsFn f = nullptr;
  void* user = nullptr;
  double t0 = 0, tend = 0;
  std::vector<double> y0;
  ErrFn1 err = nullptr;
  ErrFn1 drift = nullptr;  // constraint drift (nullptr: not tracked)
  // ERKStep only: called by ARKODE on y after every step (e.g. a projection
  // onto the constraints, ERKStepSetPostprocessStepFn); ARKODE then evaluates
  // f on the changed state for the next step's first stage.
  ARKPostProcessFn post_step = nullptr;
};

// A residual form F(t, y, y') = 0 for IDA, with a consistent (y0, yp0); id
// marks the differential components (1) and the algebraic ones (0), which are
// left out of the error test. err and drift see y, whose leading entries are
// the positions and velocities as in FirstOrder.
struct Residual {
  int n = 0;
  IDAResFn res = nullptr;
  IDALsJacFn jac = nullptr;  // dense iteration matrix (nullptr: difference quotients)
  void* user = nullptr;
  double t0 = 0, tend = 0, init_step = 0;  // init_step 0: IDA's own estimate
  std::vector<double> y0, yp0, id;
  ErrFn1 err = nullptr, drift = nullptr;
};

struct SecondOrder {
  int n = 0;  // length of x
  CEodeRhsFn f = nullptr;
  void* user = nullptr;
  double t0 = 0, tend = 0;
  std::vector<double> x0, v0;
  ErrFn2 err = nullptr;
  bool vel_dependent = false;
  CEodeVelJacFn vjac = nullptr;            // nullptr: CEODE's difference quotients
  int max_nonlin_iters = 0;                // 0: CEODE's default
  int implicit_mode = CE_IMPLICIT_NEWTON;  // CEodeSetImplicitMode (PC or AUTO: docs/theory.md 4.3)
  // -- implicit-step options (bench/wp_spinning_top.cpp): 0 keeps CEODE's default --
  double nls_reltol = 0;       // CEodeSetNonlinTolerances(reltol, 0)
  long msbj = 0;               // CEodeSetJacEvalFrequency
  int pc_corrections = 0;      // CEodeSetPCCorrections
  ErrFn2 drift = nullptr;      // constraint drift (nullptr: not tracked)
  CEodeMassFn mass = nullptr;  // constant mass matrix (nullptr: M = I)
  // Index-3 constraints Phi(x) = 0 (nc of them, Jacobian G) and the
  // saddle-point matrix [[M, G^T], [G, 0]]: dense (saddle_nnz = 0) or CSR with
  // room for saddle_nnz entries, factored by KLU.
  int nc = 0;
  CEodeConstrFn phi = nullptr;
  CEodeConstrJacFn G = nullptr;
  long saddle_nnz = 0;
};

// One integration's outcome (the timing is added by TimeMedian).
struct Outcome {
  double error = 0, drift = 0;
  long steps = 0, rhs_evals = 0;
  long jac_evals = 0, lin_setups = 0;  // CEODE only: iteration-matrix evaluations, factorisations
};

// ----------------------------------------------------------- CEODE (2nd order)
// The objects of one CEODE run, freed together.
struct CeodeObjects {
  N_Vector x = nullptr, v = nullptr, phi = nullptr, b = nullptr;
  SUNMatrix M = nullptr, A = nullptr;
  SUNLinearSolver LS = nullptr;
  void* mem = nullptr;
  CeodeObjects(SUNContext ctx, int n) : x(N_VNew_Serial(n, ctx)), v(N_VNew_Serial(n, ctx)) {
    mem = CEodeCreate(ctx);
  }
  ~CeodeObjects() {
    CEodeFree(&mem);
    if (LS != nullptr) SUNLinSolFree(LS);
    if (A != nullptr) SUNMatDestroy(A);
    if (M != nullptr) SUNMatDestroy(M);
    for (N_Vector w : {x, v, phi, b}) {
      if (w != nullptr) N_VDestroy(w);
    }
  }
  CeodeObjects(const CeodeObjects&) = delete;
  CeodeObjects& operator=(const CeodeObjects&) = delete;
};

// Linear solver, mass matrix and constraints of p; returns true on failure.
inline bool CeodeAttach(SUNContext ctx, const SecondOrder& p, CeodeObjects* o) {
  void* mem = o->mem;
  if (p.vel_dependent) {
    o->A = SUNDenseMatrix(p.n, p.n, ctx);
    o->LS = SUNLinSol_Dense(o->x, o->A, ctx);
    return o->A == nullptr || o->LS == nullptr ||
           Failed(CEodeSetVelocityDependence(mem, SUNTRUE), "CEodeSetVelocityDependence") ||
           Failed(CEodeSetLinearSolver(mem, o->LS, o->A), "CEodeSetLinearSolver") ||
           (p.vjac != nullptr && Failed(CEodeSetVelJacFn(mem, p.vjac), "CEodeSetVelJacFn")) ||
           Failed(CEodeSetImplicitMode(mem, p.implicit_mode), "CEodeSetImplicitMode") ||
           (p.nls_reltol > 0 &&
            Failed(CEodeSetNonlinTolerances(mem, p.nls_reltol, 0), "CEodeSetNonlinTolerances")) ||
           (p.msbj > 0 &&
            Failed(CEodeSetJacEvalFrequency(mem, p.msbj), "CEodeSetJacEvalFrequency")) ||
           Failed(CEodeSetPCCorrections(mem, p.pc_corrections), "CEodeSetPCCorrections") ||
           (p.max_nonlin_iters > 0 &&
            Failed(CEodeSetMaxNonlinIters(mem, p.max_nonlin_iters), "CEodeSetMaxNonlinIters"));
  }
  if (p.mass != nullptr) {
    o->M = SUNDenseMatrix(p.n, p.n, ctx);
    if (o->M == nullptr || Failed(CEodeSetMassFn(mem, p.mass, o->M, SUNTRUE), "CEodeSetMassFn")) {
      return true;
    }
  }
  if (p.nc == 0) return false;
  const int m = p.n + p.nc;  // the saddle-point system [[M, G^T], [G, 0]]
  o->phi = N_VNew_Serial(p.nc, ctx);
  o->b = N_VNew_Serial(m, ctx);
  if (o->phi == nullptr || o->b == nullptr) return true;
  if (p.saddle_nnz > 0) {
    o->A = SUNSparseMatrix(m, m, p.saddle_nnz, CSR_MAT, ctx);
    if (o->A != nullptr) o->LS = SUNLinSol_KLU(o->b, o->A, ctx);
  } else {
    o->A = SUNDenseMatrix(m, m, ctx);
    if (o->A != nullptr) o->LS = SUNLinSol_Dense(o->b, o->A, ctx);
  }
  return o->LS == nullptr ||
         Failed(CEodeSetLinearSolver(mem, o->LS, o->A), "CEodeSetLinearSolver") ||
         Failed(CEodeSetConstraints(mem, o->phi, p.phi, p.G), "CEodeSetConstraints");
}

inline int CeodeOnce(SUNContext ctx, const SecondOrder& p, const char* method, double h,
                     bool zero_start, Outcome* out) {
  CeodeObjects o(ctx, p.n);
  if (o.x == nullptr || o.v == nullptr || o.mem == nullptr) return 1;
  void* mem = o.mem;
  std::copy(p.x0.begin(), p.x0.end(), N_VGetArrayPointer(o.x));
  std::copy(p.v0.begin(), p.v0.end(), N_VGetArrayPointer(o.v));
  bool bad = Failed(CEodeInit(mem, p.f, p.t0, o.x, o.v), "CEodeInit") ||
             Failed(CEodeSetUserData(mem, p.user), "CEodeSetUserData") ||
             Failed(CEodeSetMethodByName(mem, method), "CEodeSetMethodByName") ||
             Failed(CEodeSetFixedStep(mem, h), "CEodeSetFixedStep") ||
             Failed(CEodeSetZeroStart(mem, zero_start ? SUNTRUE : SUNFALSE), "CEodeSetZeroStart") ||
             // Runs past a stability limit are part of the picture: let them blow up.
             Failed(CEodeSetStabilityGuard(mem, CE_GUARD_OFF, 0), "CEodeSetStabilityGuard") ||
             Failed(CEodeSetMaxNumSteps(mem, 100000000L), "CEodeSetMaxNumSteps") ||
             Failed(CEodeSetStopTime(mem, p.tend), "CEodeSetStopTime") || CeodeAttach(ctx, p, &o);
  double t = p.t0, emax = 0, dmax = 0;
  const double* xd = N_VGetArrayPointer(o.x);
  const double* vd = N_VGetArrayPointer(o.v);
  while (!bad && t < p.tend - 0.5 * h) {
    // One step at a time: x and x' are then known at the same instant.
    if (Failed(CEodeEvolve(mem, p.tend, o.x, o.v, &t, CE_ONE_STEP), "CEodeEvolve")) {
      bad = true;
      break;
    }
    const double e = p.err(t, xd, vd, p.user);
    if (!(e <= emax)) emax = e;  // also catches NaN
    const double d = p.drift != nullptr ? p.drift(t, xd, vd, p.user) : 0.0;
    if (!(d <= dmax)) dmax = d;
  }
  long nfe = 0, nfe_dq = 0;
  if (!bad) {
    bad = Failed(CEodeGetNumSteps(mem, &out->steps), "CEodeGetNumSteps") ||
          Failed(CEodeGetNumRhsEvals(mem, &nfe), "CEodeGetNumRhsEvals") ||
          Failed(CEodeGetNumRhsEvalsJacDQ(mem, &nfe_dq), "CEodeGetNumRhsEvalsJacDQ") ||
          Failed(CEodeGetNumJacEvals(mem, &out->jac_evals), "CEodeGetNumJacEvals") ||
          Failed(CEodeGetNumLinSolvSetups(mem, &out->lin_setups), "CEodeGetNumLinSolvSetups");
  }
  out->rhs_evals = nfe + nfe_dq;
  out->error = emax;
  out->drift = dmax;
  return bad || !std::isfinite(emax) ? 1 : 0;
}

// -------------------------------------------------- SUNDIALS (1st-order form)
enum class Sun { kErkFixed, kErkAdaptive, kCvodeAdams, kCvodeBdf, kArkDirk };

inline const char* SunName(Sun s) {
  switch (s) {
    case Sun::kErkFixed:
    case Sun::kErkAdaptive:
      return "ARKODE-ERK";
    case Sun::kCvodeAdams:
      return "CVODE-Adams";
    case Sun::kCvodeBdf:
      return "CVODE-BDF";
    case Sun::kArkDirk:
      return "ARKODE-DIRK";
  }
  return "?";
}

// Kutta's classic third-order method, the paper's "RK3" (docs/theory.md
// section 11), with the one workaround for SUNDIALS' FSAL rule: c3 is
// 1 - 1e-8, not 1. SUNDIALS before 6.7.0 (Debian's is 6.4.1) takes any ERKStep
// table with c_s = 1 to be first-same-as-last and reuses the last stage's f as
// the next step's first stage, which for Kutta's table (b != last row of A)
// silently runs a different method with 2 f calls per step. Measured: after 5
// steps of h = 0.1 on the pendulum ARKODE gave theta = -1.16642 against
// -1.16874 by hand. With c3 != 1 ARKODE evaluates f(t_n+1, y_n+1) properly (3
// calls per step, matching the hand-written method to the last digit); c only
// moves the time argument, so on autonomous problems this is exactly Kutta's
// method.
inline ARKodeButcherTable KuttaRk3() {
  sunrealtype c[3] = {0.0, 0.5, 1.0 - 1e-8};
  sunrealtype A[9] = {0.0, 0.0, 0.0, 0.5, 0.0, 0.0, -1.0, 2.0, 0.0};
  sunrealtype b[3] = {1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0};
  return ARKodeButcherTable_Create(3, 3, 0, c, A, b, nullptr);
}

// One integration with a SUNDIALS integrator in one-step mode. For kErkFixed,
// `h_or_rtol` is the step and `table` the Butcher table; otherwise it is the
// relative tolerance and atol = atol_factor * rtol.
inline int SundialsOnce(SUNContext ctx, const FirstOrder& p, Sun kind, double h_or_rtol,
                        double atol_factor, ARKodeButcherTable table, Outcome* out) {
  N_Vector y = N_VNew_Serial(p.n, ctx);
  if (y == nullptr) return 1;
  std::copy(p.y0.begin(), p.y0.end(), N_VGetArrayPointer(y));
  SUNMatrix A = nullptr;
  SUNLinearSolver LS = nullptr;
  SUNNonlinearSolver NLS = nullptr;
  void* mem = nullptr;
  const double rtol = h_or_rtol, atol = atol_factor * h_or_rtol;
  bool bad = false;
  const bool is_cvode = kind == Sun::kCvodeAdams || kind == Sun::kCvodeBdf;
  switch (kind) {
    case Sun::kErkFixed:
    case Sun::kErkAdaptive:
      mem = ERKStepCreate(p.f, p.t0, y, ctx);
      bad = mem == nullptr || Failed(ERKStepSetUserData(mem, p.user), "ERKStepSetUserData") ||
            Failed(ERKStepSetMaxNumSteps(mem, 100000000L), "ERKStepSetMaxNumSteps") ||
            Failed(ERKStepSetStopTime(mem, p.tend), "ERKStepSetStopTime") ||
            (p.post_step != nullptr &&
             Failed(ERKStepSetPostprocessStepFn(mem, p.post_step), "ERKStepSetPostprocessStepFn"));
      if (!bad && kind == Sun::kErkFixed) {
        bad = Failed(ERKStepSetTable(mem, table), "ERKStepSetTable") ||
              Failed(ERKStepSetFixedStep(mem, h_or_rtol), "ERKStepSetFixedStep");
      } else if (!bad) {
        bad = Failed(ERKStepSStolerances(mem, rtol, atol), "ERKStepSStolerances");
      }
      break;
    case Sun::kArkDirk:
      mem = ARKStepCreate(nullptr, p.f, p.t0, y, ctx);
      A = SUNDenseMatrix(p.n, p.n, ctx);
      LS = SUNLinSol_Dense(y, A, ctx);
      bad = mem == nullptr || A == nullptr || LS == nullptr ||
            Failed(ARKStepSetUserData(mem, p.user), "ARKStepSetUserData") ||
            Failed(ARKStepSetMaxNumSteps(mem, 100000000L), "ARKStepSetMaxNumSteps") ||
            Failed(ARKStepSetStopTime(mem, p.tend), "ARKStepSetStopTime") ||
            Failed(ARKStepSStolerances(mem, rtol, atol), "ARKStepSStolerances") ||
            Failed(ARKStepSetLinearSolver(mem, LS, A), "ARKStepSetLinearSolver");
      break;
    case Sun::kCvodeAdams:
    case Sun::kCvodeBdf:
      mem = CVodeCreate(kind == Sun::kCvodeAdams ? CV_ADAMS : CV_BDF, ctx);
      bad = mem == nullptr || Failed(CVodeInit(mem, p.f, p.t0, y), "CVodeInit") ||
            Failed(CVodeSetUserData(mem, p.user), "CVodeSetUserData") ||
            Failed(CVodeSetMaxNumSteps(mem, 100000000L), "CVodeSetMaxNumSteps") ||
            Failed(CVodeSetStopTime(mem, p.tend), "CVodeSetStopTime") ||
            Failed(CVodeSStolerances(mem, rtol, atol), "CVodeSStolerances");
      if (!bad && kind == Sun::kCvodeAdams) {
        // Adams is the non-stiff choice: functional (fixed-point) iteration.
        NLS = SUNNonlinSol_FixedPoint(y, 0, ctx);
        bad =
            NLS == nullptr || Failed(CVodeSetNonlinearSolver(mem, NLS), "CVodeSetNonlinearSolver");
      } else if (!bad) {
        A = SUNDenseMatrix(p.n, p.n, ctx);
        LS = SUNLinSol_Dense(y, A, ctx);
        bad = A == nullptr || LS == nullptr ||
              Failed(CVodeSetLinearSolver(mem, LS, A), "CVodeSetLinearSolver");
      }
      break;
  }
  double t = p.t0, emax = 0, dmax = 0;
  const double* yd = N_VGetArrayPointer(y);
  // Fixed steps end half a step before tend (as CeodeOnce), adaptive ones at tend.
  const double margin =
      kind == Sun::kErkFixed ? 0.5 * h_or_rtol : 1e-12 * std::max(1.0, std::fabs(p.tend));
  while (!bad && t < p.tend - margin) {
    int flag;
    if (is_cvode) {
      flag = CVode(mem, p.tend, y, &t, CV_ONE_STEP);
    } else if (kind == Sun::kArkDirk) {
      flag = ARKStepEvolve(mem, p.tend, y, &t, ARK_ONE_STEP);
    } else {
      flag = ERKStepEvolve(mem, p.tend, y, &t, ARK_ONE_STEP);
    }
    if (Failed(flag, "Evolve")) {
      bad = true;
      break;
    }
    const double e = p.err(t, yd, p.user);
    if (!(e <= emax)) emax = e;
    const double d = p.drift != nullptr ? p.drift(t, yd, p.user) : 0.0;
    if (!(d <= dmax)) dmax = d;
  }
  long nfe = 0, nfi = 0, nfe_ls = 0;
  if (!bad) {
    if (is_cvode) {
      bad = Failed(CVodeGetNumSteps(mem, &out->steps), "CVodeGetNumSteps") ||
            Failed(CVodeGetNumRhsEvals(mem, &nfe), "CVodeGetNumRhsEvals") ||
            (kind == Sun::kCvodeBdf &&
             Failed(CVodeGetNumLinRhsEvals(mem, &nfe_ls), "CVodeGetNumLinRhsEvals"));
    } else if (kind == Sun::kArkDirk) {
      bad = Failed(ARKStepGetNumSteps(mem, &out->steps), "ARKStepGetNumSteps") ||
            Failed(ARKStepGetNumRhsEvals(mem, &nfe, &nfi), "ARKStepGetNumRhsEvals") ||
            Failed(ARKStepGetNumLinRhsEvals(mem, &nfe_ls), "ARKStepGetNumLinRhsEvals");
    } else {
      bad = Failed(ERKStepGetNumSteps(mem, &out->steps), "ERKStepGetNumSteps") ||
            Failed(ERKStepGetNumRhsEvals(mem, &nfe), "ERKStepGetNumRhsEvals");
    }
  }
  out->rhs_evals = nfe + nfi + nfe_ls;
  out->error = emax;
  out->drift = dmax;
  if (is_cvode) {
    CVodeFree(&mem);
  } else if (kind == Sun::kArkDirk) {
    ARKStepFree(&mem);
  } else {
    ERKStepFree(&mem);
  }
  if (NLS != nullptr) SUNNonlinSolFree(NLS);
  if (LS != nullptr) SUNLinSolFree(LS);
  if (A != nullptr) SUNMatDestroy(A);
  N_VDestroy(y);
  return bad || !std::isfinite(emax) ? 1 : 0;
}

// ------------------------------------------------------------------------ IDA
// One integration of a residual form with IDA (variable-order BDF, dense
// iteration matrix) in one-step mode at rtol = atol = tol.
inline int IdaOnce(SUNContext ctx, const Residual& p, double tol, Outcome* out) {
  N_Vector yy = N_VNew_Serial(p.n, ctx), yp = N_VNew_Serial(p.n, ctx);
  N_Vector id = N_VNew_Serial(p.n, ctx);
  SUNMatrix J = SUNDenseMatrix(p.n, p.n, ctx);
  SUNLinearSolver LS = yy != nullptr && J != nullptr ? SUNLinSol_Dense(yy, J, ctx) : nullptr;
  void* mem = IDACreate(ctx);
  bool bad = yp == nullptr || id == nullptr || LS == nullptr || mem == nullptr;
  if (!bad) {
    std::copy(p.y0.begin(), p.y0.end(), N_VGetArrayPointer(yy));
    std::copy(p.yp0.begin(), p.yp0.end(), N_VGetArrayPointer(yp));
    std::copy(p.id.begin(), p.id.end(), N_VGetArrayPointer(id));
    bad = Failed(IDAInit(mem, p.res, p.t0, yy, yp), "IDAInit") ||
          Failed(IDASetUserData(mem, p.user), "IDASetUserData") ||
          Failed(IDASStolerances(mem, tol, tol), "IDASStolerances") ||
          Failed(IDASetId(mem, id), "IDASetId") ||
          Failed(IDASetSuppressAlg(mem, SUNTRUE), "IDASetSuppressAlg") ||
          Failed(IDASetStopTime(mem, p.tend), "IDASetStopTime") ||
          Failed(IDASetMaxNumSteps(mem, 100000000L), "IDASetMaxNumSteps") ||
          (p.init_step > 0 && Failed(IDASetInitStep(mem, p.init_step), "IDASetInitStep")) ||
          Failed(IDASetLinearSolver(mem, LS, J), "IDASetLinearSolver") ||
          (p.jac != nullptr && Failed(IDASetJacFn(mem, p.jac), "IDASetJacFn"));
  }
  double t = p.t0, emax = 0, dmax = 0;
  const double* Y = bad ? nullptr : N_VGetArrayPointer(yy);
  while (!bad && t < p.tend) {
    const int flag = IDASolve(mem, p.tend, &t, yy, yp, IDA_ONE_STEP);
    if (Failed(flag, "IDASolve")) {
      bad = true;
      break;
    }
    const double e = p.err(t, Y, p.user);
    if (!(e <= emax)) emax = e;
    const double d = p.drift != nullptr ? p.drift(t, Y, p.user) : 0.0;
    if (!(d <= dmax)) dmax = d;
    if (flag == IDA_TSTOP_RETURN) break;
  }
  long nre = 0, nre_ls = 0;
  bad = bad || Failed(IDAGetNumSteps(mem, &out->steps), "IDAGetNumSteps") ||
        Failed(IDAGetNumResEvals(mem, &nre), "IDAGetNumResEvals") ||
        Failed(IDAGetNumLinResEvals(mem, &nre_ls), "IDAGetNumLinResEvals");
  out->rhs_evals = nre + nre_ls;
  out->error = emax;
  out->drift = dmax;
  IDAFree(&mem);
  if (LS != nullptr) SUNLinSolFree(LS);
  if (J != nullptr) SUNMatDestroy(J);
  for (N_Vector w : {yy, yp, id}) {
    if (w != nullptr) N_VDestroy(w);
  }
  return bad || !std::isfinite(emax) ? 1 : 0;
}

// ------------------------------------------------------- measured + timed rows
// The row of one configuration: its numbers from an Outcome, its time per run.
inline Row OutcomeRow(const std::string& solver, const std::string& config, double h_or_tol,
                      const Outcome& o, double seconds) {
  Row r;
  r.solver = solver;
  r.config = config;
  r.h_or_tol = h_or_tol;
  r.error = o.error;
  r.drift = o.drift;
  r.steps = o.steps;
  r.rhs_evals = o.rhs_evals;
  r.seconds = seconds;
  return r;
}

// Runs once for the numbers, then times the same call; adds a row or a failure.
// Returns true when the row was added; *got (if given) receives the figures.
template <class F>
bool Measure(Table* table, const std::string& solver, const std::string& config, double h_or_tol,
             F&& once, Outcome* got = nullptr) {
  Outcome o;
  if (once(&o) != 0) {
    table->Fail(solver, config, h_or_tol, "failed or unstable");
    return false;
  }
  Outcome scratch;
  const double secs = TimeMedian([&]() { return once(&scratch); });
  if (secs < 0) {
    table->Fail(solver, config, h_or_tol, "failed while timing");
    return false;
  }
  table->Add(OutcomeRow(solver, config, h_or_tol, o, secs));
  if (got != nullptr) *got = o;
  return true;
}

// Measure's interleaved form, for the scenes whose equal-error ratios are judged (the FE
// scenes, issue 11). Timing the configurations one after the other puts a burst of load on
// this shared machine on one solver's curve; here every configuration is first run once for
// its numbers (and to plan its repetitions, as TimeMedian does), then Run() times repetition r
// of every configuration in round r, in a shuffled order, and each one's median over the rounds
// is its time. The rows are added by Run(), in the order the configurations were queued.
class Rounds {
 public:
  explicit Rounds(Table* table) : table_(table) {}
  Rounds(const Rounds&) = delete;
  Rounds& operator=(const Rounds&) = delete;

  // The numbers run; `once` is kept for the rounds, so nothing it captures by reference may end
  // with the caller's scope. Returns that run's seconds (< 0: it failed, a failure row).
  double Measure(const std::string& solver, const std::string& config, double h_or_tol,
                 std::function<int(Outcome*)> once, Outcome* got = nullptr) {
    Outcome o;
    const double t0 = Now();
    if (once(&o) != 0) {
      table_->Fail(solver, config, h_or_tol, "failed or unstable");
      return -1;
    }
    const double first = Now() - t0;
    Entry e;
    e.row = OutcomeRow(solver, config, h_or_tol, o, first);
    e.plan = PlanReps(first);
    e.once = std::move(once);
    entries_.push_back(std::move(e));
    if (got != nullptr) *got = o;
    return first;
  }

  void Run() {
    int rounds = 0;
    for (const Entry& e : entries_) rounds = std::max(rounds, e.plan.reps);
    std::vector<size_t> order(entries_.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::mt19937 rng(20261203u);  // a fixed seed: the same schedule on every run
    for (int r = 0; r < rounds; ++r) {
      std::shuffle(order.begin(), order.end(), rng);
      for (size_t i : order) TimeOne(&entries_[i], r);
    }
    for (Entry& e : entries_) {
      if (e.failed) {
        table_->Fail(e.row.solver, e.row.config, e.row.h_or_tol, "failed while timing");
        continue;
      }
      if (e.plan.reps > 0) e.row.seconds = MedianOf(e.per_call);
      table_->Add(e.row);
    }
    entries_.clear();
  }

 private:
  struct Entry {
    Row row;
    RepPlan plan;
    std::function<int(Outcome*)> once;
    std::vector<double> per_call;
    bool failed = false;
  };

  static void TimeOne(Entry* e, int round) {
    if (e->failed || round >= e->plan.reps) return;
    Outcome scratch;
    const double t = TimeRep([&]() { return e->once(&scratch); }, e->plan.calls);
    if (t < 0) e->failed = true;
    e->per_call.push_back(t);
  }

  Table* table_;
  std::vector<Entry> entries_;
};

inline bool MeasureCeode(Table* table, SUNContext ctx, const SecondOrder& p, const char* method,
                         double h, bool zero_start, const std::string& config,
                         Outcome* got = nullptr) {
  return Measure(
      table, "CEODE", config, h,
      [&](Outcome* o) { return CeodeOnce(ctx, p, method, h, zero_start, o); }, got);
}

// The constrained step's iteration-matrix reuse (issue 10's criterion: Jacobian evaluations at
// most steps/10): evaluations of the saddle-point matrix's Jacobian (G(x), or df/dv when f depends
// on v) and factorisations per step. Printed, not checked: at the coarsest steps the stale matrix
// contracts too slowly and is refreshed more often (test_constraints checks h = 1e-3).
inline void PrintMatrixReuse(const std::string& config, double h, const Outcome& o) {
  const double per_step = o.steps > 0 ? static_cast<double>(o.jac_evals) / o.steps : 0.0;
  std::printf("  matrix reuse %s h = %g: %ld Jacobian evals, %ld setups, %ld steps (%.4f/step)%s\n",
              config.c_str(), h, o.jac_evals, o.lin_setups, o.steps, per_step,
              10 * o.jac_evals <= o.steps ? "" : "  (above steps/10)");
}

inline bool MeasureSundials(Table* table, SUNContext ctx, const FirstOrder& p, Sun kind,
                            double h_or_rtol, double atol_factor, ARKodeButcherTable tab,
                            const std::string& config, const char* solver = nullptr,
                            Outcome* got = nullptr) {
  return Measure(
      table, solver != nullptr ? solver : SunName(kind), config, h_or_rtol,
      [&](Outcome* o) { return SundialsOnce(ctx, p, kind, h_or_rtol, atol_factor, tab, o); }, got);
}

inline bool MeasureIda(Table* table, SUNContext ctx, const Residual& p, double tol,
                       const std::string& config, Outcome* got = nullptr) {
  return Measure(
      table, "IDA", config, tol, [&](Outcome* o) { return IdaOnce(ctx, p, tol, o); }, got);
}

}  // namespace wp

#endif  // CEODE_BENCH_WP_COMMON_H_
