// -----------------------------------------------------------------------------
// wp_pendulum_ode: work-precision scene for the IFToMM simple pendulum
// (docs/theory.md section 11), every solver timed side by side in one run.
//
// Problem: theta'' = -(g/L) cos(theta), theta(0) = theta'(0) = 0 (released from
// the horizontal), g = 9.81, L = 1, m = 1, t in [0, 10] s.
// Reference solution: none needed; the exact flow conserves
// E = 1/2 m L^2 theta'^2 + m g L sin(theta), so error = max |E - E0| over every
// step, with theta and theta' taken at the same instant (docs/theory.md section 11).
//
// Methods:
//  * CEODE G3_CD, G3_A2, G4_A34, G4_A14, G5 at fixed h = 1e-1 ... 1e-5, and the sets a user
//    picks for a smooth problem, G5_O4, G6_O5, G7_O7, G8_O8, at h = 1e-1 ... 1e-3 (a curve stops
//    below an error of 1e-13), one step at a time as the error needs (explicit path: f does not
//    depend on theta');
//  * the same G5 and G3_CD steps as a hand-written loop on raw doubles, and G8_O8's on the
//    smooth sets' steps (wp::HandG8Run): the floor for per-step overhead (its errors must equal
//    CEODE's);
//  * CEODE error control (CEodeSStolerances, rtol = atol = 1e-4 ... 1e-14, config
//    "<set> adaptive", h_or_tol the tolerance) with G5_O4, G6_O5, G7_O7, G8_O8, the stability
//    guard at its defaults; its f evaluations are counted with the run's;
//  * ARKODE ERKStep with Kutta's RK3 (the paper's comparison) at the same h; ERKStep adaptive
//    and CVODE Adams at rtol = atol = 1e-3 ... 1e-12; the peers (bench/peers.h), the
//    symplectic ones too (f depends on theta only).
// Summaries: the best curve per side at equal error (time), and CEODE adaptive against every
// other curve at equal error (f evaluations and time).
//
// Usage: wp_pendulum_ode [--csv FILE] [--quick]
// --quick: fewer steps and tolerances (G8_O8 fixed at h = 2e-2 and 1e-2; CEODE adaptive: G6_O5
// and G8_O8 at 1e-6 and 1e-10).
// Exit code 0 when every run succeeded, ARKODE's RK3 is Kutta's method (checked
// against a hand-written RK3), the hand loops agree with CEODE to 1 %
// (or 1e-13 absolute), G5 at h = 1e-3 is within a factor 2 of the paper's
// 6.71e-11 (its Table 6) and every peer converges at its order
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

constexpr double kGrav = 9.81;
constexpr double kLen = 1.0;
constexpr double kMass = 1.0;
constexpr double kTend = 10.0;

double Energy(double th, double om) {
  return 0.5 * kMass * kLen * kLen * om * om + kMass * kGrav * kLen * std::sin(th);
}

int Accel(double, const double* x, const double*, double* a, void*) {
  a[0] = -(kGrav / kLen) * std::cos(x[0]);
  return 0;
}

// E0 = 0 for the release from the horizontal at rest.
double Err(double, const double* x, const double* v, void*) {
  return std::fabs(Energy(x[0], v[0]));
}

// The G3 step (docs/theory.md section 2, d = 3) written out on doubles.
double HandG3(double alpha, double beta, double h, long* steps) {
  const long n = std::lround(kTend / h);
  double x = 0, v = 0, a = -(kGrav / kLen) * std::cos(x), emax = 0;
  double xn = x + h * v + 0.5 * h * h * a;  // Taylor start
  for (long i = 1; i <= n; ++i) {
    x = xn;
    const double an = -(kGrav / kLen) * std::cos(x);
    v += h * ((1 - beta) * a + beta * an);
    xn = x + (h * v + 0.5 * h * h * ((1 - alpha) * a + alpha * an));
    a = an;
    const double e = std::fabs(Energy(x, v));
    if (e > emax) emax = e;
  }
  *steps = n;
  return emax;
}

// The G5 step (d = 5, parameters alpha, beta, gamma, zeta) on doubles; the
// initial jerk and snap of this problem are exactly 0 (it starts at rest).
double HandG5(const double p[4], double h, long* steps) {
  const double al = p[0], be = p[1], ga = p[2], ze = p[3];
  const long n = std::lround(kTend / h);
  const double h2 = h * h, h3 = h2 * h, h4 = h3 * h;
  double x = 0, v = 0, a = -(kGrav / kLen) * std::cos(x), j = 0, s = 0, emax = 0;
  double xn = x + h * v + 0.5 * h2 * a;
  for (long i = 1; i <= n; ++i) {
    x = xn;
    const double an = -(kGrav / kLen) * std::cos(x);
    // a(t) = a + h j + h^2/2 ((1-ga) s + ga s_new) fixes the new snap.
    const double sn = ((an - a - h * j) * (2 / h2) - (1 - ga) * s) / ga;
    const double st_b = (1 - be) * s + be * sn, st_z = (1 - ze) * s + ze * sn;
    const double st_a = (1 - al) * s + al * sn;
    v += h * a + 0.5 * h2 * j + h3 / 6 * st_b;
    j += h * st_z;
    xn = x + (h * v + 0.5 * h2 * an + h3 / 6 * j + h4 / 24 * st_a);
    a = an;
    s = sn;
    const double e = std::fabs(Energy(x, v));
    if (e > emax) emax = e;
  }
  *steps = n;
  return emax;
}

