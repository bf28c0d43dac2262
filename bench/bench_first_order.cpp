// -----------------------------------------------------------------------------
// bench_first_order: Google Benchmark of the first-order adapter's overhead. One
// explicit G5 step on a spring chain x_i'' = k (x_{i-1} - 2 x_i + x_{i+1}) (fixed
// ends, k = 1, h = 1e-3), with the acceleration supplied
//   form 0: natively, f(t, x, v) = a                       (CEodeInit / CEodeEvolve)
//   form 1: as an ARKODE F(t, y, ydot) on a ManyVector [x; v] (CEodeInitFirstOrder)
//   form 2: as an ARKODE F on a serial vector of length 2n  (CEodeInitFirstOrder)
// One iteration = one step (CE_ONE_STEP); "Time" is ns/step, ns_per_dof divides by n.
//
// Usage: bench_first_order [Google Benchmark flags], e.g.
//   bench_first_order --benchmark_min_time=0.2 --benchmark_repetitions=3
// -----------------------------------------------------------------------------
#include <benchmark/benchmark.h>
#include <ceode/ceode.h>
#include <nvector/nvector_manyvector.h>
#include <nvector/nvector_serial.h>

#include "ceode_sundials_compat.h"  // SUN_COMM_NULL on SUNDIALS 6.4

namespace {

constexpr double kStep = 1e-3;

void Chain(long n, const double* x, double* a) {
  for (long i = 0; i < n; ++i) {
    const double left = i > 0 ? x[i - 1] : 0.0;
    const double right = i + 1 < n ? x[i + 1] : 0.0;
    a[i] = left - 2.0 * x[i] + right;
  }
}

int Native(sunrealtype, N_Vector x, N_Vector, N_Vector a, void*) {
  Chain(N_VGetLength(x), N_VGetArrayPointer(x), N_VGetArrayPointer(a));
  return 0;
}

int Many(sunrealtype, N_Vector y, N_Vector ydot, void*) {
  N_Vector x = N_VGetSubvector_ManyVector(y, 0);
  N_VScale(1.0, N_VGetSubvector_ManyVector(y, 1), N_VGetSubvector_ManyVector(ydot, 0));
  Chain(N_VGetLength(x), N_VGetArrayPointer(x),
        N_VGetArrayPointer(N_VGetSubvector_ManyVector(ydot, 1)));
  return 0;
}

int Serial(sunrealtype, N_Vector y, N_Vector ydot, void*) {
  const long n = N_VGetLength(y) / 2;
  const double* yd = N_VGetArrayPointer(y);
  double* dd = N_VGetArrayPointer(ydot);
  for (long i = 0; i < n; ++i) dd[i] = yd[n + i];
  Chain(n, yd, dd + n);
  return 0;
}

void BM_ChainStep(benchmark::State& state) {
  const long n = state.range(0);
  const int form = static_cast<int>(state.range(1));
  state.SetLabel(form == 0   ? "native"
                 : form == 1 ? "first-order ManyVector"
                             : "first-order serial");
  SUNContext ctx = nullptr;
  if (SUNContext_Create(SUN_COMM_NULL, &ctx) != 0) {
    state.SkipWithError("SUNContext_Create failed");
    return;
  }
  N_Vector x = N_VNew_Serial(n, ctx), v = N_VNew_Serial(n, ctx);
  N_Vector parts[2] = {x, v};
  N_Vector y = form == 1 ? N_VNew_ManyVector(2, parts, ctx) : N_VNew_Serial(2 * n, ctx);
  void* mem = CEodeCreate(ctx);
  N_VConst(0.0, v);
  for (long i = 0; i < n; ++i) NV_Ith_S(x, i) = 1e-3 * static_cast<double>(i % 7);
  N_VConst(0.0, y);
  if (form == 2) {
    for (long i = 0; i < n; ++i) NV_Ith_S(y, i) = NV_Ith_S(x, i);
  }
  int flag = form == 0 ? CEodeInit(mem, Native, 0.0, x, v)
                       : CEodeInitFirstOrder(mem, form == 1 ? Many : Serial, 0.0, y);
  if (flag == CE_SUCCESS) flag = CEodeSetMethodByName(mem, "G5");
  if (flag == CE_SUCCESS) flag = CEodeSetFixedStep(mem, kStep);
  if (flag == CE_SUCCESS) flag = CEodeSetStabilityGuard(mem, CE_GUARD_OFF, 0);
  if (flag == CE_SUCCESS) flag = CEodeSetMaxNumSteps(mem, 1L << 40);
  sunrealtype t = 0;
  auto step = [&]() {
    return form == 0 ? CEodeEvolve(mem, t + 1.0, x, v, &t, CE_ONE_STEP)
                     : CEodeEvolveFirstOrder(mem, t + 1.0, y, &t, CE_ONE_STEP);
  };
  if (flag != CE_SUCCESS || step() < 0) {  // the start is not a step: before timing
    state.SkipWithError("CEODE setup failed");
  } else {
    for (auto _ : state) {
      if (step() < 0) {
        state.SkipWithError("step failed");
        break;
      }
    }
    state.counters["ns_per_dof"] =
        benchmark::Counter(static_cast<double>(state.iterations()) * static_cast<double>(n),
                           benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  }
  CEodeFree(&mem);
  N_VDestroy(y);
  N_VDestroy(x);
  N_VDestroy(v);
  SUNContext_Free(&ctx);
}

BENCHMARK(BM_ChainStep)->ArgsProduct({{10, 1000, 100000}, {0, 1, 2}})->Unit(benchmark::kNanosecond);

}  // namespace

BENCHMARK_MAIN();
