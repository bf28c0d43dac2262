// -----------------------------------------------------------------------------
// wp_kepler_long: the round-off floor of a long conservative run. SUNDIALS' Kepler orbit
// (e = 0.6 from the pericentre, kepler_model.h) over 1000 orbits at fixed steps, final position
// error against the exact orbit through the initial state as the program holds it in double
// (kepler::ExactAt; its energy is -1/2 + 1.4e-16, so x(2000 pi) lies 5e-12 from x0).
//
// Curves: every named set of order >= 4 in x and G3_CD, compensated summation on and off
// (config <set> and <set>_comp), N = 1000 ... 32000 steps per orbit, one CE_NORMAL call to
// tout = 1000 N h, a step's time (the dense output is not involved; --sources measures it),
// stability guard off. The peer: a symplectic integrator with compensated sums, as ARKODE's
// SPRKStep offers from SUNDIALS 6.6 on (absent from 6.4): the eighth-order triple-jump
// composition of leapfrog (Yoshida 1990; 27 kick-drift stages, 27 f per step, coefficients
// from closed forms), its whole-step increments added with Kahan summation, and without; 500 ...
// 8000 steps per orbit.
// Columns: error = |x(t_f) - x_exact(t_f)|, drift = |H(t_f) - H(0)|, seconds of one run.
// Summary: each curve's best step and best error (its floor).
//
// --sources (part of the full run): where the round-off of the compensated run comes from, on
// G8_O8 at 8000 steps per orbit: the same method in long double (kepler_replica.h) is the
// truncation; one quantity at a time rounded to double in that run shows which operation
// injects the round-off; the library's start against the exact derivatives; the dense output
// at tout = 2000 pi against the step's own time. --split: for every set at its best compensated
// step, truncation (long double run against the exact orbit) and round-off (double against long
// double).
//
// Checks (exit 1): G8_O8 with compensated summation reaches a final position error <= 2e-11 at
// its best step, and 10 times below its uncompensated floor. --quick: G8_O8 and the peer at
// 8000 steps per orbit over 100 orbits; compensated must be 10 times below uncompensated.
//
// Usage: wp_kepler_long [--csv FILE] [--quick] [--no-split]
// -----------------------------------------------------------------------------
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "kepler_model.h"
#include "kepler_replica.h"
#include "wp_common.h"

