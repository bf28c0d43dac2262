// -----------------------------------------------------------------------------
// wp_damped_pendulum: the damped driven pendulum, the 1-DOF velocity-dependent (implicit) case.
// theta'' = -9.81 cos(theta) - 0.5 theta' + sin(2t), theta(0) = theta'(0) = 0, t in [0, 10];
// error = |theta(10) - ref|. Reference: classical RK4 in long double, Richardson-extrapolated
// from 1e5/2e5 and from 2e5/4e5 steps (they must agree to 1e-14), and GSL rk8pd at tol 1e-14
// (within 1e-11).
// Methods: CEODE's sets at h = 10/N, velocity dependence declared, Newton (dense, analytic
// df/dtheta') and AUTO, N = 100 ... 1e5 (with AUTO, the sets a user picks for a smooth problem,
// G5_O4 ... G8_O8, also at N = 150, 250, 300, 400, 700, where they cross 1e-9; those sets also with
// the exact one-f solve of CEodeSetVelJacDiagonal, "-diag", on that grid); a set's sweep
// stops below an error of 3e-14. Only theta(10) counts (Problem::end_only): CEODE and SUNDIALS
// integrate to t = 10 in one normal-mode call, as a user who wants the final state. ARKODE ERKStep
// with Kutta's RK3 at the same h; ERKStep adaptive, CVODE Adams and BDF at rtol = atol = 1e-3 ...
// 1e-13; the peers (not the symplectic ones: f depends on theta'). CEODE error control (config
// "<set> adaptive", h_or_tol the tolerance) with G5_O4, G6_O5, G7_O7, G8_O8 at rtol = atol = 1e-4
// ... 1e-14, the implicit step at the library's default (AUTO). Usage: wp_damped_pendulum [--csv
// FILE] [--quick]. Prints CEODE's best time over odeint RK4's at 1e-6 and 1e-9 (not a check) and
// CEODE adaptive against every other curve at equal error (f evaluations and time). Exit code 0
// when every run succeeded, the reference checks passed and every peer converges at its order
// (peers::CheckPeerOrders).
// -----------------------------------------------------------------------------
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "wp_common.h"
#ifdef CEODE_BENCH_PEERS
#include "peers.h"
#endif

