// -----------------------------------------------------------------------------
// bench_step: the per-step cost of CEODE's explicit step against the same method written by
// hand on raw doubles (the floor), side by side in one run, with the ratios printed.
//
// Problem: n independent springs x_i'' = -k_i x_i, k_i = 1 + i/n, x(0) = 1, v(0) = 0, h = 1e-3
// (far inside every stability limit). Methods G3_CD and G4_A34 at n = 1, 10^4, 3*10^4, 10^5,
// 3*10^5, 10^6 and G8_O8 at n = 1, 10^3, 10^4 (G6_O5 and G7_O7 for --count). Variants (one
// benchmark iteration = K steps; the time shown is per iteration, the ratios table is per step):
//   ceode       CEodeEvolve(tout K steps ahead, CE_NORMAL): no output copy per step;
//   ceode_1step CEodeEvolve(CE_ONE_STEP) K times: two output copies per step (the API's);
//   ceode_freq  CEodeEvolve(CE_NORMAL) with an output every 4 steps on the step grid;
//   hand_fpass  the hand loop calling f as its own pass over the vectors (as CEODE does);
//   hand_fused  the hand loop with f fused into the update (one pass, the practical limit);
//   hand_d8     G8_O8 only: the degree-8 step written out by hand in the arithmetic of CEODE's
//               update plan, f as its own pass (CheckHandDegree8 compares it with CEODE).
// Both hand loops carry the method's history D_1..D_{d-1} and x(t) as CEODE does, update them
// in place and swap the acceleration buffer instead of copying it; f is the same function
// (SpringAccel) everywhere, called through CEODE's N_Vector interface by CEODE.
//
// Usage:
//   bench_step [--quick] [Google Benchmark flags]
//   bench_step --count VARIANT METHOD N STEPS   (no timing: for valgrind --tool=callgrind;
//                                               VARIANT also ceode_generic: the N_Vector
//                                               reference update, to count its passes;
//                                               ceode_two_buffers: CEodeSetInPlaceUpdate off;
//                                               ceode_freq_mid: as ceode_freq, half a step
//                                               past the grid (dense output every return);
//                                               f_only: f alone, STEPS calls;
//                                               ceode_adaptive: tolerances 1e-8 instead of
//                                               the fixed step, prints the steps taken;
//                                               instructions per step = difference of two
//                                               STEPS divided by their difference)
// Before timing, the program checks that CEODE and both hand loops agree with the exact
// solution cos(sqrt(k) t) and with each other (exit 1 otherwise); --quick times n <= 10^4 only.
// Each variant takes one untimed iteration before its timed ones.
// -----------------------------------------------------------------------------
#include <benchmark/benchmark.h>
#include <ceode/ceode.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "ceode_sundials_compat.h"  // SUN_COMM_NULL on SUNDIALS 6.4
#include "ceode_testing.h"          // CEodeSetFusedKernel, CEodeSetInPlaceUpdate
#include "hand_step.h"

