// The stability guard on a structural model with a known top frequency: the
// membrane of issue 13 (5-point Laplacian on an N x N grid, spacing 1/(N+1),
// fixed edges, lumped unit masses; N = 316 gives 99 856 DOF). Its top
// eigenvalue is exact: omega_max^2 = 8 (N+1)^2 sin^2(N pi / (2 (N+1))).
// For each set: the guard's estimate against the exact omega_max, then runs at
// multiples of the exact limit h_lim = Omega_max / omega_max with the guard off
// (does the run stay bounded?), in warn mode (message) and refuse mode (flag),
// the run at the warning's recommended step and at CEodeGetStableStep(0.99).
//   guard_membrane [N] [steps]      (defaults 316, 3000)
#include <ceode/ceode.h>
#include <ceode/ceode_stability.h>
#include <nvector/nvector_serial.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace {

struct Grid {
  int N;
  double inv_dx2;
};

int Membrane(sunrealtype, N_Vector x, N_Vector, N_Vector f, void* data) {
  const auto* g = static_cast<const Grid*>(data);
  const int N = g->N;
  const double* u = N_VGetArrayPointer(x);
  double* a = N_VGetArrayPointer(f);
  for (int i = 0; i < N; ++i) {
    for (int j = 0; j < N; ++j) {
      const int k = i * N + j;
      const double s = (i > 0 ? u[k - N] : 0) + (i + 1 < N ? u[k + N] : 0) +
                       (j > 0 ? u[k - 1] : 0) + (j + 1 < N ? u[k + 1] : 0);
      a[k] = g->inv_dx2 * (s - 4 * u[k]);
    }
  }
  return 0;
}

struct Msg {
  int flag = 0;
  std::string text;
};

void Capture(int flag, const char*, const char*, char* msg, void* data) {
  auto* m = static_cast<Msg*>(data);
  m->flag = flag;
  m->text = msg;
}

struct Outcome {
  int flag;
  long steps;
  double xmax;
  double omega_est;
  long nfe_guard;
  Msg msg;
};

// steps fixed steps of set at h from the lowest mode, guard in mode (-1: off).
Outcome Run(SUNContext ctx, const Grid& g, const char* set, double h, int mode, long steps) {
  const int N = g.N;
  N_Vector x = N_VNew_Serial(N * N, ctx);
  N_Vector v = N_VNew_Serial(N * N, ctx);
  for (int i = 0; i < N; ++i) {
    for (int j = 0; j < N; ++j) {
      NV_Ith_S(x, i * N + j) =
          std::sin(M_PI * (i + 1) / (N + 1)) * std::sin(M_PI * (j + 1) / (N + 1));
    }
  }
  N_VConst(0, v);
  Outcome o{};
  void* mem = CEodeCreate(ctx);
  CEodeInit(mem, Membrane, 0, x, v);
  CEodeSetUserData(mem, const_cast<Grid*>(&g));
  CEodeSetMethodByName(mem, set);
  CEodeSetFixedStep(mem, h);
  CEodeSetErrHandlerFn(mem, Capture, &o.msg);
  CEodeSetStabilityGuard(mem, mode < 0 ? CE_GUARD_OFF : mode, 0);
  sunrealtype t = 0;
  o.flag = CEodeEvolve(mem, steps * h, x, v, &t, CE_NORMAL);
  CEodeGetNumSteps(mem, &o.steps);
  CEodeGetMaxFrequencyEstimate(mem, &o.omega_est);
  long int nme_guard = 0, nsetups_guard = 0;
  CEodeGetGuardStats(mem, &o.nfe_guard, &nme_guard, &nsetups_guard);
  o.xmax = N_VMaxNorm(x);
  CEodeFree(&mem);
  N_VDestroy(x);
  N_VDestroy(v);
  return o;
}

