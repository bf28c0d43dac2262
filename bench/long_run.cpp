// -----------------------------------------------------------------------------
// long_run: what each named parameter set conserves over 10^7 steps.
//
// Problem: the IFToMM simple pendulum of examples/pendulum_ode.c,
//   theta'' = -(g/L) cos(theta), theta(0) = theta'(0) = 0, g = 9.81, L = m = 1,
// whose exact flow conserves E = 1/2 m L^2 theta'^2 + m g L sin(theta) (E0 = 0).
// Every set runs N steps of size h and N*h/h2 steps of size h2 (same end time T),
// explicit path, no stability guard, no compensated summation. At every step
// (CE_ONE_STEP, theta and theta' at the same instant) the energy error dE(t) = E(t)
// enters a least-squares line dE ~ a + b t; b is the drift rate. The ripple is
// max |dE| over the first 1 % of the run. A set is "linear drift" when the drift
// over the run |b| T exceeds that ripple, "bounded" otherwise; the exponent p of
// b ~ h^p comes from the two step sizes. Round-off shows as the growth of max |dE|
// from the first to the last 1 % of a bounded run.
//
// Usage: long_run [--steps N] [--h H] [--h2 H2] [--problem pendulum|oscillator] [--only NAME]
//                 [--csv FILE]
//   defaults N = 1e7, h = 1e-3, h2 = 2e-3 (the measurement in docs/stability.md).
// Not a test: it takes minutes; its table goes to docs/stability.md.
// -----------------------------------------------------------------------------
#include <ceode/ceode.h>
#include <nvector/nvector_serial.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

namespace {

constexpr double kGrav = 9.81;
constexpr double kLen = 1.0;

int Rhs(sunrealtype, N_Vector x, N_Vector, N_Vector f, void*) {
  NV_Ith_S(f, 0) = -(kGrav / kLen) * std::cos(NV_Ith_S(x, 0));
  return 0;
}

double Energy(double th, double om) {
  return 0.5 * kLen * kLen * om * om + kGrav * kLen * std::sin(th);
}

// --problem oscillator: the linear oscillator x'' = -g x (the pendulum's frequency at the bottom)
// from x = 1 at rest, dE = v^2/2 + g x^2/2 - g/2. The stability analysis holds exactly for this
// test equation, so weak instability (rho > 1 for every h) shows here first.
int OscRhs(sunrealtype, N_Vector x, N_Vector, N_Vector f, void*) {
  NV_Ith_S(f, 0) = -kGrav * NV_Ith_S(x, 0);
  return 0;
}

double OscEnergy(double x, double v) { return 0.5 * v * v + 0.5 * kGrav * x * x - 0.5 * kGrav; }

bool g_oscillator = false;  // the problem of this run (set once from the command line)

struct Result {
  bool ok = false;
  double t_fail = 0;     // time of the first non-finite or |dE| > 1 state (0: none)
  double ripple = 0;     // max |dE| over the first 1 % of the run
  double mid = 0;        // max |dE| over the 1 % of the run before T/2
  double late = 0;       // max |dE| over the last 1 % of the run
  double max_err = 0;    // max |dE| over the run
  double slope = 0;      // least-squares drift rate of dE per unit time
  double final_err = 0;  // dE at T
};

// Least-squares sums about the run's midpoint (t - T/2 keeps them well conditioned).
struct LineFit {
  long double n = 0, st = 0, stt = 0, se = 0, ste = 0;
  void Add(double t, double e) {
    n += 1;
    st += t;
    stt += static_cast<long double>(t) * t;
    se += e;
    ste += static_cast<long double>(t) * e;
  }
  double Slope() const {
    const long double den = n * stt - st * st;
    return den > 0 ? static_cast<double>((n * ste - st * se) / den) : 0.0;
  }
};

Result Run(SUNContext ctx, const char* method, double h, long steps) {
  Result r;
  N_Vector x = N_VNew_Serial(1, ctx);
  N_Vector v = N_VNew_Serial(1, ctx);
  NV_Ith_S(x, 0) = g_oscillator ? 1.0 : 0.0;
  NV_Ith_S(v, 0) = 0.0;
  void* mem = CEodeCreate(ctx);
  const double T = h * static_cast<double>(steps);
  bool fail = CEodeInit(mem, g_oscillator ? OscRhs : Rhs, 0.0, x, v) != CE_SUCCESS;
  fail = fail || CEodeSetMethodByName(mem, method) != CE_SUCCESS;
  fail = fail || CEodeSetFixedStep(mem, h) != CE_SUCCESS;
  fail = fail || CEodeSetStabilityGuard(mem, CE_GUARD_OFF, 0) != CE_SUCCESS;
  fail = fail || CEodeSetMaxNumSteps(mem, steps + 10) != CE_SUCCESS;
  const long win = steps / 100;
  LineFit fit;
  double t = 0;
  for (long k = 1; !fail && k <= steps; ++k) {
    fail = CEodeEvolve(mem, T + h, x, v, &t, CE_ONE_STEP) < 0;
    const double e = g_oscillator ? OscEnergy(NV_Ith_S(x, 0), NV_Ith_S(v, 0))
                                  : Energy(NV_Ith_S(x, 0), NV_Ith_S(v, 0));
    if (fail || !std::isfinite(e) || std::fabs(e) > 1) {
      r.t_fail = t;
      fail = true;
      break;
    }
    const double ae = std::fabs(e);
    if (ae > r.max_err) r.max_err = ae;
    if (k <= win && ae > r.ripple) r.ripple = ae;
    if (k > steps - win && ae > r.late) r.late = ae;
    if (k > steps / 2 - win && k <= steps / 2 && ae > r.mid) r.mid = ae;
    fit.Add(t - 0.5 * T, e);
    r.final_err = e;
  }
  r.ok = !fail;
  r.slope = fit.Slope();
  CEodeFree(&mem);
  N_VDestroy(x);
  N_VDestroy(v);
  return r;
}

const char* Verdict(const Result& r, double T) {
  if (!r.ok) return "unstable";
  // A linear drift doubles from T/2 to T; exponential growth multiplies far more.
  if (r.late > 4 * r.mid && r.late > 4 * r.ripple) return "growing";
  return std::fabs(r.slope) * T > r.ripple ? "linear drift" : "bounded";
}

}  // namespace