namespace {

constexpr double kStep = 1e-3;
using hand::Coeffs;
using hand::D8Weights;
using hand::Fact;
using hand::kMaxD;
using hand::MakeD8Weights;

struct Method {
  const char* name;
  int degree;
  double p[kMaxD];
};
// The parameters of CEODE's named sets (src/ceode_step.cpp), written out as a user would.
const Method kMethods[] = {
    {"G3_CD", 3, {1.0, 0.5}},
    {"G4_A34", 4, {0.75, 1.0 / 3.0, 0.5}},
    {"G6_O5",
     6,
     {7.8581049690442608, 3.2003060015391878, 2.306472520152492, 1.445972372099134,
      0.78920709629572905}},
    {"G7_O7",
     7,
     {19.362993681325158, 15.310841926671563, 8.7099568711498723, 3.9685609709725753,
      2.3539640770647496, 0.90130820250696653}},
    {"G8_O8",
     8,
     {399.99982239054896, 278.28678067794129, 134.15990720943549, 51.039413540261052,
      20.827940678986256, 6.8588048481939303, 2.805527440772015}},
};

const Method* FindMethod(const std::string& name) {
  for (const Method& m : kMethods) {
    if (name == m.name) return &m;
  }
  return nullptr;
}

Coeffs MakeCoeffs(const Method& m, double h) { return hand::MakeCoeffs(m.degree, m.p, h); }

std::vector<double> SpringConstants(long n) {
  std::vector<double> k(n);
  for (long i = 0; i < n; ++i) k[i] = 1.0 + static_cast<double>(i) / static_cast<double>(n);
  return k;
}

// The f of every variant: a = -k x.
__attribute__((noinline)) void SpringAccel(const double* k, const double* x, double* a, long n) {
  for (long i = 0; i < n; ++i) a[i] = -k[i] * x[i];
}

int CeodeRhs(sunrealtype /*t*/, N_Vector x, N_Vector /*v*/, N_Vector f, void* user) {
  const auto* k = static_cast<const std::vector<double>*>(user);
  SpringAccel(k->data(), N_VGetArrayPointer(x), N_VGetArrayPointer(f),
              static_cast<long>(k->size()));
  return 0;
}

// ---- the hand loops -----------------------------------------------------------------------
// State of the hand loop: the history D[1..d-1] at t - h, x(t), the acceleration buffer.
struct HandState {
  std::vector<std::vector<double>> D;
  std::vector<double> x, an, k;
  double* Dp[kMaxD] = {};
};

// Exact derivatives of x = cos(sqrt(k) t) at t = 0 and x(h) from their Taylor polynomial: the
// same start CEODE makes (its differences agree with these to far below the checks' tolerance).
HandState MakeHand(const Method& m, long n) {
  const int d = m.degree;
  HandState s;
  s.k = SpringConstants(n);
  s.D.assign(kMaxD, std::vector<double>(n, 0.0));
  s.x.assign(n, 1.0);
  s.an.assign(n, 0.0);
  for (long i = 0; i < n; ++i) {
    double dk = 1, xh = 1;
    for (int j = 1; j < d; ++j) {
      if (j % 2 == 0) dk *= -s.k[i];
      s.D[j][i] = j % 2 == 0 ? dk : 0.0;
      xh += std::pow(kStep, j) / Fact(j) * s.D[j][i];
    }
    s.x[i] = xh;
  }
  for (int j = 0; j < kMaxD; ++j) s.Dp[j] = s.D[j].data();
  return s;
}

// One element of the step, everything in registers (d is a template constant: unrolled).
// write_a: store a as the new D_2 (the fused loop); otherwise the caller swaps buffers.
template <int d, bool write_a>
inline void HandElement(const Coeffs& co, double* const* D, long i, double a, double* x) {
  double old[d], nw[d];
  for (int j = 1; j < d; ++j) old[j] = D[j][i];
  double z = a;
  if (d > 3) {
    double b2 = 0;
    for (int j = 2; j < d; ++j) b2 += co.T[2][j] * old[j];
    z = (a - b2) * co.inv_c2;
  }
  nw[2] = a;
  nw[d - 1] = z;
  for (int k = 1; k <= d - 2; ++k) {
    if (k == 2) continue;
    double s = old[k];
    for (int j = k + 1; j < d; ++j) s += co.T[k][j] * old[j];
    nw[k] = s + co.c[k] * z;
  }
  double dx = co.wz_old * old[d - 1] + co.wz_new * z;
  for (int j = 1; j <= d - 2; ++j) dx += co.w[j] * nw[j];
  x[i] += dx;
  for (int k = 1; k < d; ++k) {
    if (k != 2 || write_a) D[k][i] = nw[k];
  }
}

// f as its own pass, then the update; the new D_2 = a is the buffer f wrote: swapped, not copied.
template <int d>
void HandStepFpass(const Coeffs& co, HandState* s, long n) {
  SpringAccel(s->k.data(), s->x.data(), s->an.data(), n);
  const double* a = s->an.data();
  double* x = s->x.data();
  double* const* D = s->Dp;
  for (long i = 0; i < n; ++i) HandElement<d, false>(co, D, i, a[i], x);
  s->D[2].swap(s->an);
  s->Dp[2] = s->D[2].data();
}

template <int d>
void HandStepFused(const Coeffs& co, HandState* s, long n) {
  const double* k = s->k.data();
  double* x = s->x.data();
  double* const* D = s->Dp;
  for (long i = 0; i < n; ++i) HandElement<d, true>(co, D, i, -k[i] * x[i], x);
}

using HandFn = void (*)(const Coeffs&, HandState*, long);
HandFn HandStepFn(int degree, bool fused) {
  switch (degree) {
    case 3:
      return fused ? HandStepFused<3> : HandStepFpass<3>;
    case 4:
      return fused ? HandStepFused<4> : HandStepFpass<4>;
    case 6:
      return fused ? HandStepFused<6> : HandStepFpass<6>;
    default:
      return fused ? HandStepFused<8> : HandStepFpass<8>;
  }
}

// ---- the hand degree-8 loop -------------------------------------------------------------------
void HandStepD8(const D8Weights& w, HandState* s, long n) {
  SpringAccel(s->k.data(), s->x.data(), s->an.data(), n);
  double* const* D = s->Dp;
  hand::D8Update(w, s->an.data(), D[1], D[2], D[3], D[4], D[5], D[6], D[7], s->x.data(), n);
  s->D[2].swap(s->an);
  s->Dp[2] = s->D[2].data();
}

// ---- CEODE ----------------------------------------------------------------------------------
// The update's test-only toggles (the fused one-pass kernel, in-place plans): the one place they
// are set. Defaults: both on.
bool SetUpdateToggles(void* mem, bool fused, bool in_place) {
  return CEodeSetFusedKernel(mem, fused ? SUNTRUE : SUNFALSE) == CE_SUCCESS &&
         CEodeSetInPlaceUpdate(mem, in_place ? SUNTRUE : SUNFALSE) == CE_SUCCESS;
}

struct CeodeRun {
  SUNContext ctx = nullptr;
  N_Vector x = nullptr, v = nullptr;
  void* mem = nullptr;
  std::vector<double> k;
  double t = 0;
  bool ok = false;

