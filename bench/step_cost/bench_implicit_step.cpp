// -----------------------------------------------------------------------------
// bench_implicit_step: the cost of one velocity-dependent (implicit) CEODE step
// against one explicit step of the same problem, side by side in one run.
//
// Problems (serial N_Vectors, CEodeEvolve(CE_ONE_STEP), h = 1e-3, guard off):
//  * n = 1: damped driven pendulum theta'' = -(g/L) cos(theta) - 0.5 theta' + sin(2t),
//    g/L = 9.81, theta(0) = 0.3, theta'(0) = 0; G4_A34.
//  * n = 3: heavy symmetric top in ZXZ Euler angles (../oscillators/top_model.h); G5_TOP.
// Configurations of each problem:
//  * explicit   CEodeSetVelocityDependence(SUNFALSE): f sees the previous velocity
//               (the cost floor of a step, not an accurate answer);
//  * pc k=1/2   CE_IMPLICIT_PC with 1 or 2 corrections;
//  * auto       CE_IMPLICIT_AUTO (a dense linear solver attached for its Newton side);
//  * newton     CE_IMPLICIT_NEWTON, dense, difference-quotient df/dv (the default path).
// Printed: ns per step (median of 5 repetitions of the process CPU time) and the
// ratio to the explicit step. Checked (exit 1 on failure, never on a timing): every
// run succeeds and the PC and AUTO answers agree with Newton's to 1e-5 after 1 s.
//
// Usage: bench_implicit_step [--quick] [--only NAME --steps N [--set SET] [--normal]]
//   --only runs one configuration (e.g. "top/pc k=2") for N steps without timing:
//   for callgrind, per-step instructions = difference of two step counts (each block of 1000
//   steps starts again, in both); --set replaces the problem's set, --normal takes each block's
//   steps in one CE_NORMAL call instead of CE_ONE_STEP calls.
// -----------------------------------------------------------------------------
#include <ceode/ceode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

#include "oscillators/top_model.h"
#include "wp_common.h"  // the clock, CeodeRhs (the top's acceleration lifted to CEODE's form)