int main(int argc, char** argv) {
  long steps = 10000000L;
  double h = 1e-3, h2 = 2e-3;
  const char* only = nullptr;
  FILE* csv = nullptr;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--steps") == 0 && i + 1 < argc) {
      steps = std::atol(argv[++i]);
    } else if (std::strcmp(argv[i], "--h") == 0 && i + 1 < argc) {
      h = std::atof(argv[++i]);
    } else if (std::strcmp(argv[i], "--h2") == 0 && i + 1 < argc) {
      h2 = std::atof(argv[++i]);
    } else if (std::strcmp(argv[i], "--problem") == 0 && i + 1 < argc) {
      g_oscillator = std::strcmp(argv[++i], "oscillator") == 0;
    } else if (std::strcmp(argv[i], "--only") == 0 && i + 1 < argc) {
      only = argv[++i];
    } else if (std::strcmp(argv[i], "--csv") == 0 && i + 1 < argc) {
      csv = std::fopen(argv[++i], "w");
      if (csv == nullptr) return 1;
    } else {
      std::fprintf(stderr,
                   "usage: long_run [--steps N] [--h H] [--h2 H2] [--problem pendulum|oscillator] "
                   "[--only NAME] [--csv F]\n");
      return 1;
    }
  }
  SUNContext ctx;
  if (SUNContext_Create(0, &ctx) != 0) return 1;
  const char* problem = g_oscillator ? "oscillator" : "pendulum";
  const double T = h * static_cast<double>(steps);
  const long steps2 = static_cast<long>(std::llround(T / h2));
  std::printf("%s, T = %g s: N = %ld steps of h = %g, %ld steps of h2 = %g\n", problem, T, steps, h,
              steps2, h2);
  std::printf("%-8s %-12s %11s %11s %11s %12s %12s %6s\n", "set", "verdict", "ripple", "mid",
              "late", "drift(h)", "drift(h2)", "p");
  if (csv != nullptr) {
    std::fprintf(csv,
                 "problem,set,h,steps,T,verdict,ripple,mid,late,max_err,final_err,drift_rate,"
                 "t_fail,h2,verdict_h2,ripple_h2,late_h2,drift_rate_h2,p\n");
  }
  for (int i = 0; i < CEodeGetNumMethods(); ++i) {
    const char* name = CEodeGetMethodName(i);
    if (only != nullptr && std::strcmp(only, name) != 0) continue;
    const Result a = Run(ctx, name, h, steps);
    const Result b = Run(ctx, name, h2, steps2);
    const double p = (a.ok && b.ok && a.slope != 0 && b.slope != 0)
                         ? std::log(std::fabs(b.slope / a.slope)) / std::log(h2 / h)
                         : NAN;
    std::printf("%-8s %-12s %11.3e %11.3e %11.3e %12.3e %12.3e %6.2f", name, Verdict(a, T),
                a.ripple, a.mid, a.late, a.slope, b.slope, p);
    if (!a.ok) std::printf("  (h: blew up at t = %.6g)", a.t_fail);
    if (!b.ok) std::printf("  (h2: blew up at t = %.6g)", b.t_fail);
    std::printf("  [h2: %s]\n", Verdict(b, T));
    std::fflush(stdout);
    if (csv != nullptr) {
      std::fprintf(
          csv, "%s,%s,%g,%ld,%g,%s,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6g,%g,%s,%.6e,%.6e,%.6e,%.4f\n",
          problem, name, h, steps, T, Verdict(a, T), a.ripple, a.mid, a.late, a.max_err,
          a.final_err, a.slope, a.t_fail, h2, Verdict(b, T), b.ripple, b.late, b.slope, p);
    }
  }
  if (csv != nullptr) std::fclose(csv);
  SUNContext_Free(&ctx);
  return 0;
}