  // generic: the N_Vector reference update instead of the fused kernel; two_buffers: no in-place
  // plans.
  CeodeRun(const Method& m, long n, bool generic = false, bool two_buffers = false,
           bool adaptive = false)
      : k(SpringConstants(n)) {
    if (SUNContext_Create(SUN_COMM_NULL, &ctx) != 0) return;
    x = N_VNew_Serial(n, ctx);
    v = N_VNew_Serial(n, ctx);
    mem = CEodeCreate(ctx);
    if (x == nullptr || v == nullptr || mem == nullptr) return;
    N_VConst(1.0, x);
    N_VConst(0.0, v);
    ok = CEodeInit(mem, CeodeRhs, 0.0, x, v) == CE_SUCCESS &&
         CEodeSetUserData(mem, &k) == CE_SUCCESS &&
         CEodeSetMethodByName(mem, m.name) == CE_SUCCESS &&
         (adaptive ? CEodeSStolerances(mem, 1e-8, 1e-8) : CEodeSetFixedStep(mem, kStep)) ==
             CE_SUCCESS &&
         CEodeSetStabilityGuard(mem, CE_GUARD_OFF, 0) == CE_SUCCESS &&
         CEodeSetMaxNumSteps(mem, 1L << 40) == CE_SUCCESS &&
         SetUpdateToggles(mem, !generic, !two_buffers) &&
         CEodeEvolve(mem, 0.0, x, v, &t, CE_NORMAL) >= 0;  // the start, not a step
  }
  ~CeodeRun() {
    CEodeFree(&mem);
    if (x != nullptr) N_VDestroy(x);
    if (v != nullptr) N_VDestroy(v);
    if (ctx != nullptr) SUNContext_Free(&ctx);
  }
  CeodeRun(const CeodeRun&) = delete;
  CeodeRun& operator=(const CeodeRun&) = delete;

