// -----------------------------------------------------------------------------
// membrane_driver: the cost per step of CEODE driven as a user drives it, CE_NORMAL to output
// times every kOutputEvery steps, against a hand-written leapfrog with the same f and the same
// outputs, side by side in one run.
//
// Problem: a 2-D membrane, nx x nx grid, 5-point Laplacian with fixed edges and lumped unit masses
// (the f of bench/mpi_membrane_model.h on one NVECTOR_SERIAL: a = k (w + e + n + s - 4 c),
// k = (nx + 1)^2, the same sums in the same order), N = nx^2 unknowns. x(0) is the lowest mode,
// v(0) = 0; h = 0.25 / (nx + 1), so h omega_max < 0.71, far inside the leapfrog's and G3_CD's
// limit of 2.
//   ceode     G3_CD (central differences), CEodeSetFixedStep(h), the guard at its default,
//             CEodeEvolve(tout_k = 30 k h, CE_NORMAL) into xout, vout: every output on the step
//             grid;
//   leapfrog  x_{n+1} = x_n + h v_{n+1/2}, v_{n+1/2} = v_{n-1/2} + h a(x_n), f as its own pass and
//             the kick and drift fused in one; at an output time it writes x_n and
//             v_n = v_{n-1/2} + h/2 a(x_n) into its output arrays (one pass, as CEODE's copy).
// Both are the same central-difference method: the program checks that their outputs agree to
// round-off before timing (exit 1 otherwise).
//
// Usage:
//   membrane_driver [--quick] [--reps R] [N ...]   time per step, R interleaved repetitions per N
//                                                  (default 7; N default 100000 1000000): the
//                                                  median and the range of the ratios
//   membrane_driver --count VARIANT N STEPS        no timing, for valgrind --tool=callgrind
//                                                  (VARIANT ceode or leapfrog; instructions per
//                                                  step = difference of two STEPS divided by their
//                                                  difference: bench/step_cost/instructions.sh
//                                                  membrane)
// -----------------------------------------------------------------------------
#include <ceode/ceode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "ceode_sundials_compat.h"  // SUN_COMM_NULL on SUNDIALS 6.4

namespace {

constexpr long kOutputEvery = 30;  // steps between outputs

struct Grid {
  long nx = 0;
  double k = 0;  // 1 / dx^2
  double h = 0;
  long n() const { return nx * nx; }
};

Grid MakeGrid(long n) {
  Grid g;
  g.nx = std::max(2L, std::lround(std::sqrt(static_cast<double>(n))));
  g.k = static_cast<double>(g.nx + 1) * static_cast<double>(g.nx + 1);
  g.h = 0.25 / static_cast<double>(g.nx + 1);
  return g;
}

// One grid row (bench/mpi_membrane_model.h's Row): the missing neighbour at a side edge is a zero
// term; dn, up: the rows below and above (zeros at the fixed edges).
inline void Row(long nx, double k, const double* dn, const double* c, const double* up, double* a) {
  a[0] = k * ((((0.0 + c[1]) + dn[0]) + up[0]) - 4 * c[0]);
  for (long j = 1; j < nx - 1; ++j) {
    a[j] = k * ((((c[j - 1] + c[j + 1]) + dn[j]) + up[j]) - 4 * c[j]);
  }
  a[nx - 1] = k * ((((c[nx - 2] + 0.0) + dn[nx - 1]) + up[nx - 1]) - 4 * c[nx - 1]);
}

// The f of both drivers: a = f(x) on the whole grid.
__attribute__((noinline)) void Accel(const Grid& g, const double* zeros, const double* x,
                                     double* a) {
  const long nx = g.nx;
  for (long r = 0; r < nx; ++r) {
    const double* dn = r > 0 ? x + (r - 1) * nx : zeros;
    const double* up = r + 1 < nx ? x + (r + 1) * nx : zeros;
    Row(nx, g.k, dn, x + r * nx, up, a + r * nx);
  }
}

struct Problem {
  Grid g;
  std::vector<double> zeros;
};

int CeodeRhs(sunrealtype /*t*/, N_Vector x, N_Vector /*v*/, N_Vector f, void* data) {
  const auto* p = static_cast<const Problem*>(data);
  Accel(p->g, p->zeros.data(), N_VGetArrayPointer(x), N_VGetArrayPointer(f));
  return 0;
}

// The lowest mode, amplitude 1.
void InitialShape(const Grid& g, double* x) {
  const double pi = std::acos(-1.0);
  for (long i = 0; i < g.nx; ++i) {
    const double si = std::sin(pi * static_cast<double>(i + 1) / static_cast<double>(g.nx + 1));
    for (long j = 0; j < g.nx; ++j) {
      x[i * g.nx + j] =
          si * std::sin(pi * static_cast<double>(j + 1) / static_cast<double>(g.nx + 1));
    }
  }
}

// ---- CEODE, as a user drives it -------------------------------------------------------------
struct CeodeDriver {
  const Problem* p;
  SUNContext ctx = nullptr;
  N_Vector x = nullptr, v = nullptr;  // the user's outputs
  void* mem = nullptr;
  long k = 0;  // outputs so far
  double t = 0;
  bool ok = false;

