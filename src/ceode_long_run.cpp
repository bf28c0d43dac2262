// What each named set conserves over long runs, and the advice that follows for a given
// Omega = h * omega_max. The figures are measurements of bench/long_run (10^7 steps of the
// pendulum and of the linear oscillator at h = 1e-3 and 2e-3; table and command in
// docs/stability.md, "Long runs"); the limits are those of docs/data/stability_limits.csv.
// Pure functions: no CEODE memory, no allocation, so the stability guard can call them anywhere.
#include <cmath>
#include <cstdio>
#include <cstring>

#include "ceode_impl.hpp"

namespace ceode {

namespace {

// Ordered as the method table (ceode_method.cpp).
constexpr LongRunBehaviour kLongRun[] = {
    {"G3_CD", kLongRunBounded, 0, 0, 2.0},
    {"G3_A43", kLongRunLinearDrift, 8.63e-8, 3, 1.549193338},
    {"G3_A2", kLongRunLinearDrift, 2.59e-7, 3, 1.154700538},
    {"G4_A54", kLongRunGrowing, 1.66e-13, 0, 0},  // order: the 2e-3 run grows, no fit
    {"G4_A14", kLongRunLinearDrift, 8.63e-8, 3, 1.264911064},
    {"G4_A34", kLongRunLinearDrift, 4.31e-8, 3, 1.732050814},
    {"G5", kLongRunGrowing, 2.65e-13, 0, 0},
    {"G5_TOP", kLongRunLinearDrift, 4.08e-11, 3, 0.06816569051},
    {"G5_ONES", kLongRunGrowing, 1.65e-13, 0, 0},
    {"G5_O4", kLongRunLinearDrift, 3.38e-13, 5, 1.970651341},
    {"G6_O5", kLongRunLinearDrift, 2.25e-13, 5, 0.8050},
    {"G6_O6", kLongRunRoundOff, 1.42e-16, 0, 0.066},
    {"G7_O7", kLongRunRoundOff, 8.18e-16, 0, 1.0320},
    {"G8_O8", kLongRunRoundOff, 3.83e-16, 0, 0.9891},
};

// Steps that stay this far inside a limit are not on its edge (the guard's estimate of
// omega_max is a lower bound).
constexpr sunrealtype kLimitMargin = 0.9;

bool StableAt(const LongRunBehaviour& b, sunrealtype Omega) {
  return b.omega_max > 0 && Omega < kLimitMargin * b.omega_max;
}

// The set to recommend beside G3_CD at Omega (nullptr: none). Sets whose drift stayed below
// round-off are tied on drift (their fitted rates are noise), so the widest stability margin
// decides among them; otherwise the drifting set with the slowest measured drift.
const LongRunBehaviour* SlowestStableDrift(sunrealtype Omega) {
  const LongRunBehaviour* roundoff = nullptr;
  const LongRunBehaviour* drift = nullptr;
  for (const LongRunBehaviour& b : kLongRun) {
    if (!StableAt(b, Omega)) continue;
    if (b.kind == kLongRunRoundOff && (roundoff == nullptr || b.omega_max > roundoff->omega_max)) {
      roundoff = &b;
    }
    if (b.kind == kLongRunLinearDrift && (drift == nullptr || b.drift_rate < drift->drift_rate)) {
      drift = &b;
    }
  }
  return roundoff != nullptr ? roundoff : drift;
}

}  // namespace

const LongRunBehaviour* FindLongRunBehaviour(const char* name) {
  if (name == nullptr) return nullptr;
  for (const LongRunBehaviour& b : kLongRun) {
    if (std::strcmp(b.name, name) == 0) return &b;
  }
  return nullptr;
}

const char* LongRunAdvice(const char* current, sunrealtype Omega, char* buf, size_t len) {
  if (buf == nullptr || len == 0) return "";
  buf[0] = '\0';
  const LongRunBehaviour& cd = kLongRun[0];
  if (!std::isfinite(Omega) || Omega < 0) return buf;
  if (!StableAt(cd, Omega)) {
    std::snprintf(
        buf, len,
        "no named set is stable at Omega = %.3g (the largest limit is G3_CD's 2): reduce h",
        static_cast<double>(Omega));
    return buf;
  }
  const LongRunBehaviour* cur = FindLongRunBehaviour(current);
  if (cur == &cd) return buf;  // already the set whose energy error stays bounded
  const LongRunBehaviour* drift = SlowestStableDrift(Omega);
  if (drift == nullptr || (cur != nullptr && cur == drift)) {
    std::snprintf(buf, len,
                  "for long runs use G3_CD, whose energy error stays bounded (every other named "
                  "set drifts or grows, docs/stability.md)");
  } else if (drift->kind == kLongRunRoundOff) {
    std::snprintf(buf, len,
                  "for long runs use G3_CD, whose energy error stays bounded; if its second order "
                  "is not accurate enough, %s is stable here and its energy drift stayed below "
                  "round-off over 10^7 steps (docs/stability.md)",
                  drift->name);
  } else {
    std::snprintf(buf, len,
                  "for long runs use G3_CD, whose energy error stays bounded; if its second order "
                  "is not accurate enough, %s is stable here and drifts slowest (linearly, "
                  "proportional to h^%d; docs/stability.md)",
                  drift->name, drift->drift_order);
  }
  return buf;
}

}  // namespace ceode
