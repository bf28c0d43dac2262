// -----------------------------------------------------------------------------
// wp_high_order: CEODE's high-degree sets (G6_O5 ... G8_O8, docs/stability.md) against
// the high-order integrators users pick for smooth problems, error against CPU time:
//   * GSL rk8pd (Prince-Dormand 8(7), gsl_odeiv2_driver, eps_abs = eps_rel = tol),
//   * Boost.Odeint runge_kutta_fehlberg78 (controlled) and bulirsch_stoer (these three
//     through bench/peers.h, the peer runners of every scene: one evolve step at a time),
//   * ARKODE ERKStep at order 8 (Fehlberg 13-7-8), adaptive, stop time at t_end,
//   * CEODE at fixed steps (h divides t_end), stability guard off;
//   * CEODE error control (CEodeSStolerances, rtol = atol = tol, stop time t_end, the guard at
//     its defaults) with G5_O4, G6_O5, G7_O7, G8_O8: solver "<set> adaptive", config
//     "adaptive tol", the tolerance in h_or_tol, as the peers' rows.
// Problems: the IFToMM pendulum theta'' = -9.81 cos theta, theta(0) = theta'(0) = 0, error
// |theta(10) - ref|; and an FPU-beta chain of 16 masses (fixed ends, beta = 1, released from
// rest in mode 1 (amplitude 1) plus mode 5 (amplitude 0.3): strongly nonlinear), error
// max_i |x_i(10) - ref_i|. References: classical RK4 in long double,
// Richardson-extrapolated from 2e5 and 4e5 steps (agreement of the two runs: < 1e-16).
// Timing: wp::TimeMedian (process CPU time, median of >= 5 repetitions of >= 50 ms).
//
//   wp_high_order [--csv FILE] [--quick]
//   wp_high_order --count METHOD STEPS REPS [comp]   (for callgrind: REPS untimed pendulum runs,
//                                                     bench/step_cost/instructions.sh high-order)
//   wp_high_order --count gsl_rk8pd TOL REPS         (the same for rk8pd at one tolerance)
// Prints one row per run and a summary: per solver, the CPU time and the f evaluations at errors
// 1e-9 and 1e-11 (wp::TimeAtError, the equal-error rule of every scene) and the smallest error
// reached. --quick: a few runs (CEODE adaptive: G8_O8 at 1e-9 and 1e-12); exit code 1 unless
// G8_O8 reaches 1e-11 on the pendulum.
// -----------------------------------------------------------------------------
#include <algorithm>
#include <map>

#include "peers.h"  // GSL rk8pd, odeint rkf78 and Bulirsch-Stoer: the peers of every scene
#include "wp_common.h"

