// Regression against the paper's pendulum tables (docs/theory.md section 11):
// the max energy error over 10 s of the IFToMM simple pendulum must match the
// published figure within 5 % at h = 1e-3 and 1e-4 wherever it is above 1e-10
// (below that the figures are round-off and machine dependent).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "test_util.hpp"

namespace {

using ceode_test::PendulumEnergyError;

struct Reference {
  std::string method;
  double h = 0;
  double error = 0;
};

std::vector<Reference> LoadReferences() {
  std::vector<Reference> rows;
  std::ifstream in(std::string(CEODE_TEST_DATA_DIR) + "/paper_pendulum_ode.csv");
  std::string line;
  bool header = true;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (header) {  // method,h,error
      header = false;
      continue;
    }
    std::stringstream ss(line);
    Reference r;
    std::string h, e;
    std::getline(ss, r.method, ',');
    std::getline(ss, h, ',');
    std::getline(ss, e, ',');
    r.h = std::stod(h);
    r.error = std::stod(e);
    rows.push_back(r);
  }
  return rows;
}

// The rows this test judges: h = 1e-3 or 1e-4 and a figure above 1e-10.
std::vector<Reference> CheckedReferences() {
  std::vector<Reference> out;
  for (const Reference& r : LoadReferences()) {
    const bool step_checked = std::fabs(r.h - 1e-3) < 1e-12 || std::fabs(r.h - 1e-4) < 1e-13;
    if (step_checked && r.error > 1e-10) out.push_back(r);
  }
  return out;
}

// The paper's figures carry 3 to 6 digits and were reproduced to 3 digits;
// 5 % is the project's acceptance band (examples/pendulum_ode.c uses the same).
constexpr double kRelTol = 0.05;

TEST(PaperPendulumTable, HoldsEveryFigureTheTestJudges) {
  // Tables 1-2 (G3, 3 sets x 2 steps) and 4 (G4_A14, G4_A34 x 2 steps) give 10
  // figures above 1e-10; G4_A54 and G5 are below it at these steps.
  EXPECT_EQ(LoadReferences().size(), 32u);
  EXPECT_EQ(CheckedReferences().size(), 10u);
}

struct Case {
  Reference ref;
  bool zero_start;
};

std::ostream& operator<<(std::ostream& os, const Case& c) {
  return os << c.ref.method << " h=" << c.ref.h << (c.zero_start ? " zero start" : "");
}

std::vector<Case> AllCases() {
  std::vector<Case> out;
  for (const Reference& r : CheckedReferences()) {
    out.push_back({r, true});
    out.push_back({r, false});
  }
  return out;
}

class PaperPendulum : public ::testing::TestWithParam<Case> {};

// With the paper's zero start the runs are the paper's runs. The pendulum starts
// at rest from the horizontal, so its true jerk and x^(4) vanish at t = 0 and the
// consistent start must reproduce the same figures.
TEST_P(PaperPendulum, MatchesThePublishedEnergyErrorWithinFivePercent) {
  const Case& c = GetParam();
  const double err = PendulumEnergyError(c.ref.method, c.ref.h, c.zero_start);
  std::printf("[ pendulum ] %-7s h = %g %-16s error = %.6e  paper = %.6e  ratio = %.4f\n",
              c.ref.method.c_str(), c.ref.h, c.zero_start ? "zero start" : "consistent start", err,
              c.ref.error, err / c.ref.error);
  RecordProperty("error", std::to_string(err));
  EXPECT_NEAR(err / c.ref.error, 1.0, kRelTol);
}

INSTANTIATE_TEST_SUITE_P(Tables1To6, PaperPendulum, ::testing::ValuesIn(AllCases()),
                         [](const ::testing::TestParamInfo<Case>& info) {
                           const Case& c = info.param;
                           const int e = static_cast<int>(std::lround(-std::log10(c.ref.h)));
                           return c.ref.method + "AtHTenToMinus" + std::to_string(e) +
                                  (c.zero_start ? "WithPapersZeroStart" : "WithConsistentStart");
                         });

}  // namespace
