// -----------------------------------------------------------------------------
// wp_fpu_chain: a smooth problem with an expensive f, every solver side by side. The FPU-beta
// chain of N = 1000 unit masses and springs with fixed ends,
//   x_i'' = (d_i - d_{i-1}) + beta (d_i^3 - d_{i-1}^3),  d_i = x_{i+1} - x_i,  x_0 = x_{N+1} = 0,
// beta = 1, released from rest on x_i = 2 sin(50 pi i / (N + 1)) (the chain of
// bench/python/problem_chain.py: largest strain 0.31, the cubic force up to 10 % of the linear
// one, feeding the harmonics 150, 250, ... that make accuracy decide the step), t in [0, 100].
// f is one pass over the chain, about 1 us. Error: max_i |x_i(100) - ref_i| (the amplitude is 2).
// Reference: classical RK4 in long double, Richardson-extrapolated from 4e4 and 8e4 steps; it
// must agree with the extrapolation from 2e4 and 4e4 steps to 1e-13 and with GSL rk8pd at tol
// 1e-14 to 1e-11 (both printed).
// Solvers, all driven as a user wants the final state (Problem::end_only: CEODE and SUNDIALS
// integrate to t = 100 in one normal-mode call with the stop time there; the peers step on as
// their own drivers do):
//  * CEODE G5_O4, G6_O5, G7_O7, G8_O8 at fixed h = 100 / N_steps (stability guard off) and with
//    error control (CEodeSStolerances, rtol = atol = tol, config "<set> adaptive", the guard at
//    its defaults, its f evaluations counted with the run's); f does not read x' (declared);
//  * the peers (bench/peers.h): GSL rk8pd, Boost.Odeint rkf78, dopri5 and Bulirsch-Stoer at
//    eps_abs = eps_rel = tol;
//  * ARKODE ERKStep adaptive at its default order and at order 8, CVODE Adams (fixed-point), at
//    rtol = atol = tol.
// Summaries: the best curve per side at equal error (1e-6, 1e-8, 1e-10), CEODE adaptive against
// every other curve, and at 1e-8 and 1e-10 CEODE's best curve against the best peer in time and f
// evaluations (printed, not a check: times are the machine's).
//
// Usage: wp_fpu_chain [--csv FILE] [--quick]
// --quick: G8_O8 at two fixed steps and two tolerances, GSL rk8pd and Bulirsch-Stoer at two
// tolerances, ARKODE order 8 at one (the ctest).
// Exit code 0 when every run succeeded, the reference checks passed, G8_O8 at fixed steps reaches
// 1e-10 and (full run) every peer converges at its order (peers::CheckPeerOrders).
// -----------------------------------------------------------------------------
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "wp_common.h"
#ifdef CEODE_BENCH_PEERS
#include "peers.h"
#endif

