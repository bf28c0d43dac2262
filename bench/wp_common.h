// -----------------------------------------------------------------------------
// wp_common.h: shared pieces of the work-precision scenes (bench/wp_*.cpp).
//
//  * Timing: every configuration is run back to back until one repetition has
//    lasted >= 50 ms, and the per-run time is the median of >= 5 repetitions.
//    Each timed run is the whole user-visible cost: create, init, integrate in
//    one-step mode with the error measured after every step, free. The clock
//    is the process CPU time (see Now).
//  * Rows in the common CSV schema
//      scene,solver,config,h_or_tol,error,drift,steps,rhs_evals,seconds
//    printed as a table while the scene runs.
//  * Runners for CEODE (second-order form) and for ARKODE ERKStep (fixed Butcher
//    table or adaptive), ARKODE ARKStep DIRK and CVODE (Adams / BDF) on the
//    equivalent first-order system, so that every solver of a scene is driven,
//    observed and timed the same way in the same process.
// -----------------------------------------------------------------------------
#ifndef CEODE_BENCH_WP_COMMON_H_
#define CEODE_BENCH_WP_COMMON_H_

#include <arkode/arkode_arkstep.h>
#include <arkode/arkode_butcher.h>
#include <arkode/arkode_erkstep.h>
#include <ceode/ceode.h>
#include <cvode/cvode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

#include "ceode_sundials_compat.h"  // SUN_COMM_NULL on SUNDIALS 6.4

