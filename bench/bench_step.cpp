// -----------------------------------------------------------------------------
// bench_step: Google Benchmark of the cost of ONE explicit CEODE step, against
// the same step written by hand on raw doubles (the floor for overhead).
//
// Problems: n independent springs x_i'' = -k_i x_i, k_i = 1 + i/n (n = 1 is the
// 1-DOF oscillator), explicit path, h = 1e-3 (far inside every stability limit).
// Methods: G3_CD (d = 3) and G5 (d = 5); CEODE through CEodeEvolve(CE_ONE_STEP)
// with serial N_Vectors, the hand loop with the docs/theory.md section 2 formulas.
// One benchmark iteration = one step, so "Time" is ns/step; for n > 1 the
// counter ns_per_dof divides it by n.
//
// Usage: bench_step [Google Benchmark flags], e.g.
//   bench_step --benchmark_min_time=0.05 --benchmark_repetitions=5
// The program aborts the benchmark (state.SkipWithError) on any failed call.
// -----------------------------------------------------------------------------
#include <benchmark/benchmark.h>
#include <ceode/ceode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>

#include <cmath>
#include <string>
#include <vector>

#include "ceode_sundials_compat.h"  // SUN_COMM_NULL on SUNDIALS 6.4

namespace {

constexpr double kStep = 1e-3;

struct Springs {
  std::vector<double> k;
};

int SpringRhs(sunrealtype, N_Vector x, N_Vector, N_Vector f, void* user) {
  const std::vector<double>& k = static_cast<Springs*>(user)->k;
  const double* xd = N_VGetArrayPointer(x);
  double* fd = N_VGetArrayPointer(f);
  const size_t n = k.size();
  for (size_t i = 0; i < n; ++i) fd[i] = -k[i] * xd[i];
  return 0;
}

Springs MakeSprings(long n) {
  Springs s;
  s.k.resize(n);
  for (long i = 0; i < n; ++i) s.k[i] = 1.0 + static_cast<double>(i) / static_cast<double>(n);
  return s;
}

// method: 0 = G3_CD, 1 = G5.
void BM_CeodeStep(benchmark::State& state) {
  const long n = state.range(0);
  const char* method = state.range(1) == 0 ? "G3_CD" : "G5";
  state.SetLabel(method);
  SUNContext ctx = nullptr;
  if (SUNContext_Create(SUN_COMM_NULL, &ctx) != 0) {
    state.SkipWithError("SUNContext_Create failed");
    return;
  }
  Springs sp = MakeSprings(n);
  N_Vector x = N_VNew_Serial(n, ctx), v = N_VNew_Serial(n, ctx);
  void* mem = CEodeCreate(ctx);
  if (x == nullptr || v == nullptr || mem == nullptr) {
    state.SkipWithError("allocation failed");
    return;
  }
  N_VConst(1.0, x);
  N_VConst(0.0, v);
  if (CEodeInit(mem, SpringRhs, 0.0, x, v) != CE_SUCCESS ||
      CEodeSetUserData(mem, &sp) != CE_SUCCESS || CEodeSetMethodByName(mem, method) != CE_SUCCESS ||
      CEodeSetFixedStep(mem, kStep) != CE_SUCCESS ||
      CEodeSetMaxNumSteps(mem, 1L << 40) != CE_SUCCESS) {
    state.SkipWithError("CEODE setup failed");
  } else {
    sunrealtype t = 0;
    // The start (initial derivatives) is not a step: take it before timing.
    if (CEodeEvolve(mem, 1.0, x, v, &t, CE_ONE_STEP) < 0) state.SkipWithError("first step failed");
    for (auto _ : state) {
      if (CEodeEvolve(mem, t + 1.0, x, v, &t, CE_ONE_STEP) < 0) {
        state.SkipWithError("CEodeEvolve failed");
        break;
      }
      benchmark::DoNotOptimize(t);
    }
  }
  if (n > 1) {
    state.counters["ns_per_dof"] =
        benchmark::Counter(static_cast<double>(state.iterations()) * static_cast<double>(n),
                           benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  }
  CEodeFree(&mem);
  N_VDestroy(x);
  N_VDestroy(v);
  SUNContext_Free(&ctx);
}

// The same steps on plain arrays: state kept in structure-of-arrays form.
void BM_HandStep(benchmark::State& state) {
  const long n = state.range(0);
  const bool g5 = state.range(1) != 0;
  state.SetLabel(g5 ? "G5" : "G3_CD");
  const Springs sp = MakeSprings(n);
  const double h = kStep, h2 = h * h, h3 = h2 * h, h4 = h3 * h;
  // G5 = (4/5, 1, 1, 1); G3_CD = (1, 1/2).
  const double al = g5 ? 0.8 : 1.0, be = g5 ? 1.0 : 0.5, ga = 1.0, ze = 1.0;
  std::vector<double> x(n, 1.0), v(n, 0.0), a(n), j(n, 0.0), s(n, 0.0), xn(n);
  for (long i = 0; i < n; ++i) {
    a[i] = -sp.k[i] * x[i];
    xn[i] = x[i] + h * v[i] + 0.5 * h2 * a[i];
  }
  for (auto _ : state) {
    if (g5) {
      for (long i = 0; i < n; ++i) {
        const double xi = xn[i];
        const double an = -sp.k[i] * xi;
        const double sn = ((an - a[i] - h * j[i]) * (2 / h2) - (1 - ga) * s[i]) / ga;
        const double sb = (1 - be) * s[i] + be * sn, sz = (1 - ze) * s[i] + ze * sn;
        const double sa = (1 - al) * s[i] + al * sn;
        v[i] += h * a[i] + 0.5 * h2 * j[i] + h3 / 6 * sb;
        j[i] += h * sz;
        x[i] = xi;
        xn[i] = xi + (h * v[i] + 0.5 * h2 * an + h3 / 6 * j[i] + h4 / 24 * sa);
        a[i] = an;
        s[i] = sn;
      }
    } else {
      for (long i = 0; i < n; ++i) {
        const double xi = xn[i];
        const double an = -sp.k[i] * xi;
        v[i] += h * ((1 - be) * a[i] + be * an);
        x[i] = xi;
        xn[i] = xi + (h * v[i] + 0.5 * h2 * ((1 - al) * a[i] + al * an));
        a[i] = an;
      }
    }
    benchmark::DoNotOptimize(xn.data());
    benchmark::ClobberMemory();
  }
  if (n > 1) {
    state.counters["ns_per_dof"] =
        benchmark::Counter(static_cast<double>(state.iterations()) * static_cast<double>(n),
                           benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  }
}

void Sizes(benchmark::internal::Benchmark* b) {
  for (long n : {1L, 1000L, 100000L}) {
    for (long m : {0L, 1L}) b->Args({n, m});
  }
}

}  // namespace

BENCHMARK(BM_CeodeStep)->Apply(Sizes)->ArgNames({"n", "G5"});
BENCHMARK(BM_HandStep)->Apply(Sizes)->ArgNames({"n", "G5"});

BENCHMARK_MAIN();