// ARKODE with the RK3 table must be Kutta's method: 5 steps of h = 0.1 against
// the same steps by hand (see KuttaRk3 for the SUNDIALS 6.4.1 trap it guards).
bool CheckRk3(SUNContext ctx, const wp::Problem& p, ARKodeButcherTable rk3) {
  const double h = 0.1;
  double y[2] = {0, 0};
  for (int i = 0; i < 5; ++i) {
    double k1[2], k2[2], k3[2], s[2];
    k1[0] = y[1], k1[1] = -(kGrav / kLen) * std::cos(y[0]);
    s[0] = y[0] + 0.5 * h * k1[0], s[1] = y[1] + 0.5 * h * k1[1];
    k2[0] = s[1], k2[1] = -(kGrav / kLen) * std::cos(s[0]);
    s[0] = y[0] + h * (2 * k2[0] - k1[0]), s[1] = y[1] + h * (2 * k2[1] - k1[1]);
    k3[0] = s[1], k3[1] = -(kGrav / kLen) * std::cos(s[0]);
    for (int j = 0; j < 2; ++j) y[j] += h * (k1[j] / 6 + 2 * k2[j] / 3 + k3[j] / 6);
  }
  N_Vector v = N_VNew_Serial(2, ctx);
  if (v == nullptr) return false;
  N_VConst(0, v);
  void* mem = ERKStepCreate(p.f1, 0.0, v, ctx);
  sunrealtype t = 0;
  bool ok = mem != nullptr && !wp::Failed(ERKStepSetTable(mem, rk3), "ERKStepSetTable") &&
            !wp::Failed(ERKStepSetFixedStep(mem, h), "ERKStepSetFixedStep");
  for (int i = 0; ok && i < 5; ++i) {
    ok = !wp::Failed(ERKStepEvolve(mem, 10.0, v, &t, ARK_ONE_STEP), "ERKStepEvolve");
  }
  ok = ok && std::fabs(NV_Ith_S(v, 0) - y[0]) < 1e-12 && std::fabs(NV_Ith_S(v, 1) - y[1]) < 1e-12;
  std::printf("ARKODE RK3 table == Kutta's RK3 by hand after 5 steps: %s\n", ok ? "yes" : "NO");
  ERKStepFree(&mem);
  N_VDestroy(v);
  return ok;
}

}  // namespace