namespace {

using kepler::ExactAt;

const double kX0[2] = {1 - kepler::kEcc, 0};
const double kV0[2] = {0, std::sqrt((1 + kepler::kEcc) / (1 - kepler::kEcc))};

struct LongRun {
  int flag = 0;
  double x[2] = {0, 0};
  double error = 0, drift = 0, seconds = 0;
  long steps = 0, evals = 0;
};

double PositionError(long double t, const double* x) {
  long double xe[2];
  ExactAt(t, xe);
  const long double ex = x[0] - xe[0], ey = x[1] - xe[1];
  return static_cast<double>(std::sqrt(ex * ex + ey * ey));
}

int Rhs(sunrealtype t, N_Vector x, N_Vector v, N_Vector a, void* user) {
  return kepler::Acc(t, N_VGetArrayPointer(x), N_VGetArrayPointer(v), N_VGetArrayPointer(a), user);
}

// One CEODE run of `orbits` orbits at N steps per orbit; on_step: tout = the last step's time,
// otherwise tout = 2 pi orbits through the dense output.
LongRun CeodeLong(SUNContext ctx, const char* set, long N, int orbits, bool comp, bool on_step) {
  LongRun r;
  kepler::Kepler k;
  N_Vector x = N_VNew_Serial(2, ctx), v = N_VNew_Serial(2, ctx);
  double* X = N_VGetArrayPointer(x);
  double* V = N_VGetArrayPointer(v);
  std::copy(kX0, kX0 + 2, X);
  std::copy(kV0, kV0 + 2, V);
  const auto t0 = std::chrono::steady_clock::now();
  void* mem = CEodeCreate(ctx);
  const double h = 2 * M_PI / static_cast<double>(N);
  const long n = N * orbits;
  int flag = CEodeInit(mem, Rhs, 0, x, v);
  if (flag == 0) flag = CEodeSetUserData(mem, &k);
  if (flag == 0) flag = CEodeSetMethodByName(mem, set);
  if (flag == 0) flag = CEodeSetFixedStep(mem, h);
  if (flag == 0) flag = CEodeSetStabilityGuard(mem, CE_GUARD_OFF, 0);
  if (flag == 0 && comp) flag = CEodeSetCompensatedSummation(mem, SUNTRUE);
  if (flag == 0) flag = CEodeSetMaxNumSteps(mem, n + 10);
  sunrealtype t = 0;
  const double tout = on_step ? static_cast<double>(n) * h : 2 * M_PI * orbits;
  if (flag == 0) flag = CEodeEvolve(mem, tout, x, v, &t, CE_NORMAL);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  CEodeGetNumSteps(mem, &r.steps);
  r.flag = flag;
  r.evals = k.evals;
  r.x[0] = X[0];
  r.x[1] = X[1];
  r.error = PositionError(t, X);
  r.drift = std::fabs(kepler::Energy(X, V) - kepler::Energy(kX0, kV0));
  CEodeFree(&mem);
  N_VDestroy(x);
  N_VDestroy(v);
  return r;
}

// ---- the peer: eighth-order triple-jump composition of leapfrog, compensated sums ----------
// w(2k+2) = triple jump of w(2k): weights (g, 1 - 2g, g), g = 1 / (2 - 2^(1/(2k+1))).
std::vector<double> TripleJump8() {
  std::vector<double> w = {1.0};
  for (int order = 2; order < 8; order += 2) {
    const double g = 1 / (2 - std::pow(2.0, 1.0 / (order + 1)));
    std::vector<double> next;
    for (double f : {g, 1 - 2 * g, g}) {
      for (double x : w) next.push_back(f * x);
    }
    w = next;
  }
  return w;  // 27 drifts
}

// Kick-drift-kick stages merged (the kick between two drifts is one evaluation), the step's
// increments of q and p summed from the stages and added to q, p with Kahan summation (comp) or
// plainly.
LongRun PeerLong(long N, int orbits, bool comp) {
  LongRun r;
  const std::vector<double> w = TripleJump8();
  const int s = static_cast<int>(w.size());
  std::vector<double> kick(s + 1);
  kick[0] = w[0] / 2;
  for (int i = 1; i < s; ++i) kick[i] = (w[i - 1] + w[i]) / 2;
  kick[s] = w[s - 1] / 2;
  const double h = 2 * M_PI / static_cast<double>(N);
  const long n = N * orbits;
  kepler::Kepler k;
  double q[2] = {kX0[0], kX0[1]}, p[2] = {kV0[0], kV0[1]}, cq[2] = {0, 0}, cp[2] = {0, 0};
  double a[2];
  const auto t0 = std::chrono::steady_clock::now();
  kepler::Acc(0, q, nullptr, a, &k);
  for (long step = 0; step < n; ++step) {
    double dq[2] = {0, 0}, dp[2] = {0, 0};
    for (int i = 0; i <= s; ++i) {
      for (int c = 0; c < 2; ++c) dp[c] += kick[i] * h * a[c];
      if (i == s) break;
      for (int c = 0; c < 2; ++c) dq[c] += w[i] * h * (p[c] + dp[c]);
      const double qs[2] = {q[0] + dq[0], q[1] + dq[1]};
      kepler::Acc(0, qs, nullptr, a, &k);
    }
    for (int c = 0; c < 2; ++c) {
      if (!comp) {
        q[c] += dq[c];
        p[c] += dp[c];
        continue;
      }
      const double yq = dq[c] - cq[c], nq = q[c] + yq;
      cq[c] = (nq - q[c]) - yq;
      q[c] = nq;
      const double yp = dp[c] - cp[c], np = p[c] + yp;
      cp[c] = (np - p[c]) - yp;
      p[c] = np;
    }
  }
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  r.steps = n;
  r.evals = k.evals;
  r.x[0] = q[0];
  r.x[1] = q[1];
  r.error = PositionError(static_cast<long double>(n) * h, q);
  r.drift = std::fabs(kepler::Energy(q, p) - kepler::Energy(kX0, kV0));
  return r;
}

// ---- the long double replica ---------------------------------------------------------------
struct ReplicaRun {
  long double x[2];
  double error;
};

ReplicaRun ReplicaLong(const char* set, long N, int orbits, unsigned rounded, bool exact_start) {
  int d = 0;
  double p[8];
  CEodeGetMethodParams(set, &d, p, 8);
  const double h = 2 * M_PI / static_cast<double>(N);
  kepler::Replica<long double> rep(d, p, h, rounded);
  rep.Start(exact_start);
  const long n = N * orbits;
  for (long i = 0; i < n; ++i) rep.Step();
  ReplicaRun r;
  r.x[0] = rep.X()[0];
  r.x[1] = rep.X()[1];
  long double xe[2];
  ExactAt(static_cast<long double>(n) * h, xe);
  r.error = static_cast<double>(std::hypot(r.x[0] - xe[0], r.x[1] - xe[1]));
  return r;
}

// ---- the sweep -----------------------------------------------------------------------------
struct Floor {
  std::string config;
  long best_n = 0;
  double best = -1;
};

void Record(wp::Table* table, const std::string& solver, const std::string& config, long N,
            const LongRun& r, std::vector<Floor>* floors) {
  const double h = 2 * M_PI / static_cast<double>(N);
  if (r.flag < 0 || !std::isfinite(r.error)) {
    table->Flagged(solver, config, h, r.flag < 0 ? CEodeGetReturnFlagName(r.flag) : "not finite");
    return;
  }
  wp::Row row;
  row.solver = solver;
  row.config = config;
  row.h_or_tol = h;
  row.error = r.error;
  row.drift = r.drift;
  row.steps = r.steps;
  row.rhs_evals = r.evals;
  row.seconds = r.seconds;
  table->Add(row);
  Floor* f = nullptr;
  for (Floor& x : *floors) f = x.config == solver + " " + config ? &x : f;
  if (f == nullptr) {
    floors->push_back({solver + " " + config});
    f = &floors->back();
  }
  if (f->best < 0 || r.error < f->best) f->best = r.error, f->best_n = N;
}

const Floor* FindFloor(const std::vector<Floor>& floors, const std::string& name) {
  for (const Floor& f : floors) {
    if (f.config == name) return &f;
  }
  return nullptr;
}

void PrintFloors(const std::vector<Floor>& floors) {
  std::printf("\nfloor per curve (best final position error over the sweep)\n%-26s %10s %12s\n",
              "curve", "N/orbit", "best error");
  for (const Floor& f : floors)
    std::printf("%-26s %10ld %12.3e\n", f.config.c_str(), f.best_n, f.best);
}

// Truncation and round-off of every set at its best compensated step.
void PrintSplit(SUNContext ctx, const std::vector<const char*>& sets,
                const std::vector<Floor>& floors, int orbits) {
  std::printf(
      "\nsplit at each set's best compensated step: truncation = long double run against the "
      "exact orbit, round-off = |x_double - x_long_double|\n%-8s %8s %12s %12s %12s %12s\n",
      "set", "N/orbit", "truncation", "round-off c", "round-off", "error comp");
  for (const char* set : sets) {
    const Floor* f = FindFloor(floors, std::string("CEODE ") + set + "_comp");
    if (f == nullptr || f->best < 0) continue;
    const ReplicaRun ld = ReplicaLong(set, f->best_n, orbits, 0, false);
    const LongRun c = CeodeLong(ctx, set, f->best_n, orbits, true, true);
    const LongRun u = CeodeLong(ctx, set, f->best_n, orbits, false, true);
    const double rc = static_cast<double>(std::hypot(c.x[0] - ld.x[0], c.x[1] - ld.x[1]));
    const double ru = static_cast<double>(std::hypot(u.x[0] - ld.x[0], u.x[1] - ld.x[1]));
    std::printf("%-8s %8ld %12.3e %12.3e %12.3e %12.3e\n", set, f->best_n, ld.error, rc, ru,
                c.error);
  }
}

// Which operation injects the round-off (G8_O8, 8000 steps per orbit).
void PrintSources(SUNContext ctx, int orbits) {
  const char* set = "G8_O8";
  const long N = 8000;
  std::printf("\nsources of round-off: %s, %ld steps per orbit, %d orbits\n", set, N, orbits);
  const LongRun plain = CeodeLong(ctx, set, N, orbits, false, true);
  const LongRun comp = CeodeLong(ctx, set, N, orbits, true, true);
  const LongRun dense = CeodeLong(ctx, set, N, orbits, true, false);
  std::printf("  CEODE double, plain sums                          %12.3e (drift %.1e)\n",
              plain.error, plain.drift);
  std::printf("  CEODE double, compensated                         %12.3e (drift %.1e)\n",
              comp.error, comp.drift);
  std::printf("  CEODE double, compensated, tout = 2000 pi (dense) %12.3e\n", dense.error);
  struct Case {
    const char* what;
    unsigned rounded;
    bool exact;
  };
  const Case cases[] = {
      {"long double (truncation)", 0, false},
      {"long double, exact start", 0, true},
      {"long double, f reads x rounded to double", kepler::kFInput, false},
      {"long double, f's output rounded", kepler::kFOutput, false},
      {"long double, top derivative z rounded", kepler::kTop, false},
      {"long double, x stored in double", kepler::kPosition, false},
      {"long double, velocity stored in double", kepler::kVelocity, false},
      {"long double, D_3..D_6 stored in double", kepler::kHigher, false},
      {"long double, weights rounded to double", kepler::kCoefficients, false},
      {"long double, velocity increment in double", kepler::kVelocitySum, false},
      {"long double, position increment in double", kepler::kPositionSum, false},
  };
  for (const Case& c : cases) {
    std::printf("  %-49s %12.3e\n", c.what, ReplicaLong(set, N, orbits, c.rounded, c.exact).error);
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // progress of a long run, line by line
  std::string csv;
  bool quick = false, split = true;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--csv") == 0 && i + 1 < argc) csv = argv[++i];
    if (std::strcmp(argv[i], "--quick") == 0) quick = true;
    if (std::strcmp(argv[i], "--no-split") == 0) split = false;
  }
  SUNContext ctx = nullptr;
  if (SUNContext_Create(SUN_COMM_NULL, &ctx) != 0) return 1;
  const int orbits = quick ? 100 : 1000;
  std::vector<const char*> sets = {"G3_CD", "G4_A54", "G5",    "G5_ONES", "G5_O4",
                                   "G6_O5", "G6_O6",  "G7_O7", "G8_O8"};
  std::vector<long> per_orbit = {1000, 2000, 4000, 8000, 16000, 32000};
  std::vector<long> peer_per_orbit = {500, 1000, 2000, 4000, 8000};
  if (quick) sets = {"G8_O8"}, per_orbit = {8000}, peer_per_orbit = {8000};
  std::printf("Kepler e = 0.6, %d orbits, fixed steps (N per orbit), final position error\n",
              orbits);
  wp::Table table("kepler_long", csv);
  std::vector<Floor> floors;
  for (const char* set : sets) {
    for (long N : per_orbit) {
      for (bool comp : {false, true}) {
        const std::string config = std::string(set) + (comp ? "_comp" : "");
        Record(&table, "CEODE", config, N, CeodeLong(ctx, set, N, orbits, comp, true), &floors);
      }
    }
  }
  for (long N : peer_per_orbit) {
    for (bool comp : {false, true}) {
      Record(&table, "TripleJump8", comp ? "comp" : "plain", N, PeerLong(N, orbits, comp), &floors);
    }
  }
  PrintFloors(floors);
  const Floor* c = FindFloor(floors, "CEODE G8_O8_comp");
  const Floor* u = FindFloor(floors, "CEODE G8_O8");
  bool ok = c != nullptr && u != nullptr && c->best > 0 && c->best * 10 < u->best;
  if (!quick) ok = ok && c->best <= 2e-11;
  std::printf("G8_O8 compensated floor %.3e against %.3e uncompensated%s: %s\n",
              c != nullptr ? c->best : -1.0, u != nullptr ? u->best : -1.0,
              quick ? "" : " (must be <= 2e-11)", ok ? "ok" : "-- OFF");
  if (!quick && split) {
    PrintSources(ctx, orbits);
    PrintSplit(ctx, sets, floors, orbits);
  }
  SUNContext_Free(&ctx);
  return ok ? 0 : 1;
}