namespace {

constexpr int kN = 1000;
constexpr int kMode = 50;
constexpr double kAmp = 2.0;
constexpr double kBeta = 1.0;
constexpr double kTend = 100.0;

struct Scene {
  std::vector<double> ref;  // x(kTend)
};

// a = f(x): one pass, each spring's force computed once and carried to the next mass.
template <class T>
void ChainAccel(const T* x, T* a, int n) {
  T dl = x[0];  // d_0 = x_1 - x_0, x_0 = 0
  T sl = dl + T(kBeta) * dl * dl * dl;
  for (int i = 0; i < n; ++i) {
    const T dr = (i + 1 < n ? x[i + 1] : T(0)) - x[i];
    const T sr = dr + T(kBeta) * dr * dr * dr;
    a[i] = sr - sl;
    sl = sr;
  }
}

int Accel(double, const double* x, const double*, double* a, void*) {
  ChainAccel(x, a, kN);
  return 0;
}

// Only x(100) counts: the instants before report no error.
double Err(double t, const double* x, const double*, void* user) {
  if (t < kTend - 1e-9) return 0;
  const std::vector<double>& r = static_cast<Scene*>(user)->ref;
  double e = 0;
  for (int i = 0; i < kN; ++i) e = std::max(e, std::fabs(x[i] - r[i]));
  return e;
}

std::vector<double> StartState() {
  std::vector<double> x0(kN);
  for (int i = 0; i < kN; ++i) x0[i] = kAmp * std::sin(M_PI * kMode * (i + 1) / (kN + 1));
  return x0;
}

// x(kTend) by classical RK4 in long double with `steps` steps, from rest at x0.
std::vector<long double> Rk4LongDouble(const std::vector<double>& x0, long steps) {
  using LD = long double;
  std::vector<LD> x(x0.begin(), x0.end()), v(kN, 0), xs(kN), vs(kN), a(kN);
  std::vector<LD> kx(kN), kv(kN), sx(kN), sv(kN);
  const LD h = static_cast<LD>(kTend) / steps;
  const LD c[4] = {0, 0.5L, 0.5L, 1}, w[4] = {1, 2, 2, 1};
  for (long s = 0; s < steps; ++s) {
    std::fill(sx.begin(), sx.end(), 0);
    std::fill(sv.begin(), sv.end(), 0);
    for (int st = 0; st < 4; ++st) {
      for (int i = 0; i < kN; ++i) {
        xs[i] = x[i] + c[st] * h * kx[i];
        vs[i] = v[i] + c[st] * h * kv[i];
      }
      ChainAccel(xs.data(), a.data(), kN);
      for (int i = 0; i < kN; ++i) {
        kx[i] = vs[i], kv[i] = a[i];
        sx[i] += w[st] * kx[i], sv[i] += w[st] * kv[i];
      }
    }
    for (int i = 0; i < kN; ++i) x[i] += h / 6 * sx[i], v[i] += h / 6 * sv[i];
  }
  return x;
}

// The reference and its convergence check (see the header comment).
bool Reference(Scene* s) {
  const std::vector<double> x0 = StartState();
  const auto a = Rk4LongDouble(x0, 20000), b = Rk4LongDouble(x0, 40000);
  const auto c = Rk4LongDouble(x0, 80000);
  s->ref.resize(kN);
  double gap = 0;
  for (int i = 0; i < kN; ++i) {
    const long double r1 = (16 * b[i] - a[i]) / 15, r2 = (16 * c[i] - b[i]) / 15;
    s->ref[i] = static_cast<double>(r2);
    gap = std::max(gap, static_cast<double>(std::fabs(r1 - r2)));
  }
  const bool ok = gap < 1e-13;
  std::printf(
      "reference x(100): RK4 long double, Richardson 4e4/8e4 steps; against 2e4/4e4: max %.2e "
      "%s\n",
      gap, ok ? "ok" : "-- NOT CONVERGED");
  return ok;
}

struct Plan {
  std::vector<long> steps;
  std::vector<double> tols, ce_tols;
  std::vector<const char*> sets, adaptive_sets;
};

// Fixed steps from 320 (h = 0.31: h omega_max about 0.7 with omega_max about 2.3 at the largest
// strain, inside the stability limits 0.8 ... 2 of the four sets) to 3200, a curve stopping below
// an error of 1e-12 (past every level of the summaries).
Plan MakePlan(bool quick) {
  Plan plan;
  plan.sets = plan.adaptive_sets = {"G5_O4", "G6_O5", "G7_O7", "G8_O8"};
  plan.steps = {320, 400, 560, 800, 1100, 1600, 2200, 3200};
  plan.tols = {1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12};
  plan.ce_tols = {1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13};
  if (quick) {
    plan.sets = plan.adaptive_sets = {"G8_O8"};
    plan.steps = {500, 1300};
    plan.tols = {1e-8, 1e-10};
    plan.ce_tols = {1e-8, 1e-10};
  }
  return plan;
}

wp::Problem MakeProblem(Scene* scene) {
  wp::Problem p;
  p.n = kN;
  p.Lift<Accel>();
  p.user = scene;
  p.tend = kTend;
  p.x0 = StartState();
  p.v0.assign(kN, 0.0);
  p.err = Err;
  p.separable = true;
  p.end_only = true;
  return p;
}

// CEODE at fixed steps and with error control; returns G8_O8's smallest fixed-step error.
double RunCeode(SUNContext ctx, const wp::Problem& p, const Plan& plan, wp::Table* table) {
  double g8 = 1;
  for (const char* m : plan.sets) {
    for (long n : plan.steps) {
      wp::Outcome o;
      if (!wp::MeasureCeode(table, ctx, p, m, kTend / n, false, m, &o)) continue;
      if (std::string(m) == "G8_O8") g8 = std::min(g8, o.error);
      if (o.error < 1e-12) break;
    }
  }
  for (const char* m : plan.adaptive_sets) {
    wp::MeasureTolCurve(table, ctx, p, {"", wp::CeodeOpts(m), plan.ce_tols});
  }
  return g8;
}

// ARKODE ERKStep at its default order and at order 8, CVODE Adams; a curve stops once measuring
// one tolerance took 5 kSundialsCutoff CPU seconds (runs of about kSundialsCutoff s: past every
// CEODE and peer point by then).
void RunSundials(SUNContext ctx, const wp::Problem& p, const Plan& plan, bool quick,
                 wp::Table* table) {
  struct Curve {
    wp::SunOpts opts;
    const char* config;
  };
  std::vector<Curve> curves = {{{wp::Sun::kErk, 0}, "adaptive"},
                               {{wp::Sun::kErk, 8}, "order8"},
                               {{wp::Sun::kCvodeAdams}, "adaptive"}};
  if (quick) curves = {{{wp::Sun::kErk, 8}, "order8"}};
  for (const Curve& c : curves) {
    for (double tol : quick ? std::vector<double>{1e-8} : plan.tols) {
      const double t0 = wp::Now();
      if (!wp::MeasureSundials(table, ctx, p, c.opts, tol, c.config)) break;
      if (wp::Now() - t0 > 5 * wp::kSundialsCutoff) break;
    }
  }
}

#ifdef CEODE_BENCH_PEERS
// An independent check of the reference: GSL rk8pd at tol 1e-14.
bool CrossCheck(const wp::Problem& p) {
  wp::Outcome o;
  const bool ran = peers::PeerOnce<kN>(p, peers::InfoOf(peers::Kind::kRk8pd), 1e-14, 1.0, &o) == 0;
  const bool ok = ran && o.error < 1e-11;
  std::printf("GSL rk8pd at tol 1e-14 against the reference: %.2e %s\n", o.error,
              ok ? "ok" : "-- DISAGREES");
  return ok;
}

// GSL rk8pd, odeint rkf78, dopri5 and Bulirsch-Stoer; returns the problems (reference
// cross-check, order checks of a full run).
int RunPeers(const wp::Problem& p, const Plan& plan, bool quick, wp::Table* table) {
  peers::Setup();
  int bad = CrossCheck(p) ? 0 : 1;
  std::vector<peers::Kind> kinds = {peers::Kind::kRk8pd, peers::Kind::kRkf78, peers::Kind::kDopri5,
                                    peers::Kind::kBulirschStoer};
  if (quick) kinds = {peers::Kind::kRk8pd, peers::Kind::kBulirschStoer};
  for (peers::Kind k : kinds) {
    const peers::Info& info = peers::InfoOf(k);
    for (double tol : plan.tols) {
      wp::Measure(table, info.solver, info.config, tol,
                  [&](wp::Outcome* o) { return peers::PeerOnce<kN>(p, info, tol, 1.0, o); });
    }
  }
  if (!quick) bad += peers::CheckPeerOrders(*table, 1e-12, 1e-3);
  return bad;
}
#endif

// At each level: CEODE's fastest curve against the fastest peer, time and f evaluations.
void PrintAgainstPeers(const wp::Table& table, const std::vector<double>& levels) {
  std::vector<std::pair<std::string, std::string>> curves;
  for (const wp::Row& r : table.rows()) {
    const auto key = std::make_pair(r.solver, r.config);
    if (std::find(curves.begin(), curves.end(), key) == curves.end()) curves.push_back(key);
  }
  std::printf("\nCEODE's fastest curve against the fastest peer (odeint, GSL):\n");
  for (double e : levels) {
    const std::pair<std::string, std::string>* best[2] = {nullptr, nullptr};
    double t[2] = {-1, -1};
    for (const auto& k : curves) {
      const int side = k.first == "CEODE" ? 0 : wp::IsPeerSolver(k.first) ? 1 : -1;
      if (side < 0) continue;
      const double s = wp::TimeAtError(table.rows(), k.first, k.second, e);
      if (s > 0 && (t[side] < 0 || s < t[side])) t[side] = s, best[side] = &k;
    }
    if (best[0] == nullptr || best[1] == nullptr) {
      std::printf("  %.0e: %s\n", e, best[0] == nullptr ? "CEODE does not reach it" : "no peer");
      continue;
    }
    const double f0 = wp::EvalsAtError(table.rows(), best[0]->first, best[0]->second, e);
    const double f1 = wp::EvalsAtError(table.rows(), best[1]->first, best[1]->second, e);
    std::printf("  %.0e: CEODE %s %.3e s %.0f f, %s %s %.3e s %.0f f: time %.3f, f %.3f%s\n", e,
                best[0]->second.c_str(), t[0], f0, best[1]->first.c_str(), best[1]->second.c_str(),
                t[1], f1, t[0] / t[1], f0 / f1,
                t[0] <= t[1] ? " (CEODE at least as fast)" : " (CEODE SLOWER)");
  }
}

}  // namespace