namespace {

constexpr double kG = 9.81;  // g/L
constexpr double kDamp = 0.5;
constexpr double kTend = 10.0;

struct Scene {
  double ref = 0;  // theta(10)
};

double Accel(double t, double th, double om) {
  return -kG * std::cos(th) - kDamp * om + std::sin(2 * t);
}

int AccelFn(double t, const double* x, const double* v, double* a, void*) {
  a[0] = Accel(t, x[0], v[0]);
  return 0;
}

int VelJac(sunrealtype, N_Vector, N_Vector, N_Vector, SUNMatrix J, void*, N_Vector, N_Vector,
           N_Vector) {
  SM_ELEMENT_D(J, 0, 0) = -kDamp;
  return 0;
}

// Only the end counts: the instants before t = 10 report no error.
double Err(double t, const double* x, const double*, void* user) {
  if (t < kTend - 1e-9) return 0;
  return std::fabs(x[0] - static_cast<Scene*>(user)->ref);
}

// theta(10) by classical RK4 in long double with n steps.
long double Rk4LongDouble(long n) {
  const long double h = static_cast<long double>(kTend) / n;
  auto acc = [](long double t, long double x, long double v) {
    return -static_cast<long double>(kG) * std::cos(x) - static_cast<long double>(kDamp) * v +
           std::sin(2 * t);
  };
  long double x = 0, v = 0;
  for (long i = 0; i < n; ++i) {
    const long double t = i * h;
    const long double k1x = v, k1v = acc(t, x, v);
    const long double k2x = v + h / 2 * k1v, k2v = acc(t + h / 2, x + h / 2 * k1x, k2x);
    const long double k3x = v + h / 2 * k2v, k3v = acc(t + h / 2, x + h / 2 * k2x, k3x);
    const long double k4x = v + h * k3v, k4v = acc(t + h, x + h * k3x, k4x);
    x += h / 6 * (k1x + 2 * k2x + 2 * k3x + k4x);
    v += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
  }
  return x;
}

// The reference and its convergence check (see the header comment).
bool Reference(Scene* s) {
  const long double a = Rk4LongDouble(100000), b = Rk4LongDouble(200000), c = Rk4LongDouble(400000);
  const long double r1 = (16 * b - a) / 15, r2 = (16 * c - b) / 15;
  s->ref = static_cast<double>(r2);
  const double gap = static_cast<double>(std::fabs(r1 - r2));
  const bool ok = gap < 1e-14;
  std::printf(
      "reference theta(10) = %.17g (RK4 long double, Richardson 2e5/4e5 steps); "
      "against 1e5/2e5: %.2e %s\n",
      s->ref, gap, ok ? "ok" : "-- NOT CONVERGED");
  return ok;
}

#ifdef CEODE_BENCH_PEERS
// An independent check of the reference: GSL rk8pd at tol 1e-14.
bool CrossCheck(const wp::Problem& p) {
  wp::Outcome o;
  const peers::Info& rk8pd = peers::InfoOf(peers::Kind::kRk8pd);
  const bool ran = peers::PeerOnce<1>(p, rk8pd, 1e-14, 1.0, &o) == 0;
  const bool ok = ran && o.error < 1e-11;
  std::printf("GSL rk8pd at tol 1e-14 against the reference: %.2e %s\n", o.error,
              ok ? "ok" : "-- DISAGREES");
  return ok;
}

// CEODE's best curve over odeint RK4's at one error level (the target).
void PrintAgainstRk4(const wp::Table& table, const std::vector<std::string>& sets, double e) {
  double tc = -1;
  std::string best = "not reached";
  for (const std::string& set : sets) {
    for (const std::string& m : {set, set + "-auto", set + "-diag"}) {  // every solve alike
      const double t = wp::TimeAtError(table.rows(), "CEODE", m, e);
      if (t > 0 && (tc < 0 || t < tc)) tc = t, best = m;
    }
  }
  const double tr = wp::TimeAtError(table.rows(), "odeint", "rk4", e);
  std::printf("CEODE best (%s) / odeint rk4 at %.0e: %.3e s / %.3e s = %.3f%s\n", best.c_str(), e,
              tc, tr, tc > 0 && tr > 0 ? tc / tr : 0.0,
              tc > 0 && tr > 0 ? (tc <= tr ? " (CEODE at least as fast)" : " (CEODE SLOWER)")
                               : " (not reached)");
}

#endif

constexpr double kRoundOff = 3e-14;  // below: the sweep of a fixed-step curve stops

struct Plan {
  std::vector<double> steps, fine_steps, tols, ce_tols;
  std::vector<std::string> sets, adaptive_sets;
};

// The sets swept on the finer grid with AUTO.
bool OnFineGrid(const std::string& set) {
  return set == "G5_O4" || set == "G6_O5" || set == "G6_O6" || set == "G7_O7" || set == "G8_O8";
}

Plan MakePlan(bool quick) {
  std::vector<long> ns = {100, 200, 500, 1000, 2000, 5000, 10000, 20000, 50000, 100000};
  std::vector<long> fine = {100, 150, 200, 250, 300, 400, 500, 700, 1000, 2000, 5000};
  Plan plan;
  plan.tols = {1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13};
  plan.sets = {"G3_CD", "G4_A34", "G5",    "G5_TOP", "G5_ONES",
               "G5_O4", "G6_O5",  "G6_O6", "G7_O7",  "G8_O8"};
  plan.ce_tols = {1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13, 1e-14};
  plan.adaptive_sets = {"G5_O4", "G6_O5", "G7_O7", "G8_O8"};
  if (quick) {
    ns = fine = {200, 1000};
    plan.tols = {1e-5, 1e-9};
    plan.sets = {"G5", "G8_O8"};
    plan.ce_tols = {1e-6, 1e-10};
    plan.adaptive_sets = {"G6_O5", "G8_O8"};
  }
  for (long n : ns) plan.steps.push_back(kTend / static_cast<double>(n));
  for (long n : fine) plan.fine_steps.push_back(kTend / static_cast<double>(n));
  return plan;
}

wp::Problem MakeProblem(Scene* scene) {
  wp::Problem p;
  p.n = 1;
  p.Lift<AccelFn>();
  p.user = scene;
  p.tend = kTend;
  p.x0 = {0.0};
  p.v0 = {0.0};
  p.err = Err;
  p.vjac = VelJac;
  p.vel_diag = {-0.5};  // f is affine in theta'
  p.end_only = true;
  return p;
}

// CEODE's sets (implicit path, Newton and AUTO, analytic df/dtheta'; on the finer grid also the
// exact one-f solve of CEodeSetVelJacDiagonal, "-diag").
void RunCeode(SUNContext ctx, const wp::Problem& p, const Plan& plan, wp::Table* table) {
  // One curve over steps, stopped below round-off.
  const auto sweep = [&](const wp::CeodeOpts& c, const std::vector<double>& steps,
                         const std::string& label) {
    for (double h : steps) {
      wp::Outcome o;
      if (!wp::MeasureCeode(table, ctx, p, c, h, label, &o)) continue;
      if (o.error < kRoundOff) break;
    }
  };
  wp::CeodeOpts c;
  c.vel = true;
  // Newton (the default), then AUTO: prediction-correction where kappa ||df/dv|| is small.
  for (int mode : {CE_IMPLICIT_NEWTON, CE_IMPLICIT_AUTO}) {
    c.implicit_mode = mode;
    for (const std::string& m : plan.sets) {
      const std::string label = mode == CE_IMPLICIT_AUTO ? m + "-auto" : m;
      c.method = m.c_str();
      const bool fine = mode == CE_IMPLICIT_AUTO && OnFineGrid(m);
      sweep(c, fine ? plan.fine_steps : plan.steps, label);
    }
  }
  c.diagonal = true;
  for (const std::string& m : plan.sets) {
    if (!OnFineGrid(m)) continue;
    c.method = m.c_str();
    sweep(c, plan.fine_steps, m + "-diag");
  }
  c.diagonal = false;
  // Error control at the library's default implicit step (AUTO).
  c.implicit_mode = CE_IMPLICIT_AUTO;
  for (const std::string& m : plan.adaptive_sets) {
    c.method = m.c_str();
    wp::MeasureTolCurve(table, ctx, p, {"", c, plan.ce_tols});
  }
}

// ARKODE (RK3 at the same h, adaptive ERK) and CVODE (Adams, BDF); false if no RK3 table.
bool RunSundials(SUNContext ctx, const wp::Problem& p, const Plan& plan, wp::Table* table) {
  ARKodeButcherTable rk3 = wp::KuttaRk3();
  if (rk3 == nullptr) return false;
  for (double h : plan.steps) {
    wp::Outcome o;
    if (wp::MeasureSundials(table, ctx, p, {wp::Sun::kErkFixed, 0, rk3}, h, "RK3-Kutta", nullptr,
                            &o) &&
        o.error < kRoundOff) {
      break;
    }
  }
  ARKodeButcherTable_Free(rk3);
  for (wp::Sun kind : {wp::Sun::kErk, wp::Sun::kCvodeAdams, wp::Sun::kCvodeBdf}) {
    for (double tol : plan.tols) wp::MeasureSundials(table, ctx, p, {kind}, tol, "adaptive");
  }
  return true;
}

// The peers, the reference's cross-check and their order checks; returns the problems.
int RunPeers(const wp::Problem& p, const Plan& plan, wp::Table* table) {
#ifdef CEODE_BENCH_PEERS
  peers::Setup();
  int bad = CrossCheck(p) ? 0 : 1;
  peers::MeasurePeers<1>(table, p, plan.steps, plan.tols, 1.0);
  return bad + peers::CheckPeerOrders(*table, 1e-12, 1e-2);
#else
  (void)p, (void)plan, (void)table;
  std::printf("(built without GSL/Boost: no odeint/GSL peer curves)\n");
  return 0;
#endif
}

}  // namespace