int main(int argc, char** argv) {
  const wp::Args args = wp::ParseArgs(argc, argv);
  SUNContext ctx = nullptr;
  if (wp::Failed(SUNContext_Create(SUN_COMM_NULL, &ctx), "SUNContext_Create")) return 1;
  std::printf("IFToMM simple pendulum, 10 s, error = max |E - E0| (J)\n");
  wp::Table table("pendulum_ode", args.csv);

  wp::Problem p;
  p.n = 1;
  p.Lift<Accel>();
  p.tend = kTend;
  p.x0 = {0.0};
  p.v0 = {0.0};
  p.err = Err;
  p.separable = true;  // f depends on theta only: the symplectic peers apply

  std::vector<double> steps = {1e-1, 1e-2, 1e-3, 1e-4, 1e-5};
  std::vector<double> tols = {1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12};
  // CEODE's tolerances reach below ERKStep's: its energy error is 10 to 100 times the tolerance.
  std::vector<double> ce_tols = {1e-4,  1e-5,  1e-6,  1e-7,  1e-8, 1e-9,
                                 1e-10, 1e-11, 1e-12, 1e-13, 1e-14};
  std::vector<const char*> adaptive_sets = {"G5_O4", "G6_O5", "G7_O7", "G8_O8"};
  if (args.quick) {
    steps = {1e-2, 1e-3};
    tols = {1e-4, 1e-8};
    ce_tols = {1e-6, 1e-10};
    adaptive_sets = {"G6_O5", "G8_O8"};
  }
  int bad = 0;
  double g5_1e3 = -1;
  const char* methods[] = {"G3_CD", "G3_A2", "G4_A34", "G4_A14", "G5"};
  for (const char* m : methods) {
    for (double h : steps) {
      wp::MeasureCeode(&table, ctx, p, m, h, false, m);
      if (std::string(m) == "G5" && std::fabs(h - 1e-3) < 1e-15) {
        wp::Outcome o;
        if (wp::CeodeRun(ctx, p, m, h, &o) == 0) g5_1e3 = o.error;
      }
    }
  }

  // The sets a user picks for a smooth problem at fixed steps: h down to 1e-3, where G5_O4 is at
  // 1e-12 and the others at rounding.
  std::vector<const char*> smooth_sets = {"G5_O4", "G6_O5", "G7_O7", "G8_O8"};
  std::vector<double> smooth_steps = {1e-1, 5e-2, 2e-2, 1e-2, 5e-3, 2e-3, 1e-3};
  if (args.quick) smooth_sets = {"G8_O8"}, smooth_steps = {2e-2, 1e-2};
  for (const char* m : smooth_sets) {
    for (double h : smooth_steps) {
      wp::Outcome o;
      if (wp::MeasureCeode(&table, ctx, p, m, h, false, m, &o) && o.error < 1e-13) break;
    }
  }
  // G8_O8's steps by hand on the same grid: the method's floor (wp::MeasureHandG8 checks its
  // errors against CEODE's; a failure row counts as a problem).
  for (double h : smooth_steps) {
    wp::Outcome o;
    if (!wp::MeasureHandG8(&table, ctx, p, h, 1e-13, &o) || o.error < 1e-13) break;
  }

  // Error control with the sets a user picks for a smooth problem.
  for (const char* m : adaptive_sets) {
    wp::MeasureTolCurve(&table, ctx, p, {"", wp::CeodeOpts(m), ce_tols});
  }

  // Hand-written loops: the same arithmetic without any API or N_Vector.
  double g5p[4];
  int g5deg = 0;
  if (wp::Failed(CEodeGetMethodParams("G5", &g5deg, g5p, 4), "CEodeGetMethodParams")) ++bad;
  for (double h : steps) {
    for (int which = 0; which < 2; ++which) {
      const std::string cfg = which == 0 ? "G5" : "G3_CD";
      long nst = 0;
      double err = which == 0 ? HandG5(g5p, h, &nst) : HandG3(1.0, 0.5, h, &nst);
      volatile double sink = 0;
      const double secs = wp::TimeMedian([&]() {
        long dummy;
        sink = which == 0 ? HandG5(g5p, h, &dummy) : HandG3(1.0, 0.5, h, &dummy);
        return 0;
      });
      (void)sink;
      wp::Row r;
      r.solver = "CEODE-hand";
      r.config = cfg;
      r.h_or_tol = h;
      r.error = err;
      r.steps = nst;
      r.rhs_evals = nst + 1;
      r.seconds = secs;
      table.Add(r);
      // The loop must be the same method: compare with the library's figure.
      wp::Outcome o;
      if (wp::CeodeRun(ctx, p, cfg.c_str(), h, &o, true) != 0 ||
          std::fabs(o.error - err) > std::max(1e-2 * err, 1e-13)) {
        std::printf("  hand loop %s h=%g: %.6e vs CEODE %.6e -- MISMATCH\n", cfg.c_str(), h, err,
                    o.error);
        ++bad;
      }
    }
  }

  ARKodeButcherTable rk3 = wp::KuttaRk3();
  if (rk3 == nullptr) return 1;
  if (!CheckRk3(ctx, p, rk3)) ++bad;
  for (double h : steps) {
    wp::MeasureSundials(&table, ctx, p, {wp::Sun::kErkFixed, 0, rk3}, h, "RK3-Kutta");
  }
  ARKodeButcherTable_Free(rk3);
  for (wp::Sun kind : {wp::Sun::kErk, wp::Sun::kCvodeAdams}) {
    for (double tol : tols) wp::MeasureSundials(&table, ctx, p, {kind}, tol, "adaptive");
  }

#ifdef CEODE_BENCH_PEERS
  peers::Setup();
  // A finer h grid than CEODE's: RK4 and SB3A go from pre-asymptotic (h = 0.1) to
  // round-off (h = 1e-3) within two decades, and their order fits need points between.
  std::vector<double> peer_steps = {1e-1, 5e-2, 2e-2, 1e-2, 5e-3, 2e-3, 1e-3, 1e-4, 1e-5};
  if (args.quick) peer_steps = {1e-2, 5e-3};
  peers::MeasurePeers<1>(&table, p, peer_steps, tols, 1.0);
  bad += peers::CheckPeerOrders(table, 1e-11, 1e-1);
#else
  std::printf("(built without GSL/Boost: no odeint/GSL peer curves)\n");
#endif
  wp::PrintEqualError(table, {1e-6, 1e-9, 1e-11});
  wp::PrintAdaptiveEqualError(table, {1e-6, 1e-9, 1e-11});
  bad += table.failures();
  if (!args.quick) {
    const bool ok = g5_1e3 > 0 && g5_1e3 < 2 * 6.71e-11 && g5_1e3 > 6.71e-11 / 2;
    std::printf("G5 at h = 1e-3: %.3e (paper 6.71e-11) %s\n", g5_1e3, ok ? "ok" : "-- OFF");
    if (!ok) ++bad;
  }
  std::printf("%d problem(s)\n", bad);
  SUNContext_Free(&ctx);
  return bad == 0 ? 0 : 1;
}
