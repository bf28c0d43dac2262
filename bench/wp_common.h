// -----------------------------------------------------------------------------
// wp_common.h: the harness of the work-precision scenes (bench/*/wp_*.cpp).
//
//  * One problem description (Problem): a second-order problem x'' = a(t, x, x') written once,
//    with its start, error and drift functions; Lift<A>() derives CEODE's right-hand side and the
//    first-order form y = (x, x') of ARKODE, CVODE and the peers (bench/peers.h), and a DAE
//    scene adds its residual form for IDA.
//  * One runner family: CeodeRun (second-order form, optionally a mass matrix, index-3
//    constraints, the implicit step; fixed steps or error control), SundialsRun (ARKODE ERKStep
//    with a fixed Butcher table or adaptive, ARKStep DIRK / IMEX, CVODE Adams / BDF with a dense,
//    SPGMR or KLU solver), IdaRun (residual form), each in one of three modes: one step at a time
//    with the error measured after every step, or (Problem::nout > 0) to nout output instants in
//    the normal mode, or (Problem::end_only) to the end time in one normal-mode call. Every solver
//    of a scene is driven, observed and timed the same way in the same process. HandG8Run is
//    the same method's floor: G8_O8 at fixed steps written out by hand (hand_step.h), started by
//    CEODE, in the one-step and end modes.
//  * Timing: every configuration is run back to back until one repetition has lasted >= 50 ms,
//    and the per-run time is the median of 5 repetitions (3 for runs of >= 0.5 s; a run of
//    >= 2 s is its own measurement), either configuration by configuration (Measure) or in
//    interleaved rounds (Rounds). A timed run is the whole user-visible cost: create, init,
//    integrate, free. The clock is the process CPU time (Now).
//  * Rows in the common CSV schema
//      scene,solver,config,h_or_tol,error,drift,steps,rhs_evals,seconds
//    printed as a table while the scene runs, and one equal-error rule (TimeAtError, the
//    cheapest time at which a curve reaches a given error, as scripts/wp_curves.py computes it).
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
#include <sunlinsol/sunlinsol_spgmr.h>
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
#include <memory>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "ceode_sundials_compat.h"  // SUN_COMM_NULL on SUNDIALS 6.4
#include "hand_step.h"              // the hand loop of G8_O8

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
// CPU time of this (single-threaded) process: on an idle machine it equals the wall time; on a
// shared one it is not inflated by waiting for a core, so solvers timed minutes apart stay
// comparable.
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
// Long runs are far past every equal-error comparison (the FE scenes' implicit SUNDIALS curves
// take seconds a point): a run of >= kFewRepSeconds is repeated 3 times, one of
// >= kOneRunSeconds is measured once.
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
  // A run that ended with the solver's own failure flag (an adaptive run that gives up at a
  // tolerance, say): a result to show, not a failed check.
  void Flagged(const std::string& solver, const std::string& config, double h_or_tol,
               const char* flag_name) {
    std::printf("%-16s %-14s %9.2e   (returned %s: a result, not a failed check)\n", solver.c_str(),
                config.c_str(), h_or_tol, flag_name);
    ++nflagged_;
  }
  int failures() const { return nfail_; }
  int flagged() const { return nflagged_; }
  const std::vector<Row>& rows() const { return rows_; }

 private:
  std::string scene_;
  std::vector<Row> rows_;
  FILE* csv_ = nullptr;
  int nfail_ = 0;
  int nflagged_ = 0;
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

// The integrators users pick outside SUNDIALS (bench/peers.h writes these solver names).
inline bool IsPeerSolver(const std::string& solver) {
  return solver == "odeint" || solver == "GSL";
}

// The side of a curve in the equal-error table: 0 CEODE, 1 SUNDIALS, 2 hand loop, 3 peer.
inline int SideOf(const std::string& solver) {
  return solver == "CEODE" ? 0 : solver == "CEODE-hand" ? 2 : IsPeerSolver(solver) ? 3 : 1;
}

// Prints, at each error level, the best curve of each side present in the table (CEODE,
// SUNDIALS, the hand loop, the peers) and CEODE's time ratio to each (< 1: CEODE faster).
inline void PrintEqualError(const Table& table, const std::vector<double>& levels) {
  static const char* const kSide[4] = {"CEODE", "SUNDIALS", "hand", "peer"};
  std::vector<std::pair<std::string, std::string>> curves;
  bool present[4] = {false, false, false, false};
  for (const Row& r : table.rows()) {
    const auto key = std::make_pair(r.solver, r.config);
    if (std::find(curves.begin(), curves.end(), key) == curves.end()) curves.push_back(key);
    present[SideOf(r.solver)] = true;
  }
  std::printf("\ntime at equal error (best curve per side; ratio CEODE / side):\n%9s", "error");
  for (int s = 0; s < 4; ++s) {
    if (present[s])
      std::printf(" %-30s %11s%s", (std::string("best ") + kSide[s]).c_str(), "seconds",
                  s > 0 ? "    ratio" : "");
  }
  std::printf("\n");
  for (double e : levels) {
    double best[4] = {-1, -1, -1, -1};
    std::string name[4] = {"not reached", "not reached", "not reached", "not reached"};
    for (const auto& k : curves) {
      const int s = SideOf(k.first);
      const double t = TimeAtError(table.rows(), k.first, k.second, e);
      if (t > 0 && (best[s] < 0 || t < best[s])) best[s] = t, name[s] = k.first + " " + k.second;
    }
    if (best[0] < 0 && best[1] < 0 && best[2] < 0 && best[3] < 0) continue;
    std::printf("%9.0e", e);
    for (int s = 0; s < 4; ++s) {
      if (!present[s]) continue;
      std::printf(" %-30s %11.3e", name[s].c_str(), best[s]);
      if (s > 0) std::printf(" %8.3f", best[0] > 0 && best[s] > 0 ? best[0] / best[s] : 0.0);
    }
    std::printf("\n");
  }
}

// f evaluations at which one curve reaches error <= e: TimeAtError's rule on rhs_evals.
inline double EvalsAtError(const std::vector<Row>& rows, const std::string& solver,
                           const std::string& config, double e) {
  std::vector<Row> f;
  for (const Row& r : rows) {
    if (r.solver != solver || r.config != config) continue;
    f.push_back(r);
    f.back().seconds = static_cast<double>(r.rhs_evals);
  }
  return TimeAtError(f, solver, config, e);
}

inline bool IsCeodeAdaptive(const std::string& solver, const std::string& config) {
  return solver == "CEODE" && config.find("adaptive") != std::string::npos;
}

// CEODE's error control at equal error. At each level: every CEODE adaptive curve's f
// evaluations and CPU seconds, then the fastest of them against CEODE's fastest fixed-step curve
// and against every curve of another solver, as ratios CEODE adaptive / curve (< 1: CEODE
// adaptive cheaper). f and seconds by TimeAtError's rule; '-': the curve does not reach it.
inline void PrintAdaptiveEqualError(const Table& table, const std::vector<double>& levels) {
  const std::vector<Row>& rows = table.rows();
  std::vector<std::pair<std::string, std::string>> curves;
  for (const Row& r : rows) {
    const auto key = std::make_pair(r.solver, r.config);
    if (std::find(curves.begin(), curves.end(), key) == curves.end()) curves.push_back(key);
  }
  std::printf(
      "\nCEODE adaptive at equal error (f evaluations and CPU seconds per run, each the cheapest "
      "of its curve at that error by TimeAtError's rule; ratios: the fastest CEODE adaptive curve "
      "/ the curve, < 1: CEODE adaptive cheaper):\n");
  for (double e : levels) {
    const std::pair<std::string, std::string>* best = nullptr;
    const std::pair<std::string, std::string>* fixed = nullptr;
    double tb = -1, tf = -1;
    for (const auto& k : curves) {
      const double t = TimeAtError(rows, k.first, k.second, e);
      if (!(t > 0) || k.first != "CEODE") continue;
      if (IsCeodeAdaptive(k.first, k.second)) {
        if (tb < 0 || t < tb) tb = t, best = &k;
      } else if (tf < 0 || t < tf) {
        tf = t, fixed = &k;
      }
    }
    std::printf("error %.0e:", e);
    if (best == nullptr) {
      std::printf(" no CEODE adaptive curve reaches it\n");
      continue;
    }
    const double fb = EvalsAtError(rows, best->first, best->second, e);
    std::printf(" fastest CEODE adaptive: %s, %.0f f, %.3e s\n", best->second.c_str(), fb, tb);
    std::printf("  %-44s %10s %11s %8s %8s\n", "curve", "f", "seconds", "f ratio", "t ratio");
    std::string missed;
    for (const auto& k : curves) {
      const bool adaptive = IsCeodeAdaptive(k.first, k.second);
      if (&k == best || (k.first == "CEODE" && !adaptive && &k != fixed)) continue;
      std::string name = k.first + " " + k.second;
      const double f = EvalsAtError(rows, k.first, k.second, e);
      const double t = TimeAtError(rows, k.first, k.second, e);
      if (!(t > 0)) {
        missed += (missed.empty() ? "" : ", ") + name;
        continue;
      }
      if (&k == fixed) name += " (fastest fixed)";
      const char* verdict = tb <= t ? "CEODE adaptive faster" : "CEODE adaptive SLOWER";
      std::printf("  %-44s %10.0f %11.3e %8.3f %8.3f  %s\n", name.c_str(), f, t, fb / f, tb / t,
                  adaptive ? "" : verdict);
    }
    if (!missed.empty()) std::printf("  not reached: %s\n", missed.c_str());
  }
}

