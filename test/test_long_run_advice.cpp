// The long-run table the stability guard advises from (src/ceode_long_run.cpp) against the
// measurement it came from: docs/data/long_run_pendulum.csv and long_run_oscillator.csv, written
// by `bench/long_run --csv ...` (10^7 steps at h = 1e-3, 5e6 at 2e-3; docs/stability.md), and the
// advice it gives for the cases at hand.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "../src/ceode_impl.hpp"

namespace {

using Row = std::map<std::string, std::string>;

std::vector<Row> ReadCsv(const std::string& path) {
  std::ifstream in(path);
  std::vector<Row> rows;
  std::string line;
  std::vector<std::string> head;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) cells.push_back(cell);
    if (head.empty()) {
      head = cells;
      continue;
    }
    Row r;
    for (size_t i = 0; i < head.size() && i < cells.size(); ++i) r[head[i]] = cells[i];
    rows.push_back(r);
  }
  return rows;
}

const std::string kData = std::string(CEODE_SOURCE_DIR) + "/docs/data/";

TEST(LongRunTable, MatchesThePendulumMeasurementForEveryNamedSet) {
  const std::vector<Row> rows = ReadCsv(kData + "long_run_pendulum.csv");
  ASSERT_EQ(static_cast<int>(rows.size()), CEodeGetNumMethods());
  for (const Row& r : rows) {
    const ceode::LongRunBehaviour* b = ceode::FindLongRunBehaviour(r.at("set").c_str());
    ASSERT_NE(b, nullptr) << r.at("set");
    const double rate = std::fabs(std::stod(r.at("drift_rate")));
    if (b->kind == ceode::kLongRunBounded) {
      EXPECT_EQ(r.at("verdict"), "bounded") << b->name;
      continue;
    }
    EXPECT_NEAR(b->drift_rate, rate, 0.01 * rate) << b->name;
    if (b->kind == ceode::kLongRunRoundOff) {  // below round-off at both step sizes
      EXPECT_LT(rate, 1e-14) << b->name;
      EXPECT_LT(std::fabs(std::stod(r.at("drift_rate_h2"))), 1e-14) << b->name;
      EXPECT_LT(std::stod(r.at("late")), 1e-11) << b->name;
    }
    if (b->kind == ceode::kLongRunLinearDrift) {
      EXPECT_EQ(r.at("verdict"), "linear drift") << b->name;
      EXPECT_NEAR(std::stod(r.at("p")), b->drift_order, 0.05) << b->name;  // both h agree
    }
  }
}

TEST(LongRunTable, CallsGrowingExactlyTheSetsThatBlowUpOrGrowOnTheOscillator) {
  for (const Row& r : ReadCsv(kData + "long_run_oscillator.csv")) {
    const ceode::LongRunBehaviour* b = ceode::FindLongRunBehaviour(r.at("set").c_str());
    ASSERT_NE(b, nullptr);
    const bool grows = r.at("verdict_h2") == "unstable" || r.at("verdict_h2") == "growing";
    EXPECT_EQ(grows, b->kind == ceode::kLongRunGrowing) << b->name;
    if (b->kind == ceode::kLongRunRoundOff) {
      EXPECT_LT(std::fabs(std::stod(r.at("drift_rate"))), 1e-14) << b->name;
      continue;
    }
    EXPECT_EQ(r.at("verdict") == "bounded", b->kind == ceode::kLongRunBounded) << b->name;
  }
}

std::string Advice(const char* current, double Omega) {
  char buf[512];
  return ceode::LongRunAdvice(current, Omega, buf, sizeof(buf));
}

TEST(LongRunAdvice, RecommendsTheBoundedSetAndTheSlowestStableDriftForTheStepAtHand) {
  // The pendulum at h = 1e-3 (Omega ~ 3e-3) with a weakly unstable set: G3_CD, then the set
  // without resolved drift that has the widest stability interval, G7_O7 (Omega_max 1.032).
  EXPECT_NE(Advice("G5", 3e-3).find("G3_CD"), std::string::npos);
  EXPECT_NE(Advice("G5", 3e-3).find("G7_O7"), std::string::npos);
  EXPECT_NE(Advice("G5", 0.9).find("G7_O7"), std::string::npos);
  // Beyond 0.9 * 1.032 no set without resolved drift is stable: the slowest linear drift,
  // G5_O4's (3.4e-13, where G4_A34 drifts at 4.3e-8).
  EXPECT_NE(Advice("G5", 0.95).find("G5_O4"), std::string::npos);
  // Beyond G5_TOP's limit 0.068 the slowest stable drift is G5_O4's, up to 0.9 * 1.97.
  EXPECT_NE(Advice("G4_A54", 1.0).find("G5_O4"), std::string::npos);
  EXPECT_EQ(Advice("G4_A54", 1.0).find("G5_TOP"), std::string::npos);
  EXPECT_NE(Advice("G4_A34", 1.7).find("G5_O4"), std::string::npos);
  // Between 0.9 * 1.97 and 0.9 * 2 only G3_CD is stable.
  EXPECT_NE(Advice("G4_A34", 1.78).find("G3_CD"), std::string::npos);
  EXPECT_EQ(Advice("G4_A34", 1.78).find("G5_O4"), std::string::npos);
  // Beyond every limit: reduce h. Already bounded: nothing to add.
  EXPECT_NE(Advice("G4_A34", 2.5).find("reduce h"), std::string::npos);
  EXPECT_EQ(Advice("G3_CD", 0.5), "");
  EXPECT_EQ(Advice("G3_CD", NAN), "");
}

}  // namespace