namespace {

constexpr double kStep = 1e-3;
constexpr long kBlock = 1000;

int PendulumRhs(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, void*) {
  NV_Ith_S(f, 0) = -9.81 * std::cos(NV_Ith_S(x, 0)) - 0.5 * NV_Ith_S(v, 0) + std::sin(2 * t);
  return 0;
}

struct Problem {
  const char* name;
  int n;
  CEodeRhsFn f;
  const char* method;
  std::vector<double> x0, v0;
};

struct Config {
  const char* name;
  int vel;   // CEodeSetVelocityDependence
  int mode;  // CEodeSetImplicitMode
  int k;     // CEodeSetPCCorrections
};

const Config kConfigs[] = {
    {"explicit", SUNFALSE, CE_IMPLICIT_NEWTON, 0}, {"pc k=1", SUNTRUE, CE_IMPLICIT_PC, 1},
    {"pc k=2", SUNTRUE, CE_IMPLICIT_PC, 2},        {"auto", SUNTRUE, CE_IMPLICIT_AUTO, 0},
    {"newton", SUNTRUE, CE_IMPLICIT_NEWTON, 0},
};

// Runs `steps` steps after the start, one CE_ONE_STEP call each (normal: a block's in one
// CE_NORMAL call); returns seconds per step (< 0: failure) and x at the end.
double RunSteps(const Problem& p, const Config& c, long steps, std::vector<double>* xend,
                double h = kStep, long block = kBlock, bool normal = false) {
  SUNContext ctx = nullptr;
  if (SUNContext_Create(SUN_COMM_NULL, &ctx) != 0) return -1;
  top::Top top;
  N_Vector x = N_VNew_Serial(p.n, ctx), v = N_VNew_Serial(p.n, ctx);
  SUNMatrix A = SUNDenseMatrix(p.n, p.n, ctx);
  SUNLinearSolver LS = SUNLinSol_Dense(x, A, ctx);
  void* mem = CEodeCreate(ctx);
  N_Vector x0 = N_VNew_Serial(p.n, ctx), v0 = N_VNew_Serial(p.n, ctx);
  std::copy(p.x0.begin(), p.x0.end(), N_VGetArrayPointer(x0));
  std::copy(p.v0.begin(), p.v0.end(), N_VGetArrayPointer(v0));
  N_VScale(1, x0, x);
  N_VScale(1, v0, v);
  bool ok = mem != nullptr && LS != nullptr && CEodeInit(mem, p.f, 0, x, v) == CE_SUCCESS &&
            CEodeSetUserData(mem, &top) == CE_SUCCESS &&
            CEodeSetMethodByName(mem, p.method) == CE_SUCCESS &&
            CEodeSetFixedStep(mem, h) == CE_SUCCESS &&
            CEodeSetStabilityGuard(mem, CE_GUARD_OFF, 0) == CE_SUCCESS &&
            CEodeSetMaxNumSteps(mem, 1L << 40) == CE_SUCCESS &&
            CEodeSetVelocityDependence(mem, c.vel) == CE_SUCCESS &&
            CEodeSetImplicitMode(mem, c.mode) == CE_SUCCESS &&
            CEodeSetPCCorrections(mem, c.k) == CE_SUCCESS &&
            (c.vel == SUNFALSE || CEodeSetLinearSolver(mem, LS, A) == CE_SUCCESS);
  sunrealtype t = 0;
  double clock = 0;
  // Blocks of kBlock steps from the initial state (the lagged velocity of the explicit step
  // makes the top unstable after about 1250 steps); the start (CEodeReInit and the first step)
  // is not a step and stays off the clock.
  for (long done = 0; ok && done < steps; done += block) {
    ok = (done == 0 || CEodeReInit(mem, 0, x0, v0) == CE_SUCCESS) &&
         CEodeEvolve(mem, 1e9, x, v, &t, CE_ONE_STEP) == CE_SUCCESS;
    const long n = std::min(block, steps - done);
    const double t0 = wp::Now();
    if (normal) {
      ok = CEodeEvolve(mem, h * static_cast<double>(n + 1), x, v, &t, CE_NORMAL) == 0;
    }
    for (long i = 0; ok && !normal && i < n; ++i) {
      ok = CEodeEvolve(mem, 1e9, x, v, &t, CE_ONE_STEP) == 0;
    }
    clock += wp::Now() - t0;
  }
  const double per_step = clock / static_cast<double>(std::max(steps, 1L));
  if (xend != nullptr) xend->assign(N_VGetArrayPointer(x), N_VGetArrayPointer(x) + p.n);
  CEodeFree(&mem);
  SUNLinSolFree(LS);
  SUNMatDestroy(A);
  for (N_Vector w : {x, v, x0, v0}) N_VDestroy(w);
  SUNContext_Free(&ctx);
  return ok ? per_step : -1;
}

double MedianPerStep(const Problem& p, const Config& c, long steps) {
  std::vector<double> t;
  for (int r = 0; r < 5; ++r) {
    const double s = RunSteps(p, c, steps, nullptr);
    if (s < 0) return -1;
    t.push_back(s);
  }
  std::sort(t.begin(), t.end());
  return t[2];
}

std::vector<Problem> Problems() {
  const double pi = std::acos(-1.0);
  return {{"pendulum", 1, PendulumRhs, "G4_A34", {0.3}, {0.0}},
          {"top", 3, wp::CeodeRhs<top::Accel>, "G5_TOP", {0.0, pi / 6, 0.0}, {0.0, 0.0, 4 * pi}}};
}

// PC and AUTO against Newton after 1 s (one block), beside Newton's own error there (against
// Newton at h/8, whose error is 8^order times smaller).
int CheckAgreement(const Problem& p) {
  std::vector<double> ref, fine, x;
  if (RunSteps(p, kConfigs[4], 999, &ref) < 0) return 1;
  if (RunSteps(p, kConfigs[4], 7999, &fine, kStep / 8, 8000) < 0) return 1;
  double e = 0;
  for (int j = 0; j < p.n; ++j) e = std::max(e, std::fabs(ref[j] - fine[j]));
  std::printf("  %-9s newton  |x - x(h/8)| at t = 1: %.2e (Newton's own error)\n", p.name, e);
  int bad = 0;
  for (int i = 1; i <= 3; ++i) {
    if (RunSteps(p, kConfigs[i], 999, &x) < 0) return 1;
    double d = 0;
    for (int j = 0; j < p.n; ++j) d = std::max(d, std::fabs(x[j] - ref[j]));
    std::printf("  %-9s %-7s |x - x_newton| at t = 1: %.2e\n", p.name, kConfigs[i].name, d);
    if (!(d < 1e-5)) ++bad;
  }
  return bad;
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false;
  std::string only, set;
  bool normal = false;
  long steps = 200000;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0) {
      quick = true;
    } else if (std::strcmp(argv[i], "--only") == 0 && i + 1 < argc) {
      only = argv[++i];
    } else if (std::strcmp(argv[i], "--steps") == 0 && i + 1 < argc) {
      steps = std::atol(argv[++i]);
    } else if (std::strcmp(argv[i], "--set") == 0 && i + 1 < argc) {
      set = argv[++i];
    } else if (std::strcmp(argv[i], "--normal") == 0) {
      normal = true;
    } else {
      std::fprintf(stderr,
                   "usage: %s [--quick] [--only PROBLEM/CONFIG --steps N [--set SET] [--normal]]\n",
                   argv[0]);
      return 2;
    }
  }
  if (quick) steps = 20000;
  int bad = 0;
  for (Problem p : Problems()) {
    if (!set.empty()) p.method = set.c_str();
    for (const Config& c : kConfigs) {
      if (!only.empty() && only != std::string(p.name) + "/" + c.name) continue;
      if (!only.empty()) return RunSteps(p, c, steps, nullptr, kStep, kBlock, normal) < 0 ? 1 : 0;
    }
  }
  if (!only.empty()) {
    std::fprintf(stderr, "unknown configuration %s\n", only.c_str());
    return 2;
  }
  std::printf("Implicit against explicit step, h = %g, %ld steps per run, median of 5 (CPU time)\n",
              kStep, steps);
  for (const Problem& p : Problems()) {
    const double base = MedianPerStep(p, kConfigs[0], steps);
    for (const Config& c : kConfigs) {
      const double s = MedianPerStep(p, c, steps);
      if (s < 0 || base < 0) {
        std::printf("  %-9s %-9s FAILED\n", p.name, c.name);
        ++bad;
        continue;
      }
      std::printf("  %-9s n=%d %-9s %8.1f ns/step   implicit/explicit = %.2f\n", p.name, p.n,
                  c.name, 1e9 * s, s / base);
    }
    bad += CheckAgreement(p);
  }
  return bad == 0 ? 0 : 1;
}