double StableStep(SUNContext ctx, const Grid& g, const char* set) {
  const int N = g.N;
  N_Vector x = N_VNew_Serial(N * N, ctx);
  N_Vector v = N_VNew_Serial(N * N, ctx);
  N_VConst(0.5, x);
  N_VConst(0, v);
  void* mem = CEodeCreate(ctx);
  CEodeInit(mem, Membrane, 0, x, v);
  CEodeSetUserData(mem, const_cast<Grid*>(&g));
  CEodeSetMethodByName(mem, set);
  sunrealtype hmax = 0;
  CEodeGetStableStep(mem, 0, &hmax);
  CEodeFree(&mem);
  N_VDestroy(x);
  N_VDestroy(v);
  return hmax;
}

// The recommended step of a warning ("h <= X ... is stable"), 0 when none.
double Recommended(const std::string& msg) {
  const auto p = msg.find("h <= ");
  return p == std::string::npos ? 0 : std::atof(msg.c_str() + p + 5);
}

const char* Verdict(const Outcome& o, long steps) {
  if (o.flag < 0 && o.steps == 0) return "refused";
  if (o.flag < 0) return "diverged";
  return o.xmax <= 2 && o.steps == steps ? "bounded" : "grew";
}

}  // namespace

int main(int argc, char** argv) {
  const int N = argc > 1 ? std::atoi(argv[1]) : 316;
  const long steps = argc > 2 ? std::atol(argv[2]) : 3000;
  const Grid g{N, double(N + 1) * (N + 1)};
  const double omega = std::sqrt(8.0) * (N + 1) * std::sin(N * M_PI / (2.0 * (N + 1)));
  SUNContext ctx = nullptr;
  SUNContext_Create(nullptr, &ctx);
  std::printf("membrane %d x %d = %d DOF, omega_max exact = %.6f, %ld steps per run\n", N, N, N * N,
              omega, steps);
  int bad = 0;
  for (const char* set : {"G3_CD", "G4_A34"}) {
    int degree = 0;
    sunrealtype p[8];
    CEodeGetMethodParams(set, &degree, p, 8);
    sunrealtype lim = 0;
    CEodeStabilityLimit(degree, p, 0, &lim);
    const double hlim = lim / omega;
    const Outcome est = Run(ctx, g, set, 0.5 * hlim, CE_GUARD_WARN, 1);
    std::printf("%s: Omega_max = %.9g, h_lim = %.9g; estimate %.6f (%+.4f %%, %ld f evals)\n", set,
                lim, hlim, est.omega_est, 100 * (est.omega_est / omega - 1), est.nfe_guard);
    bad += est.omega_est < omega;
    for (double fac : {0.99, 1.0001, 1.001, 1.01}) {
      const Outcome off = Run(ctx, g, set, fac * hlim, -1, steps);
      const Outcome warn = Run(ctx, g, set, fac * hlim, CE_GUARD_WARN, 1);
      const Outcome refuse = Run(ctx, g, set, fac * hlim, CE_GUARD_REFUSE, 1);
      std::printf("  h = %.4f h_lim: guard off %s (%ld steps, max|x| %.3g); warn: %s; refuse: %s\n",
                  fac, Verdict(off, steps), off.steps, off.xmax,
                  warn.msg.flag == CE_WARNING ? "warned" : "silent",
                  refuse.flag == CE_UNSTABLE ? "CE_UNSTABLE" : "ran");
      if (warn.msg.flag == CE_WARNING) {
        std::printf("    message: %s\n", warn.msg.text.c_str());
        const double hr = Recommended(warn.msg.text);
        const Outcome rec = Run(ctx, g, set, hr, -1, steps);
        std::printf("    recommended h = %.9g = %.6f h_lim: %s\n", hr, hr / hlim,
                    Verdict(rec, steps));
        bad += hr >= hlim || std::string(Verdict(rec, steps)) != "bounded";
      }
      bad += fac > 1 && warn.msg.flag != CE_WARNING;
    }
    const double hs = StableStep(ctx, g, set);
    const Outcome st = Run(ctx, g, set, hs, -1, steps);
    std::printf("  CEodeGetStableStep(0.99) = %.9g = %.6f h_lim: %s\n", hs, hs / hlim,
                Verdict(st, steps));
    bad += hs >= hlim;
  }
  SUNContext_Free(&ctx);
  std::printf("%s\n", bad == 0 ? "all guard checks passed" : "SOME GUARD CHECKS FAILED");
  return bad == 0 ? 0 : 1;
}