  explicit CeodeDriver(const Problem* prob) : p(prob) {
    if (SUNContext_Create(SUN_COMM_NULL, &ctx) != 0) return;
    x = N_VNew_Serial(p->g.n(), ctx);
    v = N_VNew_Serial(p->g.n(), ctx);
    mem = CEodeCreate(ctx);
    if (x == nullptr || v == nullptr || mem == nullptr) return;
    InitialShape(p->g, N_VGetArrayPointer(x));
    N_VConst(0.0, v);
    ok = CEodeInit(mem, CeodeRhs, 0.0, x, v) == CE_SUCCESS &&
         CEodeSetUserData(mem, const_cast<Problem*>(p)) == CE_SUCCESS &&
         CEodeSetMethodByName(mem, "G3_CD") == CE_SUCCESS &&
         CEodeSetFixedStep(mem, p->g.h) == CE_SUCCESS &&
         CEodeSetMaxNumSteps(mem, 1L << 40) == CE_SUCCESS &&
         CEodeEvolve(mem, 0.0, x, v, &t, CE_NORMAL) >= 0;  // the start and the guard, no step
  }
  ~CeodeDriver() {
    CEodeFree(&mem);
    if (x != nullptr) N_VDestroy(x);
    if (v != nullptr) N_VDestroy(v);
    if (ctx != nullptr) SUNContext_Free(&ctx);
  }
  CeodeDriver(const CeodeDriver&) = delete;
  CeodeDriver& operator=(const CeodeDriver&) = delete;

  // The next `outputs` output times; x and v hold the last output.
  bool Outputs(long outputs) {
    for (long j = 0; j < outputs; ++j) {
      ++k;
      const double tout = static_cast<double>(k * kOutputEvery) * p->g.h;
      if (CEodeEvolve(mem, tout, x, v, &t, CE_NORMAL) != CE_SUCCESS) return false;
    }
    return true;
  }
  const double* X() const { return N_VGetArrayPointer(x); }
  const double* V() const { return N_VGetArrayPointer(v); }
};

// ---- the hand-written leapfrog ---------------------------------------------------------------
struct Leapfrog {
  const Problem* p;
  std::vector<double> x, vh, a, xo, vo;  // x_n, v_{n-1/2}, a(x_n), the outputs
  long n = 0;                            // the step x is at

  explicit Leapfrog(const Problem* prob)
      : p(prob), x(p->g.n()), vh(p->g.n(), 0.0), a(p->g.n()), xo(p->g.n()), vo(p->g.n()) {
    InitialShape(p->g, x.data());
    Accel(p->g, p->zeros.data(), x.data(), a.data());
    const double hh = 0.5 * p->g.h;
    for (long i = 0; i < p->g.n(); ++i) vh[i] = -hh * a[i];  // v_{-1/2} from v(0) = 0
    Step(false);                                             // step 0: no output at t = 0
  }

  // One step from x_n; with output: x_n and v_n into the outputs on the way (the step computes
  // a(x_n), which v_n needs).
  __attribute__((noinline)) void Step(bool output) {
    const long len = p->g.n();
    const double h = p->g.h;
    double* __restrict xp = x.data();
    double* __restrict vp = vh.data();
    const double* __restrict ap = a.data();
    Accel(p->g, p->zeros.data(), xp, a.data());
    if (output) {
      double* __restrict xq = xo.data();
      double* __restrict vq = vo.data();
      const double hh = 0.5 * h;
      for (long i = 0; i < len; ++i) {
        xq[i] = xp[i];
        vq[i] = vp[i] + hh * ap[i];
      }
    }
    for (long i = 0; i < len; ++i) {
      vp[i] += h * ap[i];
      xp[i] += h * vp[i];
    }
    ++n;
  }