  // K steps; x and v hold the state at the end.
  bool Steps(long K, bool one_step) { return Drive(K, one_step ? kOneStep : kToEnd); }

  // How the K steps are asked for: one CE_NORMAL call to the end, one CE_ONE_STEP call per step,
  // or CE_NORMAL outputs every kOutputEvery steps on the step grid (copies of the method's values)
  // or half a step past it (dense output at every return).
  enum Mode { kToEnd, kOneStep, kFrequent, kFrequentMid };
  static constexpr long kOutputEvery = 4;
  bool Drive(long K, Mode mode) {
    if (mode == kToEnd) {
      return CEodeEvolve(mem, t + static_cast<double>(K) * kStep, x, v, &t, CE_NORMAL) >= 0;
    }
    if (mode == kOneStep) {
      for (long s = 0; s < K; ++s) {
        if (CEodeEvolve(mem, t + 1.0, x, v, &t, CE_ONE_STEP) < 0) return false;
      }
      return true;
    }
    const double off = mode == kFrequentMid ? 0.5 : 0.0;
    for (long s = 0; s < K; s += kOutputEvery) {
      grid += kOutputEvery;
      const double tout = (static_cast<double>(grid) + off) * kStep;
      if (CEodeEvolve(mem, tout, x, v, &t, CE_NORMAL) < 0) return false;
    }
    return true;
  }
  long grid = 0;  // the step-grid index of the last frequent output
};

enum Variant {
  kCeode,
  kCeodeOneStep,
  kCeodeFrequent,
  kHandFpass,
  kHandFused,
  kHandD8,
  kNumVariants
};
const char* const kVariantNames[kNumVariants] = {"ceode",      "ceode_1step", "ceode_freq",
                                                 "hand_fpass", "hand_fused",  "hand_d8"};

// Steps per benchmark iteration: 1000 on small systems, 100 from n = 10^4 on, so that `ceode`
// is a tout many steps away at every n (its two output copies at tout then cost <= 2 % of a
// step's vector traffic; with one step per iteration they were half the time at n = 10^6).
long StepsPerIteration(long n) { return n < 10000 ? 1000 : 100; }

void BM_Ceode(benchmark::State& state, const Method* m, long n, CeodeRun::Mode mode) {
  CeodeRun run(*m, n);
  if (!run.ok) {
    state.SkipWithError("CEODE setup failed");
    return;
  }
  const long K = StepsPerIteration(n);
  // One untimed iteration first (as for the hand loop): the first steps write buffers that the
  // start allocated but never touched, and their page faults are a one-time cost of the run, not
  // of a step (at n = 10^6 they were a third of a 100-step iteration).
  if (!run.Drive(K, mode)) {
    state.SkipWithError("CEodeEvolve failed");
    return;
  }
  for (auto _ : state) {
    if (!run.Drive(K, mode)) {
      state.SkipWithError("CEodeEvolve failed");
      break;
    }
    benchmark::ClobberMemory();  // (DoNotOptimize(double&) miscompiles with GCC 12 here)
  }
  state.counters["steps"] = static_cast<double>(K);
}

void BM_Hand(benchmark::State& state, const Method* m, long n, bool fused) {
  const Coeffs co = MakeCoeffs(*m, kStep);
  HandState s = MakeHand(*m, n);
  const HandFn step = HandStepFn(m->degree, fused);
  const long K = StepsPerIteration(n);
  for (long j = 0; j < K; ++j) step(co, &s, n);  // untimed, as BM_Ceode's
  for (auto _ : state) {
    for (long j = 0; j < K; ++j) step(co, &s, n);
    benchmark::DoNotOptimize(s.x.data());
    benchmark::ClobberMemory();
  }
  state.counters["steps"] = static_cast<double>(K);
}

void BM_HandD8(benchmark::State& state, const Method* m, long n) {
  const D8Weights w = MakeD8Weights(MakeCoeffs(*m, kStep));
  HandState s = MakeHand(*m, n);
  const long K = StepsPerIteration(n);
  for (long j = 0; j < K; ++j) HandStepD8(w, &s, n);  // untimed, as BM_Ceode's
  for (auto _ : state) {
    for (long j = 0; j < K; ++j) HandStepD8(w, &s, n);
    benchmark::DoNotOptimize(s.x.data());
    benchmark::ClobberMemory();
  }
  state.counters["steps"] = static_cast<double>(K);
}

// ---- checks -----------------------------------------------------------------------------------
// Largest error against cos(sqrt(k_i) t) of a state x at time t.
double ExactError(const double* x, const std::vector<double>& k, double t) {
  double e = 0;
  for (size_t i = 0; i < k.size(); ++i)
    e = std::max(e, std::fabs(x[i] - std::cos(std::sqrt(k[i]) * t)));
  return e;
}

// Each variant 2000 steps to t = 2: errors within the method's own (h = 1e-3) and the variants
// within the same of each other.
bool CheckVariants(const Method& m, long n) {
  constexpr long kSteps = 2000;
  const double tol = m.degree == 3 ? 1e-6 : 1e-9;
  CeodeRun run(m, n);
  const bool ran = run.ok && run.Steps(kSteps, false);
  const double t = static_cast<double>(kSteps + 1) * kStep;  // the hand loops' x is x(t + h)
  const double e_ceode = ran ? ExactError(N_VGetArrayPointer(run.x), run.k, run.t) : 1.0;
  bool ok = ran && std::fabs(run.t - t + kStep) < 1e-12 && e_ceode < tol;
  for (bool fused : {false, true}) {
    const Coeffs co = MakeCoeffs(m, kStep);
    HandState s = MakeHand(m, n);
    for (long j = 0; j < kSteps; ++j) HandStepFn(m.degree, fused)(co, &s, n);
    const double e = ExactError(s.x.data(), s.k, t);
    const bool pass = e < tol;
    std::printf("check %-6s n = %-7ld ceode error %.3e  %s error %.3e  (tol %.0e) %s\n", m.name, n,
                e_ceode, fused ? "hand_fused" : "hand_fpass", e, tol, pass && ok ? "ok" : "FAILED");
    ok = ok && pass;
  }
  return ok;
}

// The hand degree-8 loop from CEODE's own start (its history at t = 0 and its x(h), read through
// CEodeGetDky) against CEODE over 2000 steps: the same update, so the same numbers to round-off.
// x(h) comes from the dense output (x(t0) + (x(t0 + h) - x(t0)), one rounding), so the two runs
// differ from the first step by at most that rounding as propagated by a stable method.
bool CheckHandDegree8(long n) {
  constexpr long kSteps = 2000;
  const Method& m = *FindMethod("G8_O8");
  CeodeRun run(m, n);
  HandState s = MakeHand(m, n);
  N_Vector tmp = run.ok ? N_VClone(run.x) : nullptr;
  bool ok = tmp != nullptr;
  const auto read = [&](double t, int k, double* to) {  // CEODE's D_k(t) into the hand state
    ok = ok && CEodeGetDky(run.mem, t, k, tmp) == CE_SUCCESS;
    if (ok) std::copy(N_VGetArrayPointer(tmp), N_VGetArrayPointer(tmp) + n, to);
  };
  for (int k = 1; k < m.degree; ++k) read(0.0, k, s.Dp[k]);
  read(kStep, 0, s.x.data());
  if (tmp != nullptr) N_VDestroy(tmp);
  ok = ok && run.Steps(kSteps, false);
  const D8Weights w = MakeD8Weights(MakeCoeffs(m, kStep));
  for (long j = 0; j + 1 < kSteps; ++j) HandStepD8(w, &s, n);  // x(t + h) = CEODE's x at kSteps
  double dx = 0, dv = 0, xmax = 0, vmax = 0;
  const double* cx = N_VGetArrayPointer(run.x);
  for (long i = 0; ok && i < n; ++i) dx = std::max(dx, std::fabs(s.x[i] - cx[i]));
  HandStepD8(w, &s, n);  // D_1 at kSteps, CEODE's v
  const double* cv = N_VGetArrayPointer(run.v);
  for (long i = 0; ok && i < n; ++i) {
    dv = std::max(dv, std::fabs(s.D[1][i] - cv[i]));
    xmax = std::max(xmax, std::fabs(cx[i]));
    vmax = std::max(vmax, std::fabs(cv[i]));
  }
  // Round-off: 2000 steps of a few roundings each on values of order 1.
  const bool pass = ok && dx <= 1e-12 * (1 + xmax) && dv <= 1e-12 * (1 + vmax);
  std::printf("check G8_O8  n = %-7ld hand_d8 against ceode: max |dx| %.3e  max |dv| %.3e %s\n", n,
              dx, dv, pass ? "ok" : "FAILED");
  return pass;
}

// ---- the ratios --------------------------------------------------------------------------------
// Collects the CPU time per step of each benchmark (the median when repeated) while the console
// reporter prints as usual; Summarise prints CEODE / hand loop.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& reports) override {
    ConsoleReporter::ReportRuns(reports);
    for (const Run& r : reports) {
      const bool single = r.run_type == Run::RT_Iteration && r.repetitions <= 1;
      const bool median = r.run_type == Run::RT_Aggregate && r.aggregate_name == "median";
      if (r.error_occurred || !(single || median)) continue;
      const auto it = r.counters.find("steps");
      const double steps = it == r.counters.end() ? 1.0 : it->second.value;
      per_step_[r.run_name.function_name] = r.GetAdjustedCPUTime() / steps;
    }
  }
  void Summarise(const std::vector<std::pair<const Method*, long>>& cases) const {
    std::printf(
        "\nPer-step CPU time (median, ns) and ratios to the hand loop with f as its pass\n");
    std::printf("%-7s %8s %10s %10s %10s %10s %10s %10s %8s %8s %8s %8s\n", "method", "n", "ceode",
                "1step", "freq", "hand_fpass", "hand_fused", "hand_d8", "c/fpass", "1s/fpass",
                "fr/fpass", "c/d8");
    for (const auto& c : cases) {
      double tv[kNumVariants];
      for (int v = 0; v < kNumVariants; ++v) {
        const auto it = per_step_.find(Name(v, *c.first, c.second));
        tv[v] = it == per_step_.end() ? NAN : it->second;
      }
      std::printf("%-7s %8ld %10.4g %10.4g %10.4g %10.4g %10.4g %10.4g %8.3f %8.3f %8.3f %8.3f\n",
                  c.first->name, c.second, tv[kCeode], tv[kCeodeOneStep], tv[kCeodeFrequent],
                  tv[kHandFpass], tv[kHandFused], tv[kHandD8], tv[kCeode] / tv[kHandFpass],
                  tv[kCeodeOneStep] / tv[kHandFpass], tv[kCeodeFrequent] / tv[kHandFpass],
                  tv[kCeode] / tv[kHandD8]);
    }
  }
  static std::string Name(int variant, const Method& m, long n) {
    return std::string(kVariantNames[variant]) + "/" + m.name + "/n:" + std::to_string(n);
  }

 private:
  std::map<std::string, double> per_step_;
};