namespace wp {

// ---------------------------------------------------------------- arguments
struct Args {
  std::string csv;     // --csv FILE: where the rows go (none: table only)
  bool quick = false;  // --quick: fewer configurations, for smoke tests
};

inline Args ParseArgs(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--csv") == 0 && i + 1 < argc) {
      a.csv = argv[++i];
    } else if (std::strcmp(argv[i], "--quick") == 0) {
      a.quick = true;
    } else {
      std::fprintf(stderr, "usage: %s [--csv FILE] [--quick]\n", argv[0]);
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

// Median seconds of one call of run(), which returns 0 on success. The first
// call calibrates how many calls fill 50 ms (it also warms caches and the
// allocator, so it is not counted). Returns < 0 if any call failed.
template <class F>
double TimeMedian(F&& run) {
  double t0 = Now();
  if (run() != 0) return -1;
  const double first = Now() - t0;
  const long calls =
      first >= kMinRepSeconds ? 1 : static_cast<long>(std::ceil(kMinRepSeconds / first));
  std::vector<double> per_call;
  for (int r = 0; r < kReps; ++r) {
    t0 = Now();
    for (long c = 0; c < calls; ++c) {
      if (run() != 0) return -1;
    }
    per_call.push_back((Now() - t0) / static_cast<double>(calls));
  }
  std::sort(per_call.begin(), per_call.end());
  return per_call[per_call.size() / 2];
}

// --------------------------------------------------------------------- rows
struct Row {
  std::string solver, config;
  double h_or_tol = 0, error = 0, drift = 0;
  long steps = 0, rhs_evals = 0;
  double seconds = 0;
};

class Table {
 public:
  Table(const std::string& scene, const std::string& csv_path) : scene_(scene) {
    if (!csv_path.empty()) {
      csv_ = std::fopen(csv_path.c_str(), "w");
      if (csv_ == nullptr) {
        std::fprintf(stderr, "ERROR: cannot write %s\n", csv_path.c_str());
        std::exit(1);
      }
      std::fprintf(csv_, "scene,solver,config,h_or_tol,error,drift,steps,rhs_evals,seconds\n");
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
    if (csv_ != nullptr) {
      std::fprintf(csv_, "%s,%s,%s,%.6g,%.6e,%.6e,%ld,%ld,%.6e\n", scene_.c_str(), r.solver.c_str(),
                   r.config.c_str(), r.h_or_tol, r.error, r.drift, r.steps, r.rhs_evals, r.seconds);
      std::fflush(csv_);
    }
  }
  void Fail(const std::string& solver, const std::string& config, double h_or_tol,
            const char* why) {
    std::printf("%-16s %-14s %9.2e   (%s)\n", solver.c_str(), config.c_str(), h_or_tol, why);
    ++nfail_;
  }
  int failures() const { return nfail_; }

 private:
  std::string scene_;
  FILE* csv_ = nullptr;
  int nfail_ = 0;
};

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
};

struct SecondOrder {
  int n = 0;  // length of x
  CEodeRhsFn f = nullptr;
  void* user = nullptr;
  double t0 = 0, tend = 0;
  std::vector<double> x0, v0;
  ErrFn2 err = nullptr;
  bool vel_dependent = false;
  CEodeVelJacFn vjac = nullptr;  // nullptr: CEODE's difference quotients
  int max_nonlin_iters = 0;      // 0: CEODE's default
};

// One integration's outcome (the timing is added by TimeMedian).
struct Outcome {
  double error = 0;
  long steps = 0, rhs_evals = 0;
};

// ----------------------------------------------------------- CEODE (2nd order)
inline int CeodeOnce(SUNContext ctx, const SecondOrder& p, const char* method, double h,
                     bool zero_start, Outcome* out) {
  N_Vector x = N_VNew_Serial(p.n, ctx);
  N_Vector v = N_VNew_Serial(p.n, ctx);
  SUNMatrix A = nullptr;
  SUNLinearSolver LS = nullptr;
  void* mem = CEodeCreate(ctx);
  if (x == nullptr || v == nullptr || mem == nullptr) return 1;
  std::copy(p.x0.begin(), p.x0.end(), N_VGetArrayPointer(x));
  std::copy(p.v0.begin(), p.v0.end(), N_VGetArrayPointer(v));
  bool bad = Failed(CEodeInit(mem, p.f, p.t0, x, v), "CEodeInit") ||
             Failed(CEodeSetUserData(mem, p.user), "CEodeSetUserData") ||
             Failed(CEodeSetMethodByName(mem, method), "CEodeSetMethodByName") ||
             Failed(CEodeSetFixedStep(mem, h), "CEodeSetFixedStep") ||
             Failed(CEodeSetZeroStart(mem, zero_start ? SUNTRUE : SUNFALSE), "CEodeSetZeroStart") ||
             // Runs past a stability limit are part of the picture: let them blow up.
             Failed(CEodeSetStabilityGuard(mem, CE_GUARD_OFF, 0), "CEodeSetStabilityGuard") ||
             Failed(CEodeSetMaxNumSteps(mem, 100000000L), "CEodeSetMaxNumSteps") ||
             Failed(CEodeSetStopTime(mem, p.tend), "CEodeSetStopTime");
  if (!bad && p.vel_dependent) {
    A = SUNDenseMatrix(p.n, p.n, ctx);
    LS = SUNLinSol_Dense(x, A, ctx);
    bad = A == nullptr || LS == nullptr ||
          Failed(CEodeSetVelocityDependence(mem, SUNTRUE), "CEodeSetVelocityDependence") ||
          Failed(CEodeSetLinearSolver(mem, LS, A), "CEodeSetLinearSolver") ||
          (p.vjac != nullptr && Failed(CEodeSetVelJacFn(mem, p.vjac), "CEodeSetVelJacFn")) ||
          (p.max_nonlin_iters > 0 &&
           Failed(CEodeSetMaxNonlinIters(mem, p.max_nonlin_iters), "CEodeSetMaxNonlinIters"));
  }
  double t = p.t0, emax = 0;
  const double* xd = N_VGetArrayPointer(x);
  const double* vd = N_VGetArrayPointer(v);
  while (!bad && t < p.tend - 0.5 * h) {
    // One step at a time: x and x' are then known at the same instant.
    if (Failed(CEodeEvolve(mem, p.tend, x, v, &t, CE_ONE_STEP), "CEodeEvolve")) {
      bad = true;
      break;
    }
    const double e = p.err(t, xd, vd, p.user);
    if (!(e <= emax)) emax = e;  // also catches NaN
  }
  long nfe = 0, nfe_dq = 0;
  if (!bad) {
    bad = Failed(CEodeGetNumSteps(mem, &out->steps), "CEodeGetNumSteps") ||
          Failed(CEodeGetNumRhsEvals(mem, &nfe), "CEodeGetNumRhsEvals") ||
          Failed(CEodeGetNumRhsEvalsJacDQ(mem, &nfe_dq), "CEodeGetNumRhsEvalsJacDQ");
  }
  out->rhs_evals = nfe + nfe_dq;
  out->error = emax;
  CEodeFree(&mem);
  if (LS != nullptr) SUNLinSolFree(LS);
  if (A != nullptr) SUNMatDestroy(A);
  N_VDestroy(x);
  N_VDestroy(v);
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

// Kutta's classic third-order method, the paper's "RK3" (method.md section 7).
// c3 is 1 - 1e-8, not 1: SUNDIALS 6.4.1's ERKStep takes any table with
// c_s = 1 to be first-same-as-last and reuses the last stage's f as the next
// step's first stage, which for Kutta's table (b != last row of A) silently
// runs a different method with 2 f calls per step. Measured: after 5 steps of
// h = 0.1 on the pendulum ARKODE gave theta = -1.16642 against -1.16874 by
// hand. With c3 != 1 ARKODE evaluates f(t_n+1, y_n+1) properly (3 calls per
// step, matching the hand-written method to the last digit); c only moves the
// time argument, so on autonomous problems this is exactly Kutta's method.
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
            Failed(ERKStepSetStopTime(mem, p.tend), "ERKStepSetStopTime");
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
  double t = p.t0, emax = 0;
  const double* yd = N_VGetArrayPointer(y);
  const double tiny = 1e-12 * std::max(1.0, std::fabs(p.tend));
  while (!bad && t < p.tend - tiny) {
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

// ------------------------------------------------------- measured + timed rows
// Runs once for the numbers, then times the same call; adds a row or a failure.
template <class F>
void Measure(Table* table, const std::string& solver, const std::string& config, double h_or_tol,
             F&& once) {
  Outcome o;
  if (once(&o) != 0) {
    table->Fail(solver, config, h_or_tol, "failed or unstable");
    return;
  }
  Outcome scratch;
  const double secs = TimeMedian([&]() { return once(&scratch); });
  if (secs < 0) {
    table->Fail(solver, config, h_or_tol, "failed while timing");
    return;
  }
  Row r;
  r.solver = solver;
  r.config = config;
  r.h_or_tol = h_or_tol;
  r.error = o.error;
  r.steps = o.steps;
  r.rhs_evals = o.rhs_evals;
  r.seconds = secs;
  table->Add(r);
}

inline void MeasureCeode(Table* table, SUNContext ctx, const SecondOrder& p, const char* method,
                         double h, bool zero_start, const std::string& config) {
  Measure(table, "CEODE", config, h,
          [&](Outcome* o) { return CeodeOnce(ctx, p, method, h, zero_start, o); });
}

inline void MeasureSundials(Table* table, SUNContext ctx, const FirstOrder& p, Sun kind,
                            double h_or_rtol, double atol_factor, ARKodeButcherTable tab,
                            const std::string& config) {
  Measure(table, SunName(kind), config, h_or_rtol,
          [&](Outcome* o) { return SundialsOnce(ctx, p, kind, h_or_rtol, atol_factor, tab, o); });
}

}  // namespace wp

#endif  // CEODE_BENCH_WP_COMMON_H_