namespace {

constexpr int kChain = 16;

// One model x'' = a(x) of n degrees of freedom (the user data of its wp::Problem, MakeProblem);
// counts its evaluations.
struct Model {
  const char* name;
  int n;
  void (*accel)(const double* x, double* a, int n);
  std::vector<double> ref;
  mutable long evals = 0;
  const wp::Problem* problem = nullptr;  // the problem it is the user data of
};

void PendulumAccel(const double* x, double* a, int /*n*/) { a[0] = -9.81 * std::cos(x[0]); }

template <class T>
void ChainAccelT(const T* x, T* a, int n) {
  for (int i = 0; i < n; ++i) {
    const T l = i > 0 ? x[i - 1] : T(0);
    const T r = i + 1 < n ? x[i + 1] : T(0);
    const T dl = x[i] - l, dr = r - x[i];
    a[i] = dr - dl + (dr * dr * dr - dl * dl * dl);
  }
}
void ChainAccel(const double* x, double* a, int n) { ChainAccelT(x, a, n); }

// Long-double RK4 reference with Richardson extrapolation (see the header comment).
std::vector<double> Reference(const wp::Problem& p) {
  auto run = [&p](long steps) {
    const int n = p.n;
    std::vector<long double> x(p.x0.begin(), p.x0.end()), v(p.v0.begin(), p.v0.end());
    std::vector<long double> k[4][2], xs(n), a(n);
    for (auto& kk : k) kk[0].resize(n), kk[1].resize(n);
    auto acc = [&](const std::vector<long double>& xx, std::vector<long double>* out) {
      if (p.n == 1) {
        (*out)[0] = -9.81L * std::cos(xx[0]);
      } else {
        ChainAccelT(xx.data(), out->data(), n);
      }
    };
    const long double h = p.tend / steps;
    const long double c[4] = {0, 0.5L, 0.5L, 1};
    for (long s = 0; s < steps; ++s) {
      for (int st = 0; st < 4; ++st) {
        std::vector<long double> vs(n);
        for (int i = 0; i < n; ++i) {
          xs[i] = x[i] + (st ? c[st] * h * k[st - 1][0][i] : 0);
          vs[i] = v[i] + (st ? c[st] * h * k[st - 1][1][i] : 0);
        }
        acc(xs, &a);
        for (int i = 0; i < n; ++i) k[st][0][i] = vs[i], k[st][1][i] = a[i];
      }
      for (int i = 0; i < n; ++i) {
        x[i] += h / 6 * (k[0][0][i] + 2 * k[1][0][i] + 2 * k[2][0][i] + k[3][0][i]);
        v[i] += h / 6 * (k[0][1][i] + 2 * k[1][1][i] + 2 * k[2][1][i] + k[3][1][i]);
      }
    }
    return x;
  };
  const std::vector<long double> a = run(200000), b = run(400000);
  std::vector<double> r(p.n);
  for (int i = 0; i < p.n; ++i) r[i] = static_cast<double>((16 * b[i] - a[i]) / 15);
  return r;
}

const Model& M(const wp::Problem& p) { return *static_cast<const Model*>(p.user); }

double ErrorOf(const wp::Problem& p, const double* x) {
  double e = 0;
  for (int i = 0; i < p.n; ++i) e = std::max(e, std::fabs(x[i] - M(p).ref[i]));
  return e;
}

// a = accel(x), counted; lifted by the harness to CEODE's, ARKODE's and the peers' forms.
int Acc(double, const double* x, const double*, double* a, void* user) {
  const auto* m = static_cast<const Model*>(user);
  ++m->evals;
  m->accel(x, a, m->n);
  return 0;
}

// Only theta(10) / x(10) counts: earlier instants report no error.
double EndError(double t, const double* x, const double*, void* user) {
  const wp::Problem* p = static_cast<const Model*>(user)->problem;
  return t < p->tend - 1e-9 ? 0.0 : ErrorOf(*p, x);
}

wp::Problem MakeProblem(Model* m, std::vector<double> x0) {
  wp::Problem p;
  p.n = m->n;
  p.Lift<Acc>();
  p.user = m;
  p.tend = 10;
  p.x0 = std::move(x0);
  p.v0.assign(m->n, 0.0);
  p.err = EndError;
  return p;
}

struct Result {
  std::string solver;
  double param = 0, error = 0, seconds = 0;
  long evals = 0;
};

// ---- CEODE in normal mode, one output at t_end: fixed steps (h divides t_end), stability guard
// off; or (tol > 0, steps ignored) error control at rtol = atol = tol to the stop time t_end, the
// guard at its defaults (its f evaluations are counted by Acc as every other) ------------------
int CeodeRun(SUNContext ctx, const wp::Problem& p, const char* method, long steps, bool comp,
             double* err, double tol = 0) {
  N_Vector x = N_VNew_Serial(p.n, ctx), v = N_VNew_Serial(p.n, ctx);
  std::copy(p.x0.begin(), p.x0.end(), N_VGetArrayPointer(x));
  std::copy(p.v0.begin(), p.v0.end(), N_VGetArrayPointer(v));
  void* mem = CEodeCreate(ctx);
  int flag = CEodeInit(mem, p.f2, 0, x, v);
  if (flag == 0) flag = CEodeSetUserData(mem, p.user);
  if (flag == 0) flag = CEodeSetMethodByName(mem, method);
  if (tol > 0) {
    if (flag == 0) flag = CEodeSStolerances(mem, tol, tol);
    if (flag == 0) flag = CEodeSetStopTime(mem, p.tend);
    if (flag == 0) flag = CEodeSetMaxNumSteps(mem, 100000000L);
  } else {
    if (flag == 0) flag = CEodeSetFixedStep(mem, p.tend / steps);
    if (flag == 0) flag = CEodeSetStabilityGuard(mem, CE_GUARD_OFF, 0);
    if (flag == 0 && comp) flag = CEodeSetCompensatedSummation(mem, SUNTRUE);
    if (flag == 0) flag = CEodeSetMaxNumSteps(mem, steps + 10);
  }
  sunrealtype t = 0;
  if (flag == 0) flag = CEodeEvolve(mem, p.tend, x, v, &t, CE_NORMAL);
  *err = ErrorOf(p, N_VGetArrayPointer(x));
  CEodeFree(&mem);
  N_VDestroy(x);
  N_VDestroy(v);
  return flag < 0 ? 1 : 0;
}

// ---- the peers (bench/peers.h): eps_abs = eps_rel = tol, first trial step 1e-3 ---------------
int PeerRun(const wp::Problem& p, peers::Kind k, double tol, double* err) {
  wp::Outcome o;
  const peers::Info& info = peers::InfoOf(k);
  const int rc = p.n == 1 ? peers::PeerOnce<1>(p, info, tol, 1.0, &o)
                          : peers::PeerOnce<kChain>(p, info, tol, 1.0, &o);
  *err = o.error;
  return rc;
}

// ---- ARKODE ERKStep at order 8 on the first-order form, stop time at t_end ----------------
int ArkRun(SUNContext ctx, const wp::Problem& p, double tol, double* err) {
  N_Vector y = N_VNew_Serial(2 * p.n, ctx);
  const std::vector<double> y0 = p.FirstOrderStart();
  std::copy(y0.begin(), y0.end(), N_VGetArrayPointer(y));
  void* mem = ERKStepCreate(p.f1, 0, y, ctx);
  int flag = ERKStepSetUserData(mem, p.user);
  if (flag == 0) flag = ERKStepSetTableNum(mem, ARKODE_FEHLBERG_13_7_8);
  if (flag == 0) flag = ERKStepSStolerances(mem, tol, tol);
  if (flag == 0) flag = ERKStepSetStopTime(mem, p.tend);
  if (flag == 0) flag = ERKStepSetMaxNumSteps(mem, 1000000);
  sunrealtype t = 0;
  if (flag == 0) flag = ERKStepEvolve(mem, p.tend, y, &t, ARK_NORMAL);
  *err = ErrorOf(p, N_VGetArrayPointer(y));
  ERKStepFree(&mem);
  N_VDestroy(y);
  return flag < 0 ? 1 : 0;
}

// Times run (returns 0 on success) and records error and evaluations of one call.
template <class F>
bool Measure(const wp::Problem& p, const std::string& solver, double param, F run,
             std::vector<Result>* out) {
  double err = 0;
  M(p).evals = 0;
  if (run(&err) != 0) return false;
  Result r{solver, param, err, 0, M(p).evals};
  double dummy = 0;
  r.seconds = wp::TimeMedian([&] { return run(&dummy); });
  std::printf("%-10s %-14s %10.4g  error %.3e  f-evals %8ld  %.3e s\n", M(p).name, solver.c_str(),
              param, r.error, r.evals, r.seconds);
  out->push_back(r);
  return r.seconds >= 0;
}

// CPU time (evals: f evaluations) at a target error: wp::TimeAtError, the one equal-error rule
// of every scene; < 0: the curve does not reach the target.
double TimeAt(const std::vector<Result>& rs, double target, bool evals = false) {
  std::vector<wp::Row> rows;
  for (const Result& r : rs) {
    wp::Row w;
    w.solver = r.solver;
    w.error = r.error;
    w.seconds = evals ? static_cast<double>(r.evals) : r.seconds;
    rows.push_back(w);
  }
  return rs.empty() ? -1 : wp::TimeAtError(rows, rs.front().solver, "", target);
}

bool IsFixedStep(const std::string& solver) {
  return solver.rfind("G", 0) == 0 && solver.find("adaptive") == std::string::npos;
}

struct Plan {
  std::vector<const char*> sets;
  std::vector<long> steps;
  std::vector<double> tols;
  std::vector<const char*> adaptive_sets;  // CEODE error control, solver "<set> adaptive"
  std::vector<double> ce_tols;
};

// Every solver on one problem; *g8_best: G8_O8's smallest error (the quick check).
bool RunSolvers(SUNContext ctx, const Plan& plan, const wp::Problem& p, std::vector<Result>* rs,
                double* g8_best) {
  bool ok = true;
  for (const char* m : plan.sets) {
    for (bool comp : {false, true}) {
      if (comp && std::strcmp(m, "G8_O8") != 0 && std::strcmp(m, "G7_O7") != 0) continue;
      const std::string name = std::string(m) + (comp ? "+comp" : "");
      for (long n : plan.steps) {
        ok &= Measure(
            p, name, p.tend / n, [&](double* e) { return CeodeRun(ctx, p, m, n, comp, e); }, rs);
        if (!comp && std::strcmp(m, "G8_O8") == 0) *g8_best = std::min(*g8_best, rs->back().error);
      }
    }
  }
  for (const char* m : plan.adaptive_sets) {
    const std::string name = std::string(m) + " adaptive";
    for (double tol : plan.ce_tols) {
      ok &= Measure(
          p, name, tol, [&](double* e) { return CeodeRun(ctx, p, m, 0, false, e, tol); }, rs);
    }
  }
  const std::pair<const char*, peers::Kind> peer_runs[] = {
      {"gsl_rk8pd", peers::Kind::kRk8pd},
      {"odeint_rkf78", peers::Kind::kRkf78},
      {"odeint_bs", peers::Kind::kBulirschStoer}};
  for (double tol : plan.tols) {
    for (const auto& k : peer_runs) {
      ok &= Measure(
          p, k.first, tol, [&](double* e) { return PeerRun(p, k.second, tol, e); }, rs);
    }
    ok &= Measure(
        p, "arkode_erk8", tol, [&](double* e) { return ArkRun(ctx, p, tol, e); }, rs);
  }
  return ok;
}

// CSV rows and the summary table of one problem.
void Summarise(const wp::Problem& p, const std::vector<Result>& rs, FILE* csv) {
  std::map<std::string, std::vector<Result>> by;
  for (const Result& r : rs) {
    by[r.solver].push_back(r);
    if (csv) {
      std::fprintf(csv, "%s,%s,%s,%.6g,%.6e,0,0,%ld,%.6e\n", M(p).name, r.solver.c_str(),
                   IsFixedStep(r.solver) ? "fixed h" : "adaptive tol", r.param, r.error, r.evals,
                   r.seconds);
    }
  }
  const std::vector<Result>& g = by["gsl_rk8pd"];
  const double g9 = TimeAt(g, 1e-9), g11 = TimeAt(g, 1e-11);
  const double f9 = TimeAt(g, 1e-9, true), f11 = TimeAt(g, 1e-11, true);
  std::printf(
      "\n%s: CPU time and f evaluations at error 1e-9 / 1e-11 (ratios to gsl_rk8pd), best "
      "error\n",
      M(p).name);
  auto ratio = [](double a, double b) { return a > 0 && b > 0 ? a / b : -1; };
  for (const auto& kv : by) {
    const double t9 = TimeAt(kv.second, 1e-9), t11 = TimeAt(kv.second, 1e-11);
    const double e9 = TimeAt(kv.second, 1e-9, true), e11 = TimeAt(kv.second, 1e-11, true);
    double best = 1e300;
    for (const Result& r : kv.second) best = std::min(best, r.error);
    std::printf(
        "  %-16s %10.3e s (%5.2f) %7.0f f (%5.2f)  %10.3e s (%5.2f) %7.0f f (%5.2f)  best %.2e\n",
        kv.first.c_str(), t9, ratio(t9, g9), e9, ratio(e9, f9), t11, ratio(t11, g11), e11,
        ratio(e11, f11), best);
  }
}

// --count: REPS pendulum runs of METHOD at STEPS steps, nothing timed (whole runs as the timed
// ones, create to free, so callgrind's counts split into a fixed cost per run and a cost per step).
int CountRuns(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr, "usage: %s --count METHOD STEPS|TOL REPS [comp]\n", argv[0]);
    return 2;
  }
  SUNContext ctx;
  if (SUNContext_Create(SUN_COMM_NULL, &ctx) != 0) return 1;
  Model pend{"pendulum", 1, PendulumAccel, {0}};
  wp::Problem p = MakeProblem(&pend, {0});
  pend.problem = &p;
  const long steps = std::atol(argv[3]);
  const int reps = std::atoi(argv[4]);
  const bool comp = argc > 5 && std::strcmp(argv[5], "comp") == 0;
  int rc = 0;
  double err = 0;
  if (std::strcmp(argv[2], "gsl_rk8pd") == 0) {  // STEPS is then the tolerance
    peers::Setup();
    const double tol = std::atof(argv[3]);
    for (int r = 0; r < reps && rc == 0; ++r) rc = PeerRun(p, peers::Kind::kRk8pd, tol, &err);
    std::printf("gsl_rk8pd tol %g x %d runs: |theta(10)| = %.17g\n", tol, reps, err);
  } else {
    for (int r = 0; r < reps && rc == 0; ++r) rc = CeodeRun(ctx, p, argv[2], steps, comp, &err);
    std::printf("%s %ld steps x %d runs%s: |theta(10)| = %.17g\n", argv[2], steps, reps,
                comp ? " +comp" : "", err);
  }
  SUNContext_Free(&ctx);
  return rc;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1 && std::strcmp(argv[1], "--count") == 0) return CountRuns(argc, argv);
  const wp::Args args = wp::ParseArgs(argc, argv);
  peers::Setup();
  SUNContext ctx;
  if (SUNContext_Create(SUN_COMM_NULL, &ctx) != 0) return 1;
  Model pend{"pendulum", 1, PendulumAccel, {}};
  Model chain{"fpu_chain_16", kChain, ChainAccel, {}};
  std::vector<double> chain_x0;
  for (int i = 0; i < kChain; ++i) {
    const double q = M_PI * (i + 1) / (kChain + 1);
    chain_x0.push_back(std::sin(q) + 0.3 * std::sin(5 * q));
  }
  std::vector<wp::Problem> problems = {MakeProblem(&pend, {0})};
  if (!args.quick) problems.push_back(MakeProblem(&chain, chain_x0));
  Plan plan;
  if (args.quick) {
    plan = {{"G8_O8"}, {400, 1600}, {1e-10}, {"G8_O8"}, {1e-9, 1e-12}};
  } else {
    plan.sets = {"G4_A34", "G5", "G6_O5", "G7_O7", "G8_O8"};
    plan.steps = {40,  60,   80,   100,  130,  160,  200,  250,  320,  400,  500,  650,
                  800, 1000, 1300, 1600, 2000, 2500, 3200, 4000, 5000, 8000, 16000};
    plan.tols = {1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13, 1e-14, 1e-15};
    plan.adaptive_sets = {"G5_O4", "G6_O5", "G7_O7", "G8_O8"};
    plan.ce_tols = plan.tols;
  }
  FILE* csv = args.csv.empty() ? nullptr : std::fopen(args.csv.c_str(), "w");
  if (csv) std::fputs(wp::kCsvHeader, csv);
  bool ok = true;
  double quick_best = 1;
  for (wp::Problem& p : problems) {
    Model* m = static_cast<Model*>(p.user);
    m->problem = &p;
    m->ref = Reference(p);
    std::vector<Result> rs;
    double g8 = 1;
    ok &= RunSolvers(ctx, plan, p, &rs, &g8);
    if (m == &pend) quick_best = g8;
    Summarise(p, rs, csv);
  }
  if (csv) std::fclose(csv);
  SUNContext_Free(&ctx);
  if (args.quick) {
    std::printf("quick: G8_O8 best pendulum error %.2e (must be <= 1e-11)\n", quick_best);
    ok &= quick_best <= 1e-11;
  }
  return ok ? 0 : 1;
}