// Observed order of one fixed-step curve from its last three rows (h_or_tol is the step).
inline double CurveOrder(const Table& table, const std::string& solver, const std::string& config) {
  std::vector<const Row*> c;
  for (const Row& r : table.rows()) {
    if (r.solver == solver && r.config == config) c.push_back(&r);
  }
  if (c.size() < 2) return 0;
  const Row* a = c.size() >= 3 ? c[c.size() - 3] : c[0];
  return std::log(a->error / c.back()->error) / std::log(a->h_or_tol / c.back()->h_or_tol);
}

// The rows of two curves at the same steps agree (one method written twice); returns mismatches.
inline int CheckSameMethod(const Table& table, const std::string& s1, const std::string& c1,
                           const std::string& s2, const std::string& c2, double rel) {
  std::vector<const Row*> a, b;
  for (const Row& r : table.rows()) {
    if (r.solver == s1 && r.config == c1) a.push_back(&r);
    if (r.solver == s2 && r.config == c2) b.push_back(&r);
  }
  int bad = 0;
  for (size_t i = 0; i < a.size() && i < b.size(); ++i) {
    if (std::fabs(a[i]->error - b[i]->error) <= rel * a[i]->error + 1e-14) continue;
    std::printf("%s %s vs %s %s at h = %.4e: error %.6e vs %.6e -- MISMATCH\n", s1.c_str(),
                c1.c_str(), s2.c_str(), c2.c_str(), a[i]->h_or_tol, a[i]->error, b[i]->error);
    ++bad;
  }
  return bad;
}

// ------------------------------------------------------- the problem description
// One second-order problem x'' = a(t, x, x') (a force when a mass matrix is given), written once
// on raw doubles. Lift<A>() derives CEODE's right-hand side and the first-order form
// y = (x, x'), y' = (x', a) of ARKODE, CVODE and the peers; a scene with another formulation of
// the same model (an index-1 DAE, an IMEX split) sets those forms itself.
using AccFn = int (*)(double t, const double* x, const double* v, double* a, void* user);
// Error or constraint drift of the state at one instant; runners keep the maximum.
using ErrFn = double (*)(double t, const double* x, const double* v, void* user);
using Vec = std::vector<double>;

template <AccFn A>
int CeodeRhs(sunrealtype t, N_Vector x, N_Vector v, N_Vector a, void* user) {
  return A(t, N_VGetArrayPointer(x), N_VGetArrayPointer(v), N_VGetArrayPointer(a), user);
}

template <AccFn A>
int FirstOrderRhs(sunrealtype t, N_Vector y, N_Vector yd, void* user) {
  const sunindextype n = N_VGetLength(y) / 2;
  const double* Y = N_VGetArrayPointer(y);
  double* D = N_VGetArrayPointer(yd);
  std::copy(Y + n, Y + 2 * n, D);
  return A(t, Y, Y + n, D + n, user);
}

struct Problem {
  int n = 0;  // length of x
  AccFn acc = nullptr;
  void* user = nullptr;
  double t0 = 0, tend = 0;
  Vec x0, v0;
  ErrFn err = nullptr;
  ErrFn drift = nullptr;  // constraint drift (nullptr: not tracked)

  // -- the lifted forms (Lift) --
  CEodeRhsFn f2 = nullptr;  // CEODE
  ARKRhsFn f1 = nullptr;    // y' = (v, a) on y = (x, v)
  // -- the first-order form's extras --
  ARKRhsFn fe = nullptr, fi = nullptr;        // IMEX split of f1 (fi stiff, implicit)
  bool fi_linear = false, f1_linear = false;  // ARKStepSetLinear
  CVLsJacFn jac1 = nullptr;                   // CSR Jacobian of f1 (CVODE BDF + KLU)
  long jac_nnz = 0;
  // ERKStep: called on y after every step (e.g. a projection onto the constraints).
  ARKPostProcessFn post_step = nullptr;
  // -- CEODE's extras --
  CEodeVelJacFn vjac = nullptr;  // df/dv (nullptr: difference quotients)
  Vec vel_diag;                  // df/dv's constant diagonal where f is affine in v (or empty)
  long vjac_nnz = 0;             // nonzeros of df/dv in CSR (CeodeOpts::kKlu)
  CEodeMassFn mass = nullptr;    // constant mass matrix (nullptr: M = I)
  Vec lumped_mass;               // the guard's inner product (CEodeSetGuardMass)
  // Index-3 constraints Phi(x) = 0 (nc of them, Jacobian G); the saddle-point matrix
  // [[M, G^T], [G, 0]] dense (saddle_nnz = 0) or CSR with saddle_nnz entries, factored by KLU.
  int nc = 0;
  CEodeConstrFn phi = nullptr;
  CEodeConstrJacFn G = nullptr;
  long saddle_nnz = 0;
  // -- the residual form F(t, y, y') = 0 of IDA (a DAE scene's own formulation): a consistent
  // (y0, yp0), id 1 on the differential components; y starts with x and v as in f1. --
  int ny = 0;
  IDAResFn res = nullptr;
  IDALsJacFn res_jac = nullptr;  // dense iteration matrix (nullptr: difference quotients)
  // The first step of IDA and of CEODE's error control (0: the solver's own estimate). With
  // constraints CEODE's estimate comes from x and v alone: from rest a tenth of the interval,
  // where the constrained start's Newton iteration fails (CE_CONV_FAILURE at t0).
  double init_step = 0;
  Vec y0, yp0, id;
  // -- the peers --
  bool separable = false;  // a depends on x only (not t, not v: v may be nullptr)
  double h0 = 1e-3;        // first trial step of the adaptive peers
  // -- output mode: nout > 0 integrates to the nout instants t0 + (tend - t0) k / nout in each
  // solver's normal mode, error ||x - ref[k-1]||_2 / x0norm there (else one step at a time with
  // err after every step) --
  int nout = 0;
  std::vector<Vec> ref;
  double x0norm = 1;
  // -- end mode (nout = 0): err counts at tend alone, so CEODE and SUNDIALS integrate to tend in
  // one normal-mode call (stop time tend) and err is taken there, as a user who wants the final
  // state drives them; the peers step on as their own drivers do --
  bool end_only = false;

  template <AccFn A>
  void Lift() {
    acc = A;
    f2 = CeodeRhs<A>;
    f1 = FirstOrderRhs<A>;
  }
  std::vector<double> FirstOrderStart() const {
    Vec y(x0);
    y.insert(y.end(), v0.begin(), v0.end());
    return y;
  }
};

inline double OutputTime(const Problem& p, int k) { return p.t0 + (p.tend - p.t0) * k / p.nout; }

inline double RelError(const Problem& p, int k, const double* x) {
  if (p.ref.empty()) return 0;
  const Vec& r = p.ref[k - 1];
  double e2 = 0;
  for (int i = 0; i < p.n; ++i) e2 += (x[i] - r[i]) * (x[i] - r[i]);
  return std::sqrt(e2) / p.x0norm;
}

inline double Norm2(const Vec& x) {
  double s = 0;
  for (double q : x) s += q * q;
  return std::sqrt(s);
}