  // The next `outputs` output times, kOutputEvery steps each (the last one writes the output);
  // xo and vo hold the last output.
  void Outputs(long outputs) {
    for (long j = 0; j < outputs; ++j) {
      for (long s = 1; s < kOutputEvery; ++s) Step(false);
      Step(true);
    }
  }
};

// ---- the check and the modes -------------------------------------------------------------------
double MaxAbs(const double* a, long n) {
  double m = 0;
  for (long i = 0; i < n; ++i) m = std::max(m, std::fabs(a[i]));
  return m;
}
double MaxDiff(const double* a, const double* b, long n) {
  double m = 0;
  for (long i = 0; i < n; ++i) m = std::max(m, std::fabs(a[i] - b[i]));
  return m;
}

Problem MakeProblem(long n) {
  Problem p;
  p.g = MakeGrid(n);
  p.zeros.assign(static_cast<size_t>(p.g.nx), 0.0);
  return p;
}

// CEODE and the leapfrog are the same central differences: their outputs after `outputs` output
// times agree to round-off (relative 1e-9 of the amplitudes; the difference is the start's and
// the update's rounding, growing with the steps).
bool Agree(long n, long outputs) {
  const Problem p = MakeProblem(n);
  CeodeDriver c(&p);
  Leapfrog l(&p);
  if (!c.ok || !c.Outputs(outputs)) {
    std::fprintf(stderr, "CEODE failed\n");
    return false;
  }
  l.Outputs(outputs);
  const long len = p.g.n();
  const double dx = MaxDiff(c.X(), l.xo.data(), len) / MaxAbs(l.xo.data(), len);
  const double dv = MaxDiff(c.V(), l.vo.data(), len) / MaxAbs(l.vo.data(), len);
  std::printf(
      "check N = %ld, t = %.6g: |x_ceode - x_leapfrog| %.2e, |v_ceode - v_leapfrog| %.2e "
      "(relative to max |x|, max |v|)\n",
      len, c.t, dx, dv);
  return dx < 1e-9 && dv < 1e-9;
}

double Seconds(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// R repetitions, each a block of outputs with CEODE and one with the leapfrog, the order
// alternating; the ratio of the times per step of each repetition.
void Time(long n, int reps) {
  const Problem p = MakeProblem(n);
  CeodeDriver c(&p);
  Leapfrog l(&p);
  if (!c.ok) {
    std::fprintf(stderr, "CEODE setup failed\n");
    std::exit(1);
  }
  const long len = p.g.n();
  const long outputs = std::max(2L, 60000000L / (len * kOutputEvery));  // ~6e7 DOF steps a block
  c.Outputs(1);  // first touches of the buffers: not a step's cost
  l.Outputs(1);
  std::vector<double> ratio, tc, tl;
  for (int r = 0; r < reps; ++r) {
    double t[2] = {0, 0};
    for (int side = 0; side < 2; ++side) {
      const bool ceode = (side == 0) == (r % 2 == 0);
      const auto a = std::chrono::steady_clock::now();
      if (ceode && !c.Outputs(outputs)) std::exit(1);
      if (!ceode) l.Outputs(outputs);
      t[ceode ? 0 : 1] = Seconds(a, std::chrono::steady_clock::now());
    }
    const double steps = static_cast<double>(outputs * kOutputEvery);
    tc.push_back(t[0] / steps);
    tl.push_back(t[1] / steps);
    ratio.push_back(t[0] / t[1]);
  }
  const auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  std::printf(
      "N = %8ld (%ld x %ld), %ld steps a repetition, outputs every %ld: CEODE G3_CD %.4g "
      "s/step, leapfrog %.4g s/step (medians); ratio median %.3f, range %.3f .. %.3f "
      "(%d repetitions)\n",
      len, p.g.nx, p.g.nx, outputs * kOutputEvery, kOutputEvery, median(tc), median(tl),
      median(ratio), *std::min_element(ratio.begin(), ratio.end()),
      *std::max_element(ratio.begin(), ratio.end()), reps);
}

// --count VARIANT N STEPS: STEPS steps (rounded up to whole output blocks) after the set-up.
int CountMode(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: membrane_driver --count ceode|leapfrog N STEPS\n");
    return 2;
  }
  const std::string variant = argv[2];
  const Problem p = MakeProblem(std::atol(argv[3]));
  const long outputs = (std::atol(argv[4]) + kOutputEvery - 1) / kOutputEvery;
  if (variant == "ceode") {
    CeodeDriver c(&p);
    return c.ok && c.Outputs(outputs) ? 0 : 1;
  }
  if (variant == "leapfrog") {
    Leapfrog l(&p);
    l.Outputs(outputs);
    return 0;
  }
  std::fprintf(stderr, "unknown variant %s (ceode, leapfrog)\n", variant.c_str());
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1 && std::strcmp(argv[1], "--count") == 0) return CountMode(argc, argv);
  bool quick = false;
  int reps = 7;
  std::vector<long> sizes;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0) {
      quick = true;
    } else if (std::strcmp(argv[i], "--reps") == 0 && i + 1 < argc) {
      reps = std::max(1, std::atoi(argv[++i]));
    } else {
      sizes.push_back(std::atol(argv[i]));
    }
  }
  if (!Agree(quick ? 2500 : 10000, 10)) {
    std::fprintf(stderr, "CEODE and the leapfrog disagree\n");
    return 1;
  }
  if (quick) return 0;
  if (sizes.empty()) sizes = {100000, 1000000};
  for (long n : sizes) Time(n, reps);
  return 0;
}