// The cases: G3_CD and G4_A34 at every n, G8_O8 at n = 1, 10^3 and 10^4.
std::vector<std::pair<const Method*, long>> Cases(bool quick) {
  std::vector<std::pair<const Method*, long>> out;
  for (const char* name : {"G3_CD", "G4_A34"}) {
    for (long n : {1L, 10000L, 30000L, 100000L, 300000L, 1000000L}) {
      if (!quick || n <= 10000) out.emplace_back(FindMethod(name), n);
    }
  }
  for (long n : {1L, 1000L, 10000L}) out.emplace_back(FindMethod("G8_O8"), n);
  return out;
}

// --count VARIANT METHOD N STEPS: the steps alone, for an instruction counter.
int CountMode(int argc, char** argv) {
  if (argc < 6) {
    std::fprintf(stderr, "usage: bench_step --count VARIANT METHOD N STEPS\n");
    return 2;
  }
  const std::string variant = argv[2];
  const Method* m = FindMethod(argv[3]);
  const long n = std::atol(argv[4]);
  const long steps = std::atol(argv[5]);
  if (m == nullptr || n < 1 || steps < 0) return 2;
  if (variant.rfind("ceode", 0) == 0) {
    CeodeRun run(*m, n, variant == "ceode_generic", variant == "ceode_two_buffers",
                 variant == "ceode_adaptive");
    const CeodeRun::Mode mode = variant == "ceode_1step"      ? CeodeRun::kOneStep
                                : variant == "ceode_freq"     ? CeodeRun::kFrequent
                                : variant == "ceode_freq_mid" ? CeodeRun::kFrequentMid
                                                              : CeodeRun::kToEnd;
    const bool ok = run.ok && run.Drive(steps, mode);
    long nst = 0;
    CEodeGetNumSteps(run.mem, &nst);
    if (variant == "ceode_adaptive") std::printf("steps %ld\n", nst);
    return ok ? 0 : 1;
  }
  const Coeffs co = MakeCoeffs(*m, kStep);
  HandState s = MakeHand(*m, n);
  if (variant == "f_only") {  // f alone, STEPS calls: what the other variants' counts include
    for (long j = 0; j < steps; ++j) SpringAccel(s.k.data(), s.x.data(), s.an.data(), n);
    benchmark::DoNotOptimize(s.an.data());
    return 0;
  }
  if (variant == "hand_d8") {
    if (m->degree != 8) return 2;
    const D8Weights w = MakeD8Weights(co);
    for (long j = 0; j < steps; ++j) HandStepD8(w, &s, n);
    benchmark::DoNotOptimize(s.x.data());
    return 0;
  }
  const HandFn step = HandStepFn(m->degree, variant == "hand_fused");
  for (long j = 0; j < steps; ++j) step(co, &s, n);
  benchmark::DoNotOptimize(s.x.data());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1 && std::strcmp(argv[1], "--count") == 0) return CountMode(argc, argv);
  bool quick = false;
  std::vector<char*> args;
  for (int i = 0; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0) {
      quick = true;
    } else {
      args.push_back(argv[i]);
    }
  }
  static char min_time[] = "--benchmark_min_time=0.01";
  if (quick) args.push_back(min_time);
  bool ok = true;
  for (const char* name : {"G3_CD", "G4_A34", "G8_O8"}) {
    for (long n : {1L, 1000L}) ok = CheckVariants(*FindMethod(name), n) && ok;
  }
  for (long n : {1L, 1000L}) ok = CheckHandDegree8(n) && ok;
  if (!ok) return 1;
  const auto cases = Cases(quick);
  constexpr CeodeRun::Mode kModes[] = {CeodeRun::kToEnd, CeodeRun::kOneStep, CeodeRun::kFrequent};
  for (const auto& c : cases) {
    const Method* m = c.first;
    const long n = c.second;
    for (int v = 0; v < kNumVariants; ++v) {
      const std::string name = RatioReporter::Name(v, *m, n);
      if (v == kCeode || v == kCeodeOneStep || v == kCeodeFrequent) {
        benchmark::RegisterBenchmark(name.c_str(), BM_Ceode, m, n, kModes[v]);
      } else if (v == kHandD8) {
        if (m->degree == 8) benchmark::RegisterBenchmark(name.c_str(), BM_HandD8, m, n);
      } else {
        benchmark::RegisterBenchmark(name.c_str(), BM_Hand, m, n, v == kHandFused);
      }
    }
  }
  int gb_argc = static_cast<int>(args.size());
  benchmark::Initialize(&gb_argc, args.data());
  RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  reporter.Summarise(cases);
  return 0;
}