// Output mode's fixed steps: h = (tend / nout) / m with the smallest m that keeps h <= h_req, so
// every output instant is a step point.
inline long StepsPerOutput(const Problem& p, double h_req) {
  return static_cast<long>(std::ceil(p.tend / p.nout / h_req - 1e-9));
}
inline double FixedStep(const Problem& p, double h_req) {
  return p.tend / p.nout / static_cast<double>(StepsPerOutput(p, h_req));
}

// One integration's outcome (the timing is added by Measure).
struct Outcome {
  double error = 0, drift = 0;
  long steps = 0, rhs_evals = 0;
  long jac_evals = 0, lin_setups = 0;  // CEODE: iteration-matrix evaluations, factorisations
  int flag = 0;                        // CEODE: CEodeEvolve's failure flag, when it returned one
};

// Keeps the largest error and drift over the instants a runner observes.
struct Track {
  const Problem& p;
  double emax = 0, dmax = 0;
  explicit Track(const Problem& pr) : p(pr) {}
  void Step(double t, const double* x, const double* v) {
    const double e = p.err(t, x, v, p.user);
    if (!(e <= emax)) emax = e;  // also catches NaN
    const double d = p.drift != nullptr ? p.drift(t, x, v, p.user) : 0.0;
    if (!(d <= dmax)) dmax = d;
  }
  void Output(int k, const double* x) {
    const double e = RelError(p, k, x);
    if (!(e <= emax)) emax = e;
  }
  int Finish(bool bad, Outcome* out) const {
    out->error = emax;
    out->drift = dmax;
    return bad || !std::isfinite(emax) ? 1 : 0;
  }
};

// ---------------------------------------------------------------------- CEODE
// How CEODE solves the step. vel declares f's velocity dependence (the implicit step); ls is
// the Newton iteration's linear solver (kNone: CEODE's own choice).
struct CeodeOpts {
  explicit CeodeOpts(const char* set = "G3_CD") : method(set) {}
  const char* method;       // a name CEodeSetMethodByName knows (a literal: runs may be queued)
  bool zero_start = false;  // one-step mode only
  bool vel = false;
  // kKlu: p.vjac fills a CSR df/dv with p.vjac_nnz entries; KLU factors M - kappa df/dv.
  enum Ls { kDense, kSpgmr, kKlu, kNone } ls = kDense;
  int implicit_mode = CE_IMPLICIT_NEWTON;  // CEodeSetImplicitMode
  double nls_rtol = 0, nls_atol = 0;       // CEodeSetNonlinTolerances (rtol 0: the default)
  long msbj = 0;                           // CEodeSetJacEvalFrequency (0: the default)
  int pc_corrections = 0;                  // CEodeSetPCCorrections (0: the set's default)
  int max_nonlin_iters = 0;                // CEodeSetMaxNonlinIters (0: the default)
  int maxl = 20;                           // SPGMR's Krylov dimension
  // Error control: CeodeRun's h_or_tol is then rtol = atol (CEodeSStolerances), the stability
  // guard keeps its defaults (its stable-step cap is part of the adaptive step, and its f
  // evaluations are counted with the run's), and output mode does not round a step.
  bool adaptive = false;
  bool diagonal = false;  // CEodeSetVelJacDiagonal with the problem's vel_diag
};

struct CeodeStats {
  long nni = 0, npc = 0, nnls = 0;
  double coupling = 0;
  long netf = 0, ncapped = 0;  // error control: failed error tests, steps the stable step decided
  long nfe = 0, guard_fe = 0;  // f evaluations of the integration and of the stability guard
};

// The objects of one CEODE run, freed together.
struct CeodeObjects {
  N_Vector x = nullptr, v = nullptr, phi = nullptr, b = nullptr, m = nullptr;
  SUNMatrix M = nullptr, A = nullptr;
  SUNLinearSolver LS = nullptr;
  void* mem = nullptr;
  // x and v from the problem's start; false when an allocation failed.
  bool Create(SUNContext ctx, const Problem& p) {
    x = N_VNew_Serial(p.n, ctx);
    v = N_VNew_Serial(p.n, ctx);
    mem = CEodeCreate(ctx);
    if (x == nullptr || v == nullptr || mem == nullptr) return false;
    std::copy(p.x0.begin(), p.x0.end(), N_VGetArrayPointer(x));
    std::copy(p.v0.begin(), p.v0.end(), N_VGetArrayPointer(v));
    return true;
  }
  CeodeObjects() = default;
  ~CeodeObjects() {
    CEodeFree(&mem);
    if (LS != nullptr) SUNLinSolFree(LS);
    if (A != nullptr) SUNMatDestroy(A);
    if (M != nullptr) SUNMatDestroy(M);
    for (N_Vector w : {x, v, phi, b, m}) {
      if (w != nullptr) N_VDestroy(w);
    }
  }
  CeodeObjects(const CeodeObjects&) = delete;
  CeodeObjects& operator=(const CeodeObjects&) = delete;
};