int main(int argc, char** argv) {
  const wp::Args args = wp::ParseArgs(argc, argv);
  SUNContext ctx = nullptr;
  if (wp::Failed(SUNContext_Create(SUN_COMM_NULL, &ctx), "SUNContext_Create")) return 1;
  std::printf(
      "Damped driven pendulum theta'' = -9.81 cos theta - 0.5 theta' + sin 2t, "
      "error = |theta(10) - ref|\n");
  Scene scene;
  int bad = Reference(&scene) ? 0 : 1;
  const Plan plan = MakePlan(args.quick);
  wp::Table table("damped_pendulum", args.csv);
  const wp::Problem p = MakeProblem(&scene);
  RunCeode(ctx, p, plan, &table);
  if (!RunSundials(ctx, p, plan, &table)) ++bad;
  bad += RunPeers(p, plan, &table);
  bad += table.failures();
  wp::PrintEqualError(table, {1e-6, 1e-9, 1e-11});
  wp::PrintAdaptiveEqualError(table, {1e-6, 1e-9, 1e-11});
#ifdef CEODE_BENCH_PEERS
  std::printf("\n");
  for (double e : {1e-6, 1e-9}) PrintAgainstRk4(table, plan.sets, e);
#endif
  std::printf("%d problem(s)\n", bad);
  SUNContext_Free(&ctx);
  return bad == 0 ? 0 : 1;
}