int main(int argc, char** argv) {
  const wp::Args args = wp::ParseArgs(argc, argv);
  SUNContext ctx = nullptr;
  if (wp::Failed(SUNContext_Create(SUN_COMM_NULL, &ctx), "SUNContext_Create")) return 1;
  std::printf(
      "FPU-beta chain, N = %d, beta = %g, from rest on %g sin(%d pi i / (N + 1)), t in [0, %g]; "
      "error = max_i |x_i(%g) - ref_i|\n",
      kN, kBeta, kAmp, kMode, kTend, kTend);
  Scene scene;
  int bad = Reference(&scene) ? 0 : 1;
  const Plan plan = MakePlan(args.quick);
  wp::Table table("fpu_chain", args.csv);
  const wp::Problem p = MakeProblem(&scene);
  const double g8 = RunCeode(ctx, p, plan, &table);
  RunSundials(ctx, p, plan, args.quick, &table);
#ifdef CEODE_BENCH_PEERS
  bad += RunPeers(p, plan, args.quick, &table);
#else
  std::printf("(built without GSL/Boost: no odeint/GSL peer curves)\n");
#endif
  wp::PrintEqualError(table, {1e-6, 1e-8, 1e-10});
  wp::PrintAdaptiveEqualError(table, {1e-8, 1e-10});
  PrintAgainstPeers(table, {1e-8, 1e-10});
  const bool g8_ok = g8 <= 1e-10;
  std::printf("G8_O8 fixed-step smallest error %.2e (must be <= 1e-10) %s\n", g8,
              g8_ok ? "ok" : "-- OFF");
  if (!g8_ok) ++bad;
  bad += table.failures();
  std::printf("%d problem(s)\n", bad);
  SUNContext_Free(&ctx);
  return bad == 0 ? 0 : 1;
}