// Velocity dependence, linear solver, mass matrix and constraints; true on failure. One-step
// mode leaves an undeclared velocity dependence to CEODE; output and end modes declare it either
// way.
inline bool CeodeAttach(SUNContext ctx, const Problem& p, const CeodeOpts& c, CeodeObjects* o) {
  void* mem = o->mem;
  if (c.vel || p.nout > 0 || p.end_only) {
    if (Failed(CEodeSetVelocityDependence(mem, c.vel ? SUNTRUE : SUNFALSE),
               "CEodeSetVelocityDependence")) {
      return true;
    }
  }
  if (c.vel) {
    if (c.ls == CeodeOpts::kDense) {
      o->A = SUNDenseMatrix(p.n, p.n, ctx);
      o->LS = o->A != nullptr ? SUNLinSol_Dense(o->x, o->A, ctx) : nullptr;
    } else if (c.ls == CeodeOpts::kSpgmr) {
      // Restarts: without them an unpreconditioned SPGMR stalls on M + kappa b K.
      o->LS = SUNLinSol_SPGMR(o->x, SUN_PREC_NONE, c.maxl, ctx);
      if (o->LS != nullptr && SUNLinSol_SPGMRSetMaxRestarts(o->LS, 5) != 0) return true;
    } else if (c.ls == CeodeOpts::kKlu && p.vjac != nullptr) {
      o->A = SUNSparseMatrix(p.n, p.n, p.vjac_nnz, CSR_MAT, ctx);
      o->LS = o->A != nullptr ? SUNLinSol_KLU(o->x, o->A, ctx) : nullptr;
      // KLU's ordering 0, AMD: the Newton matrix has df/dv's pattern, symmetric on the FE
      // scenes (K's), for which AMD's factors are sparser than those of the default COLAMD.
      if (o->LS != nullptr &&
          Failed(SUNLinSol_KLUSetOrdering(o->LS, 0), "SUNLinSol_KLUSetOrdering")) {
        return true;
      }
    }
    if ((c.ls != CeodeOpts::kNone &&
         (o->LS == nullptr ||
          Failed(CEodeSetLinearSolver(mem, o->LS, o->A), "CEodeSetLinearSolver"))) ||
        (p.vjac != nullptr && Failed(CEodeSetVelJacFn(mem, p.vjac), "CEodeSetVelJacFn")) ||
        Failed(CEodeSetImplicitMode(mem, c.implicit_mode), "CEodeSetImplicitMode") ||
        (c.nls_rtol > 0 && Failed(CEodeSetNonlinTolerances(mem, c.nls_rtol, c.nls_atol),
                                  "CEodeSetNonlinTolerances")) ||
        (c.msbj > 0 && Failed(CEodeSetJacEvalFrequency(mem, c.msbj), "CEodeSetJacEvalFrequency")) ||
        (c.pc_corrections > 0 &&
         Failed(CEodeSetPCCorrections(mem, c.pc_corrections), "CEodeSetPCCorrections")) ||
        (c.max_nonlin_iters > 0 &&
         Failed(CEodeSetMaxNonlinIters(mem, c.max_nonlin_iters), "CEodeSetMaxNonlinIters"))) {
      return true;
    }
  }
  if (c.diagonal && !p.vel_diag.empty()) {
    N_Vector d = N_VNew_Serial(p.n, ctx);  // copied by the setter
    if (d == nullptr) return true;
    std::copy(p.vel_diag.begin(), p.vel_diag.end(), N_VGetArrayPointer(d));
    const bool failed = Failed(CEodeSetVelJacDiagonal(mem, d), "CEodeSetVelJacDiagonal");
    N_VDestroy(d);
    if (failed) return true;
  }
  // The guard's estimate caps the adaptive step: in the lumped-mass inner product it is an upper
  // bound of omega_max (CEodeSetGuardMass), as a user of a lumped-mass model sets it.
  if (c.adaptive && !p.lumped_mass.empty() && p.mass == nullptr) {
    o->m = N_VNew_Serial(p.n, ctx);
    if (o->m == nullptr) return true;
    std::copy(p.lumped_mass.begin(), p.lumped_mass.end(), N_VGetArrayPointer(o->m));
    if (Failed(CEodeSetGuardMass(mem, o->m), "CEodeSetGuardMass")) return true;
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

// One CEODE run. Fixed steps (h_or_tol = h): the stability guard off (runs past a stability
// limit are part of the picture); output mode rounds h down to divide the output interval
// (FixedStep). With c.adaptive, h_or_tol = rtol = atol and the guard at its defaults. One-step
// mode observes every step; output mode every output instant, appending x there to *xs (if
// given); end mode (p.end_only) tend alone. rhs_evals counts every f evaluation: the steps', the
// difference quotients', the guard's.
inline int CeodeRun(SUNContext ctx, const Problem& p, const CeodeOpts& c, double h_or_tol,
                    Outcome* out, CeodeStats* st = nullptr, std::vector<Vec>* xs = nullptr) {
  CeodeObjects o;
  if (!o.Create(ctx, p)) return 1;
  const bool outputs = p.nout > 0;
  const double h = outputs && !c.adaptive ? FixedStep(p, h_or_tol) : h_or_tol;
  void* mem = o.mem;
  auto set_step = [&]() {
    if (c.adaptive) {
      return Failed(CEodeSStolerances(mem, h_or_tol, h_or_tol), "CEodeSStolerances") ||
             (p.init_step > 0 && Failed(CEodeSetInitStep(mem, p.init_step), "CEodeSetInitStep"));
    }
    return Failed(CEodeSetFixedStep(mem, h), "CEodeSetFixedStep") ||
           Failed(CEodeSetStabilityGuard(mem, CE_GUARD_OFF, 0), "CEodeSetStabilityGuard");
  };
  bool bad =
      Failed(CEodeInit(mem, p.f2, p.t0, o.x, o.v), "CEodeInit") ||
      Failed(CEodeSetUserData(mem, p.user), "CEodeSetUserData") ||
      Failed(CEodeSetMethodByName(mem, c.method), "CEodeSetMethodByName") || set_step() ||
      (!outputs &&
       Failed(CEodeSetZeroStart(mem, c.zero_start ? SUNTRUE : SUNFALSE), "CEodeSetZeroStart")) ||
      Failed(CEodeSetMaxNumSteps(mem, 100000000L), "CEodeSetMaxNumSteps") ||
      Failed(CEodeSetStopTime(mem, p.tend), "CEodeSetStopTime") || CeodeAttach(ctx, p, c, &o);
  Track tr(p);
  double t = p.t0;
  const double* xd = N_VGetArrayPointer(o.x);
  const double* vd = N_VGetArrayPointer(o.v);
  if (outputs) {
    for (int k = 1; k <= p.nout && !bad; ++k) {
      out->flag = CEodeEvolve(mem, OutputTime(p, k), o.x, o.v, &t, CE_NORMAL);
      bad = Failed(out->flag, "CEodeEvolve");
      if (!bad) tr.Output(k, xd);
      if (!bad && xs != nullptr) xs->emplace_back(xd, xd + p.n);
    }
  }
  if (!outputs && p.end_only && !bad) {
    out->flag = CEodeEvolve(mem, p.tend, o.x, o.v, &t, CE_NORMAL);
    bad = Failed(out->flag, "CEodeEvolve");
    if (!bad) tr.Step(t, xd, vd);
  }
  // Fixed steps end half a step before tend, adaptive ones at tend (the stop time).
  const double margin = c.adaptive ? 1e-12 * std::max(1.0, std::fabs(p.tend)) : 0.5 * h;
  while (!outputs && !p.end_only && !bad && t < p.tend - margin) {
    // One step at a time: x and x' are then known at the same instant.
    out->flag = CEodeEvolve(mem, p.tend, o.x, o.v, &t, CE_ONE_STEP);
    bad = Failed(out->flag, "CEodeEvolve");
    if (!bad) tr.Step(t, xd, vd);
  }
  CeodeStats s;
  long nfc = 0, nfe_dq = 0, nme = 0, nls = 0;
  bad = bad || Failed(CEodeGetNumSteps(mem, &out->steps), "CEodeGetNumSteps") ||
        Failed(CEodeGetNumRhsEvals(mem, &s.nfe), "CEodeGetNumRhsEvals") ||
        Failed(CEodeGetNumRhsEvalsJacDQ(mem, &nfe_dq), "CEodeGetNumRhsEvalsJacDQ") ||
        Failed(CEodeGetGuardStats(mem, &s.guard_fe, &nme, &nls), "CEodeGetGuardStats") ||
        Failed(CEodeGetNumJacEvals(mem, &out->jac_evals), "CEodeGetNumJacEvals") ||
        Failed(CEodeGetNumLinSolvSetups(mem, &out->lin_setups), "CEodeGetNumLinSolvSetups") ||
        Failed(CEodeGetNumErrTestFails(mem, &s.netf), "CEodeGetNumErrTestFails") ||
        Failed(CEodeGetNumStableStepLimited(mem, &s.ncapped), "CEodeGetNumStableStepLimited") ||
        (st != nullptr &&
         (Failed(CEodeGetNumNonlinSolvIters(mem, &s.nni), "CEodeGetNumNonlinSolvIters") ||
          Failed(CEodeGetImplicitStats(mem, &s.npc, &s.nnls, &nfc, &s.coupling),
                 "CEodeGetImplicitStats")));
  out->rhs_evals = s.nfe + nfe_dq + s.guard_fe;
  if (st != nullptr) *st = s;
  return tr.Finish(bad, out);
}

// The same for a set by name with every other option at its default.
inline int CeodeRun(SUNContext ctx, const Problem& p, const char* method, double h, Outcome* out,
                    bool zero_start = false) {
  CeodeOpts c(method);
  c.zero_start = zero_start;
  return CeodeRun(ctx, p, c, h, out);
}

// The stable step of a set from the guard (CEodeGetStableStep, safety 1) at the start, in the
// lumped-mass inner product when the problem has one; 0 on failure. *guard_fe (if given): the
// guard's f evaluations.
inline double GuardStep(SUNContext ctx, const Problem& p, const char* method,
                        long* guard_fe = nullptr) {
  CeodeObjects o;
  if (!o.Create(ctx, p)) return 0;
  sunrealtype h = 0;
  long nme = 0, nls = 0, nfe = 0;
  if (!p.lumped_mass.empty()) {
    o.m = N_VNew_Serial(p.n, ctx);
    if (o.m == nullptr) return 0;
    std::copy(p.lumped_mass.begin(), p.lumped_mass.end(), N_VGetArrayPointer(o.m));
  }
  if (Failed(CEodeInit(o.mem, p.f2, p.t0, o.x, o.v), "CEodeInit") ||
      Failed(CEodeSetUserData(o.mem, p.user), "CEodeSetUserData") ||
      Failed(CEodeSetMethodByName(o.mem, method), "CEodeSetMethodByName") ||
      Failed(CEodeSetVelocityDependence(o.mem, SUNFALSE), "CEodeSetVelocityDependence") ||
      (o.m != nullptr && Failed(CEodeSetGuardMass(o.mem, o.m), "CEodeSetGuardMass")) ||
      Failed(CEodeGetStableStep(o.mem, 1, &h), "CEodeGetStableStep") ||
      Failed(CEodeGetGuardStats(o.mem, &nfe, &nme, &nls), "CEodeGetGuardStats")) {
    return 0;
  }
  if (guard_fe != nullptr) *guard_fe = nfe;
  return h;
}

// Leapfrog, the loop explicit FE codes write (solver "CEODE-hand", the same method as CEODE
// G3_CD) in output mode: v_{n+1/2} = v_{n-1/2} + h a_n, x_{n+1} = x_n + h v_{n+1/2}, one
// accel(x, a) call and one fused update pass per step.
template <class Accel>
int LeapfrogRun(const Problem& pr, double h_req, const Accel& accel, Outcome* out) {
  const int n = pr.n;
  const long m = StepsPerOutput(pr, h_req);
  const double h = FixedStep(pr, h_req);
  Vec x(pr.x0), v(n), a(n);
  accel(x.data(), a.data());
  for (int k = 0; k < n; ++k) {
    v[k] = pr.v0[k] + 0.5 * h * a[k];
    x[k] += h * v[k];
  }
  Track tr(pr);
  long steps = 1;
  for (int o = 1; o <= pr.nout; ++o) {
    for (long j = (o == 1 ? 1 : 0); j < m; ++j, ++steps) {
      accel(x.data(), a.data());
      for (int k = 0; k < n; ++k) {
        v[k] += h * a[k];
        x[k] += h * v[k];
      }
    }
    tr.Output(o, x.data());
  }
  out->steps = steps;
  out->rhs_evals = steps;
  return tr.Finish(false, out);
}

// ------------------------------------------------- SUNDIALS (first-order form)
enum class Sun {
  kErkFixed,    // ERKStep, a fixed Butcher table
  kErk,         // ERKStep adaptive (order 0: ARKODE's default table)
  kCvodeAdams,  // fixed-point iteration
  kCvodeBdf,    // dense Newton
  kBdfSpgmr,    // CVODE BDF, matrix-free SPGMR
  kBdfKlu,      // CVODE BDF, the problem's sparse Jacobian and KLU
  kArkDirk,     // ARKStep DIRK, dense
  kDirkSpgmr,   // ARKStep DIRK, SPGMR
  kImexSpgmr    // ARKStep IMEX (fe explicit, fi implicit), SPGMR
};

struct SunOpts {
  Sun kind = Sun::kErk;
  int order = 0;                       // ERK adaptive: ERKStepSetOrder (0: default)
  ARKodeButcherTable table = nullptr;  // kErkFixed
  double atol_factor = 1;              // atol = atol_factor * rtol
};

// Kutta's classic third-order method, the paper's "RK3" (docs/theory.md section 11), with c3 =
// 1 - 1e-8: SUNDIALS before 6.7.0 takes any ERKStep table with c_s = 1 to be
// first-same-as-last and reuses the last stage's f as the next step's first stage, which for
// Kutta's table (b != last row of A) runs a different method with 2 f calls per step. With
// c3 != 1 ARKODE evaluates f(t_n+1, y_n+1) (3 calls per step, the hand-written method to the
// last digit); c only moves the time argument, so on autonomous problems this is Kutta's method.
inline ARKodeButcherTable KuttaRk3() {
  sunrealtype c[3] = {0.0, 0.5, 1.0 - 1e-8};
  sunrealtype A[9] = {0.0, 0.0, 0.0, 0.5, 0.0, 0.0, -1.0, 2.0, 0.0};
  sunrealtype b[3] = {1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0};
  return ARKodeButcherTable_Create(3, 3, 0, c, A, b, nullptr);
}

// The objects of one SUNDIALS run, freed together.
struct SunObjects {
  Sun kind;
  N_Vector y = nullptr;
  SUNMatrix J = nullptr;
  SUNLinearSolver LS = nullptr;
  SUNNonlinearSolver NLS = nullptr;
  void* mem = nullptr;
  explicit SunObjects(Sun k) : kind(k) {}
  bool Erk() const { return kind == Sun::kErkFixed || kind == Sun::kErk; }
  bool Ark() const {
    return kind == Sun::kArkDirk || kind == Sun::kDirkSpgmr || kind == Sun::kImexSpgmr;
  }
  ~SunObjects() {
    if (Erk()) {
      ERKStepFree(&mem);
    } else if (Ark()) {
      ARKStepFree(&mem);
    } else {
      CVodeFree(&mem);
    }
    if (NLS != nullptr) SUNNonlinSolFree(NLS);
    if (LS != nullptr) SUNLinSolFree(LS);
    if (J != nullptr) SUNMatDestroy(J);
    if (y != nullptr) N_VDestroy(y);
  }
  SunObjects(const SunObjects&) = delete;
  SunObjects& operator=(const SunObjects&) = delete;
};

// The linear solver of an implicit kind: dense, SPGMR (no preconditioner) or KLU.
inline SUNLinearSolver SunLinSol(SUNContext ctx, const Problem& p, SunObjects* o) {
  const int m = 2 * p.n;
  if (o->kind == Sun::kCvodeBdf || o->kind == Sun::kArkDirk) {
    o->J = SUNDenseMatrix(m, m, ctx);
    return o->J != nullptr ? SUNLinSol_Dense(o->y, o->J, ctx) : nullptr;
  }
  if (o->kind == Sun::kBdfKlu) {
    o->J = SUNSparseMatrix(m, m, p.jac_nnz, CSR_MAT, ctx);
    return o->J != nullptr && p.jac1 != nullptr ? SUNLinSol_KLU(o->y, o->J, ctx) : nullptr;
  }
  // Krylov dimension 20: the default 5 stalls on I - gamma J at large gamma omega_max.
  return SUNLinSol_SPGMR(o->y, SUN_PREC_NONE, 20, ctx);
}

// Creates and configures the integrator; true on failure. One-step mode stops at tend.
inline bool SunSetup(SUNContext ctx, const Problem& p, const SunOpts& c, double h_or_rtol,
                     SunObjects* o) {
  const double rtol = h_or_rtol, atol = c.atol_factor * h_or_rtol;
  const bool stop = p.nout == 0;
  if (o->Erk()) {
    void* mem = o->mem = ERKStepCreate(p.f1, p.t0, o->y, ctx);
    return mem == nullptr || Failed(ERKStepSetUserData(mem, p.user), "ERKStepSetUserData") ||
           (c.order > 0 && Failed(ERKStepSetOrder(mem, c.order), "ERKStepSetOrder")) ||
           Failed(ERKStepSetMaxNumSteps(mem, 100000000L), "ERKStepSetMaxNumSteps") ||
           (stop && Failed(ERKStepSetStopTime(mem, p.tend), "ERKStepSetStopTime")) ||
           (p.post_step != nullptr &&
            Failed(ERKStepSetPostprocessStepFn(mem, p.post_step), "ERKStepSetPostprocessStepFn")) ||
           (c.kind == Sun::kErkFixed
                ? Failed(ERKStepSetTable(mem, c.table), "ERKStepSetTable") ||
                      Failed(ERKStepSetFixedStep(mem, h_or_rtol), "ERKStepSetFixedStep")
                : Failed(ERKStepSStolerances(mem, rtol, atol), "ERKStepSStolerances"));
  }
  o->LS = c.kind == Sun::kCvodeAdams ? nullptr : SunLinSol(ctx, p, o);
  if (c.kind != Sun::kCvodeAdams && o->LS == nullptr) return true;
  if (o->Ark()) {
    const bool imex = c.kind == Sun::kImexSpgmr;
    void* mem = o->mem = imex ? ARKStepCreate(p.fe, p.fi, p.t0, o->y, ctx)
                              : ARKStepCreate(nullptr, p.f1, p.t0, o->y, ctx);
    return mem == nullptr || Failed(ARKStepSetUserData(mem, p.user), "ARKStepSetUserData") ||
           Failed(ARKStepSetMaxNumSteps(mem, 100000000L), "ARKStepSetMaxNumSteps") ||
           (stop && Failed(ARKStepSetStopTime(mem, p.tend), "ARKStepSetStopTime")) ||
           Failed(ARKStepSStolerances(mem, rtol, atol), "ARKStepSStolerances") ||
           Failed(ARKStepSetLinearSolver(mem, o->LS, o->J), "ARKStepSetLinearSolver") ||
           ((imex ? p.fi_linear : p.f1_linear) &&
            Failed(ARKStepSetLinear(mem, 0), "ARKStepSetLinear"));
  }
  void* mem = o->mem = CVodeCreate(c.kind == Sun::kCvodeAdams ? CV_ADAMS : CV_BDF, ctx);
  if (mem == nullptr || Failed(CVodeInit(mem, p.f1, p.t0, o->y), "CVodeInit") ||
      Failed(CVodeSetUserData(mem, p.user), "CVodeSetUserData") ||
      Failed(CVodeSetMaxNumSteps(mem, 100000000L), "CVodeSetMaxNumSteps") ||
      (stop && Failed(CVodeSetStopTime(mem, p.tend), "CVodeSetStopTime")) ||
      Failed(CVodeSStolerances(mem, rtol, atol), "CVodeSStolerances")) {
    return true;
  }
  if (c.kind == Sun::kCvodeAdams) {  // the non-stiff choice: functional (fixed-point) iteration
    o->NLS = SUNNonlinSol_FixedPoint(o->y, 0, ctx);
    return o->NLS == nullptr ||
           Failed(CVodeSetNonlinearSolver(mem, o->NLS), "CVodeSetNonlinearSolver");
  }
  return Failed(CVodeSetLinearSolver(mem, o->LS, o->J), "CVodeSetLinearSolver") ||
         (c.kind == Sun::kBdfKlu && Failed(CVodeSetJacFn(mem, p.jac1), "CVodeSetJacFn"));
}

inline int SunEvolve(const SunObjects& o, double tout, double* t, bool one_step) {
  if (o.Erk()) return ERKStepEvolve(o.mem, tout, o.y, t, one_step ? ARK_ONE_STEP : ARK_NORMAL);
  if (o.Ark()) return ARKStepEvolve(o.mem, tout, o.y, t, one_step ? ARK_ONE_STEP : ARK_NORMAL);
  return CVode(o.mem, tout, o.y, t, one_step ? CV_ONE_STEP : CV_NORMAL);
}

// Steps and f evaluations of every kind (explicit, implicit, the Krylov and difference-quotient
// Jacobians' evaluations); true on failure.
inline bool SunCounters(const SunObjects& o, Outcome* out) {
  long nfe = 0, nfi = 0, nfls = 0;
  bool bad;
  if (o.Erk()) {
    bad = Failed(ERKStepGetNumSteps(o.mem, &out->steps), "ERKStepGetNumSteps") ||
          Failed(ERKStepGetNumRhsEvals(o.mem, &nfe), "ERKStepGetNumRhsEvals");
  } else if (o.Ark()) {
    bad = Failed(ARKStepGetNumSteps(o.mem, &out->steps), "ARKStepGetNumSteps") ||
          Failed(ARKStepGetNumRhsEvals(o.mem, &nfe, &nfi), "ARKStepGetNumRhsEvals") ||
          Failed(ARKStepGetNumLinRhsEvals(o.mem, &nfls), "ARKStepGetNumLinRhsEvals");
  } else {
    bad = Failed(CVodeGetNumSteps(o.mem, &out->steps), "CVodeGetNumSteps") ||
          Failed(CVodeGetNumRhsEvals(o.mem, &nfe), "CVodeGetNumRhsEvals") ||
          (o.kind != Sun::kCvodeAdams &&
           Failed(CVodeGetNumLinRhsEvals(o.mem, &nfls), "CVodeGetNumLinRhsEvals"));
  }
  out->rhs_evals = nfe + nfi + nfls;
  return bad;
}

// One integration of the first-order form. kErkFixed: h_or_rtol is the step; otherwise the
// relative tolerance. One-step mode observes every step; output mode every output instant; end
// mode (p.end_only) tend alone.
inline int SundialsRun(SUNContext ctx, const Problem& p, const SunOpts& c, double h_or_rtol,
                       Outcome* out) {
  SunObjects o(c.kind);
  o.y = N_VNew_Serial(2 * p.n, ctx);
  if (o.y == nullptr) return 1;
  const Vec y0 = p.FirstOrderStart();
  double* Y = N_VGetArrayPointer(o.y);
  std::copy(y0.begin(), y0.end(), Y);
  bool bad = SunSetup(ctx, p, c, h_or_rtol, &o);
  Track tr(p);
  double t = p.t0;
  for (int k = 1; k <= p.nout && !bad; ++k) {
    bad = Failed(SunEvolve(o, OutputTime(p, k), &t, false), "Evolve");
    if (!bad) tr.Output(k, Y);
  }
  if (p.nout == 0 && p.end_only && !bad) {
    bad = Failed(SunEvolve(o, p.tend, &t, false), "Evolve");
    if (!bad) tr.Step(t, Y, Y + p.n);
  }
  // Fixed steps end half a step before tend (as CeodeRun), adaptive ones at tend.
  const double margin =
      c.kind == Sun::kErkFixed ? 0.5 * h_or_rtol : 1e-12 * std::max(1.0, std::fabs(p.tend));
  while (p.nout == 0 && !p.end_only && !bad && t < p.tend - margin) {
    bad = Failed(SunEvolve(o, p.tend, &t, true), "Evolve");
    if (!bad) tr.Step(t, Y, Y + p.n);
  }
  bad = bad || SunCounters(o, out);
  return tr.Finish(bad, out);
}

// ------------------------------------------------------------------------ IDA
// One integration of the residual form with IDA (variable-order BDF, dense iteration matrix) in
// one-step mode at rtol = atol = tol.
inline int IdaRun(SUNContext ctx, const Problem& p, double tol, Outcome* out) {
  const int m = p.ny;
  N_Vector yy = N_VNew_Serial(m, ctx), yp = N_VNew_Serial(m, ctx), id = N_VNew_Serial(m, ctx);
  SUNMatrix J = SUNDenseMatrix(m, m, ctx);
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
          (p.res_jac != nullptr && Failed(IDASetJacFn(mem, p.res_jac), "IDASetJacFn"));
  }
  Track tr(p);
  double t = p.t0;
  const double* Y = bad ? nullptr : N_VGetArrayPointer(yy);
  while (!bad && t < p.tend) {
    const int flag = IDASolve(mem, p.tend, &t, yy, yp, IDA_ONE_STEP);
    bad = Failed(flag, "IDASolve");
    if (!bad) tr.Step(t, Y, Y + p.n);
    if (flag == IDA_TSTOP_RETURN) break;
  }
  long nre = 0, nre_ls = 0;
  bad = bad || Failed(IDAGetNumSteps(mem, &out->steps), "IDAGetNumSteps") ||
        Failed(IDAGetNumResEvals(mem, &nre), "IDAGetNumResEvals") ||
        Failed(IDAGetNumLinResEvals(mem, &nre_ls), "IDAGetNumLinResEvals");
  out->rhs_evals = nre + nre_ls;
  IDAFree(&mem);
  if (LS != nullptr) SUNLinSolFree(LS);
  if (J != nullptr) SUNMatDestroy(J);
  for (N_Vector w : {yy, yp, id}) {
    if (w != nullptr) N_VDestroy(w);
  }
  return tr.Finish(bad, out);
}
// ------------------------------------------------------- measured + timed rows
// The row of one configuration: its numbers from an Outcome, its time per run.
inline Row OutcomeRow(const std::string& solver, const std::string& config, double h_or_tol,
                      const Outcome& o, double seconds) {
  return Row{solver, config, h_or_tol, o.error, o.drift, o.steps, o.rhs_evals, seconds};
}

// Runs once for the numbers, then times the same call; adds a row or a failure. With
// flag_is_result, a run that ends with CEODE's own failure flag is a flagged result instead.
// Returns true when the row was added; *got (if given) receives the figures.
template <class F>
bool Measure(Table* table, const std::string& solver, const std::string& config, double h_or_tol,
             F&& once, Outcome* got = nullptr, bool flag_is_result = false) {
  Outcome o;
  if (once(&o) != 0) {
    if (flag_is_result && o.flag < 0) {
      char* name = CEodeGetReturnFlagName(o.flag);  // the caller owns it
      table->Flagged(solver, config, h_or_tol, name != nullptr ? name : "a failure flag");
      std::free(name);
    } else {
      table->Fail(solver, config, h_or_tol, "failed or unstable");
    }
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
// plate family). Timing the configurations one after the other puts a burst of load on a
// shared machine on one solver's curve; here every configuration is first run once for
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

// One CEODE configuration at step h (one-step mode: h as given; output mode: FixedStep(h)), or
// at rtol = atol = h with c.adaptive.
inline bool MeasureCeode(Table* table, SUNContext ctx, const Problem& p, const CeodeOpts& c,
                         double h, const std::string& config, Outcome* got = nullptr) {
  return Measure(
      table, "CEODE", config, p.nout > 0 && !c.adaptive ? FixedStep(p, h) : h,
      [&](Outcome* o) { return CeodeRun(ctx, p, c, h, o); }, got);
}

// The same for a set by name with the scene's other options at their defaults.
inline bool MeasureCeode(Table* table, SUNContext ctx, const Problem& p, const char* method,
                         double h, bool zero_start, const std::string& config,
                         Outcome* got = nullptr) {
  CeodeOpts c(method);
  c.zero_start = zero_start;
  return MeasureCeode(table, ctx, p, c, h, config, got);
}

// ------------------------------------------------------------------ the hand loop
// G8_O8 at the fixed step h written out by hand (hand_step.h) on the problem's own a(x): the
// floor of the method's cost, beside CEODE's fixed-step curve of the same set. CEODE takes the
// first step (its start included, in the time too); the history at t1 = t0 + h and x(t1 + h)
// come from its interpolant there (CEodeGetDky, k = 0 .. 8, p(h) summed as the dense output
// does), every later step by hand. One-step mode observes every step, end mode tend alone (as
// CeodeRun); for problems whose a does not depend on v or t (Problem::separable) and without
// outputs, constraints or a mass matrix.
inline int HandG8Run(SUNContext ctx, const Problem& p, double h, Outcome* out) {
  constexpr int d = 8;
  int degree = 0;
  double prm[hand::kMaxD] = {};
  if (!p.separable || p.nout > 0 || p.nc > 0 || p.mass != nullptr ||
      Failed(CEodeGetMethodParams("G8_O8", &degree, prm, hand::kMaxD), "CEodeGetMethodParams") ||
      degree != d) {
    return 1;
  }
  CeodeObjects o;
  if (!o.Create(ctx, p)) return 1;
  void* mem = o.mem;
  double t = p.t0;
  long nfe = 0;
  bool bad = Failed(CEodeInit(mem, p.f2, p.t0, o.x, o.v), "CEodeInit") ||
             Failed(CEodeSetUserData(mem, p.user), "CEodeSetUserData") ||
             Failed(CEodeSetMethodByName(mem, "G8_O8"), "CEodeSetMethodByName") ||
             Failed(CEodeSetFixedStep(mem, h), "CEodeSetFixedStep") ||
             Failed(CEodeSetStabilityGuard(mem, CE_GUARD_OFF, 0), "CEodeSetStabilityGuard") ||
             Failed(CEodeSetStopTime(mem, p.tend), "CEodeSetStopTime") ||
             Failed(CEodeEvolve(mem, p.tend, o.x, o.v, &t, CE_ONE_STEP), "CEodeEvolve") ||
             Failed(CEodeGetNumRhsEvals(mem, &nfe), "CEodeGetNumRhsEvals");
  const long n = p.n;
  // D[0] = x(t1), D[1 .. 7] the history, D[8] the interpolant's top derivative.
  std::vector<Vec> D(d + 1, Vec(n));
  for (int k = 0; k <= d && !bad; ++k) {
    bad = Failed(CEodeGetDky(mem, t, k, o.x), "CEodeGetDky");
    const double* xd = N_VGetArrayPointer(o.x);
    std::copy(xd, xd + n, D[k].begin());
  }
  if (bad) return 1;
  Track tr(p);
  if (!p.end_only) tr.Step(t, D[0].data(), D[1].data());
  Vec x(n, 0.0), xprev(n), an(n);
  for (long i = 0; i < n; ++i) {  // x(t1 + h) = p(h)
    double s = 0, w = 1;
    for (int k = 1; k <= d; ++k) {
      w *= h / k;
      s += w * D[k][i];
    }
    x[i] = D[0][i] + s;
  }
  const hand::D8Weights w = hand::MakeD8Weights(hand::MakeCoeffs(d, prm, h));
  const long nsteps = std::lround((p.tend - p.t0) / h);
  for (long j = 2; j <= nsteps; ++j) {
    t = p.t0 + static_cast<double>(j) * h;
    xprev = x;
    if (p.acc(t, x.data(), D[1].data(), an.data(), p.user) != 0) return 1;
    hand::D8Update(w, an.data(), D[1].data(), D[2].data(), D[3].data(), D[4].data(), D[5].data(),
                   D[6].data(), D[7].data(), x.data(), n);
    D[2].swap(an);
    if (!p.end_only) tr.Step(t, xprev.data(), D[1].data());
  }
  if (p.end_only) tr.Step(t, xprev.data(), D[1].data());
  out->steps = nsteps;
  out->rhs_evals = nfe + nsteps - 1;
  return tr.Finish(false, out);
}

// The hand loop's row at step h (solver "CEODE-hand", config G8_O8), checked against CEODE's
// fixed step of the same set: the errors agree to 1 %, or to the scene's round-off floor (the
// two sum in other orders), else a failure.
inline bool MeasureHandG8(Table* table, SUNContext ctx, const Problem& p, double h, double floor,
                          Outcome* got = nullptr) {
  Outcome hand_o, ceode_o;
  if (HandG8Run(ctx, p, h, &hand_o) != 0 || CeodeRun(ctx, p, "G8_O8", h, &ceode_o) != 0) {
    table->Fail("CEODE-hand", "G8_O8", h, "failed or unstable");
    return false;
  }
  if (!(std::fabs(hand_o.error - ceode_o.error) <= std::max(1e-2 * ceode_o.error, floor))) {
    std::printf("  hand loop G8_O8 h=%g: error %.6e vs CEODE %.6e -- MISMATCH\n", h, hand_o.error,
                ceode_o.error);
    table->Fail("CEODE-hand", "G8_O8", h, "differs from CEODE");
    return false;
  }
  return Measure(
      table, "CEODE-hand", "G8_O8", h, [&](Outcome* o) { return HandG8Run(ctx, p, h, o); }, got);
}

// ------------------------------------------------------------ CEODE adaptive
// A CEODE error-control curve: one row per tolerance (rtol = atol), config "<set> adaptive"
// unless a label is given.
struct TolCurve {
  std::string label;
  CeodeOpts opts;
  std::vector<double> tols;
  std::string Config() const {
    return label.empty() ? std::string(opts.method) + " adaptive" : label;
  }
};

// What error control did in a run: failed tests, capped steps, and where the f evaluations went.
inline void PrintAdaptStats(const std::string& config, double tol, const Outcome& o,
                            const CeodeStats& st) {
  std::printf(
      "    %s tol %.0e: %ld failed error tests, %ld steps capped by the stable step, f: %ld by "
      "the step, %ld by the guard, %ld in all; %ld steps, %ld nonlinear iterations, %ld "
      "linear-solver setups\n",
      config.c_str(), tol, st.netf, st.ncapped, st.nfe, st.guard_fe, o.rhs_evals, o.steps, st.nni,
      o.lin_setups);
}

// The curve in one-step (or output) mode, configuration by configuration (Measure); the outcome
// of every run that succeeded goes to *got_all (if given). A run that ends with CEODE's failure
// flag (the controller gives up at a tolerance) is a flagged result. Returns the runs that failed
// otherwise (also failure rows of the table).
inline int MeasureTolCurve(Table* table, SUNContext ctx, const Problem& p, const TolCurve& c,
                           std::vector<Outcome>* got_all = nullptr) {
  CeodeOpts opts = c.opts;
  opts.adaptive = true;
  const std::string config = c.Config();
  int failed = 0;
  for (double tol : c.tols) {
    CeodeStats st;  // the numbers run's; the timed calls overwrite it with the same figures
    Outcome got;
    const int flagged = table->flagged();
    if (!Measure(
            table, "CEODE", config, tol,
            [&](Outcome* o) { return CeodeRun(ctx, p, opts, tol, o, &st); }, &got, true)) {
      if (table->flagged() == flagged) ++failed;
      continue;
    }
    PrintAdaptStats(config, tol, got, st);
    if (got_all != nullptr) got_all->push_back(got);
  }
  return failed;
}

// The curves in interleaved rounds (output mode); a curve stops after the first run that costs
// more than max_seconds or fails, as SundialsCurves.
inline void TolCurves(SUNContext ctx, const Problem* p, const std::vector<TolCurve>& curves,
                      double max_seconds, Rounds* rounds) {
  for (const TolCurve& c : curves) {
    CeodeOpts opts = c.opts;
    opts.adaptive = true;
    const std::string config = c.Config();
    for (double tol : c.tols) {
      auto st = std::make_shared<CeodeStats>();
      Outcome got;
      const double first = rounds->Measure(
          "CEODE", config, tol,
          [ctx, p, opts, tol, st](Outcome* o) { return CeodeRun(ctx, *p, opts, tol, o, st.get()); },
          &got);
      if (first >= 0) PrintAdaptStats(config, tol, got, *st);
      if (first < 0 || first > max_seconds) break;
    }
  }
}

inline const char* SunName(Sun s) {
  switch (s) {
    case Sun::kErkFixed:
    case Sun::kErk:
      return "ARKODE-ERK";
    case Sun::kCvodeAdams:
      return "CVODE-Adams";
    case Sun::kCvodeBdf:
    case Sun::kBdfSpgmr:
    case Sun::kBdfKlu:
      return "CVODE-BDF";
    case Sun::kArkDirk:
    case Sun::kDirkSpgmr:
      return "ARKODE-DIRK";
    case Sun::kImexSpgmr:
      return "ARKODE-IMEX";
  }
  return "?";
}

inline bool MeasureSundials(Table* table, SUNContext ctx, const Problem& p, const SunOpts& c,
                            double h_or_rtol, const std::string& config,
                            const char* solver = nullptr, Outcome* got = nullptr) {
  return Measure(
      table, solver != nullptr ? solver : SunName(c.kind), config, h_or_rtol,
      [&](Outcome* o) { return SundialsRun(ctx, p, c, h_or_rtol, o); }, got);
}

inline bool MeasureIda(Table* table, SUNContext ctx, const Problem& p, double tol,
                       const std::string& config, Outcome* got = nullptr) {
  return Measure(
      table, "IDA", config, tol, [&](Outcome* o) { return IdaRun(ctx, p, tol, o); }, got);
}

// The constrained step's iteration-matrix reuse: evaluations of the saddle-point matrix's
// Jacobian (G(x), or df/dv when f depends on v) and factorisations per step. Printed, not
// checked: at the coarsest steps the stale matrix contracts too slowly and is refreshed more
// often (test_constraints checks h = 1e-3).
inline void PrintMatrixReuse(const std::string& config, double h, const Outcome& o) {
  const double per_step = o.steps > 0 ? static_cast<double>(o.jac_evals) / o.steps : 0.0;
  std::printf("  matrix reuse %s h = %g: %ld Jacobian evals, %ld setups, %ld steps (%.4f/step)%s\n",
              config.c_str(), h, o.jac_evals, o.lin_setups, o.steps, per_step,
              10 * o.jac_evals <= o.steps ? "" : "  (above steps/10)");
}

// A SUNDIALS curve per configuration over the tolerances in interleaved rounds (output mode);
// a curve stops after the first run that costs more than max_seconds (it is past every CEODE
// point by then) or fails.
struct SunCurve {
  SunOpts opts;
  const char* solver;
  const char* config;
};

inline void SundialsCurves(SUNContext ctx, const Problem* p, const std::vector<SunCurve>& curves,
                           const std::vector<double>& tols, double max_seconds, Rounds* rounds) {
  for (const SunCurve& c : curves) {
    for (double tol : tols) {
      const double first = rounds->Measure(c.solver, c.config, tol, [ctx, p, c, tol](Outcome* o) {
        return SundialsRun(ctx, *p, c.opts, tol, o);
      });
      if (first < 0 || first > max_seconds) break;
    }
  }
}

// A curve stops after the first tolerance whose run costs more than this (CPU s; that run is
// kept): the output-mode scenes' implicit SUNDIALS curves take seconds a point.
constexpr double kSundialsCutoff = 1.5;

// The tolerances of the FE plate variants.
inline std::vector<double> FeTols(bool quick) {
  return quick ? std::vector<double>{1e-4} : std::vector<double>{1e-3, 1e-4, 1e-5, 1e-6};
}

// The first-order configurations every FE plate scene is compared with: ARKODE ERK orders 3, 4,
// 5, CVODE Adams (fixed point), CVODE BDF + SPGMR, `extra` (CVODE BDF + KLU or ARKStep IMEX +
// SPGMR), ARKStep DIRK + SPGMR.
inline void FeSundialsCurves(SUNContext ctx, const Problem* p, Sun extra,
                             const std::vector<double>& tols, double max_seconds, Rounds* rounds) {
  const std::vector<SunCurve> curves = {
      {{Sun::kErk, 3}, "ARKODE-ERK", "order3"},
      {{Sun::kErk, 4}, "ARKODE-ERK", "order4"},
      {{Sun::kErk, 5}, "ARKODE-ERK", "order5"},
      {{Sun::kCvodeAdams}, "CVODE-Adams", "fixedpoint"},
      {{Sun::kBdfSpgmr}, "CVODE-BDF", "SPGMR"},
      {{extra}, SunName(extra), extra == Sun::kBdfKlu ? "KLU" : "SPGMR"},
      {{Sun::kDirkSpgmr}, "ARKODE-DIRK", "SPGMR"}};
  SundialsCurves(ctx, p, curves, tols, max_seconds, rounds);
}

// CEODE's error-control curves of the FE plate scenes: each set of `sets` with the options
// `opts`, config "<set><suffix> adaptive". The step is the stable step of the guard's omega_max
// (in the lumped-mass inner product) wherever the error allows more: at the loose tolerances for
// G3_CD, G4_A34 and G5_O4; from G6_O5 on (degree >= 6) at nearly every step of 1e-3 ... 1e-8,
// so those curves run at 1e-3 and 1e-8 only. G3_CD stops at 1e-7 (its steps grow like
// tol^(-1/2)). --quick: G3_CD at 1e-4 and 1e-6, G5_O4 at 1e-5 (the cap on the quick mesh) and
// 1e-7.
inline std::vector<TolCurve> FeTolCurves(const CeodeOpts& opts, const std::string& suffix,
                                         const std::vector<const char*>& sets, bool quick) {
  std::vector<TolCurve> curves;
  for (const char* m : sets) {
    const std::string name(m);
    std::vector<double> tols = {1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8};
    if (name == "G3_CD") tols.pop_back();
    int degree = 0;
    double params[8];
    if (CEodeGetMethodParams(m, &degree, params, 8) == 0 && degree >= 6) tols = {1e-3, 1e-8};
    if (quick) {
      if (name == "G3_CD") {
        tols = {1e-4, 1e-6};
      } else if (name == "G5_O4") {
        tols = {1e-5, 1e-7};
      } else {
        continue;
      }
    }
    CeodeOpts o = opts;
    o.method = m;
    curves.push_back({name + suffix + " adaptive", o, tols});
  }
  return curves;
}

// CEODE curves in output mode at fractions of each set's own stable step (GuardStep), queued in
// rounds; `hand` (if given) runs the hand loop beside the "G3_CD" curve at the same steps.
// Prints the implicit step's figures of the numbers run of every curve with vel declared.
// Returns the stable step of the first curve.
struct FracCurve {
  std::string label;
  CeodeOpts opts;
  std::vector<double> frac;
};

inline double FractionCurves(SUNContext ctx, const Problem* p, const std::vector<FracCurve>& curves,
                             Rounds* rounds,
                             const std::function<int(double, Outcome*)>& hand = nullptr) {
  double first = 0;
  for (const FracCurve& c : curves) {
    const double hs = GuardStep(ctx, *p, c.opts.method);
    if (first == 0) first = hs;
    for (double f : c.frac) {
      const double hr = f * hs, h = FixedStep(*p, hr);
      auto st = std::make_shared<CeodeStats>();  // the numbers run's; the timed calls overwrite it
      const CeodeOpts opts = c.opts;
      Outcome got;
      const bool ok = rounds->Measure(
                          "CEODE", c.label, h,
                          [ctx, p, opts, hr, st](Outcome* o) {
                            return CeodeRun(ctx, *p, opts, hr, o, st.get());
                          },
                          &got) >= 0;
      if (ok && opts.vel) {
        std::printf(
            "    %s h = %.3e: %.3f f/step, %.3f nonlinear iters/step, %ld PC steps, "
            "%ld NLS steps, coupling kappa |df/dv| = %.3e, %ld linear-solver setups\n",
            c.label.c_str(), h, static_cast<double>(got.rhs_evals) / got.steps,
            static_cast<double>(st->nni) / got.steps, st->npc, st->nnls, st->coupling,
            got.lin_setups);
      }
      if (hand && c.label == "G3_CD") {
        rounds->Measure("CEODE-hand", "G3_CD", h, [hand, hr](Outcome* o) { return hand(hr, o); });
      }
    }
  }
  return first;
}

// A second-order CEODE curve's observed order from its last three steps is in (1.8, 2.3);
// prints it, returns 1 when it is not.
inline int CheckSecondOrder(const Table& table, const std::string& config) {
  const double p = CurveOrder(table, "CEODE", config);
  const bool ok = p > 1.8 && p < 2.3;
  std::printf("CEODE %s order from the last three steps: %.3f %s\n", config.c_str(), p,
              ok ? "ok" : "-- OFF");
  return ok ? 0 : 1;
}

}  // namespace wp

#endif  // CEODE_BENCH_WP_COMMON_H_
