// Linear stability analysis (docs/theory.md section 9) and the runtime stability guard.
#include <ceode/ceode.h>
#include <ceode/ceode_stability.h>
#include <gtest/gtest.h>
#include <nvector/nvector_serial.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "ceode_sundials_compat.h"  // SUN_COMM_NULL on SUNDIALS 6.4

namespace {

struct Set {
  int degree = 0;
  sunrealtype p[8] = {};
};

Set Named(const char* name) {
  Set s;
  EXPECT_EQ(CEodeGetMethodParams(name, &s.degree, s.p, 8), CE_SUCCESS) << name;
  return s;
}

sunrealtype Limit(const char* name, sunrealtype xi = 0) {
  const Set s = Named(name);
  sunrealtype lim = -1;
  EXPECT_EQ(CEodeStabilityLimit(s.degree, s.p, xi, &lim), CE_SUCCESS) << name;
  return lim;
}

sunrealtype Rho(const char* name, sunrealtype Omega, sunrealtype xi = 0) {
  const Set s = Named(name);
  sunrealtype rho = -1;
  EXPECT_EQ(CEodeSpectralRadius(s.degree, s.p, Omega, xi, &rho), CE_SUCCESS) << name;
  return rho;
}

// |a - b| within half a unit of b's third significant digit.
void ExpectThreeDigits(sunrealtype a, sunrealtype b) {
  const sunrealtype unit = std::pow(10.0, std::floor(std::log10(std::fabs(b))) - 2);
  EXPECT_LE(std::fabs(a - b), 0.5 * unit) << "measured " << a << ", claimed " << b;
}

TEST(StabilityLimit, MatchesThePapersThirdDegreeLimits) {
  ExpectThreeDigits(Limit("G3_CD"), 2.0);
  ExpectThreeDigits(Limit("G3_A43"), 1.549);
  ExpectThreeDigits(Limit("G3_A2"), 1.1547);
  // The closed forms of the paper's Section 4.2, to the scan's bisection accuracy.
  EXPECT_NEAR(Limit("G3_CD"), 2.0, 1e-9);
  EXPECT_NEAR(Limit("G3_A43"), std::sqrt(12.0 / 5.0), 1e-9);
  EXPECT_NEAR(Limit("G3_A2"), std::sqrt(4.0 / 3.0), 1e-9);
}

TEST(StabilityLimit, MatchesThePapersFourthDegreeLimitsToThreeDigits) {
  ExpectThreeDigits(Limit("G4_A14"), 1.2649);
  ExpectThreeDigits(Limit("G4_A34"), 1.731);
  // Measured: alpha = 1/4 gives sqrt(8/5); alpha = 3/4 gives sqrt(3) = 1.7320508, where a
  // real eigenvalue crosses -1. The paper's 1.7310020041 is off in the fourth digit.
  EXPECT_NEAR(Limit("G4_A14"), std::sqrt(8.0 / 5.0), 1e-9);
  EXPECT_NEAR(Limit("G4_A34"), std::sqrt(3.0), 1e-7);
}

TEST(StabilityLimit, IsZeroForTheSetThatIsUnstableForEveryStep) {
  EXPECT_EQ(Limit("G4_A54"), 0.0);
  for (sunrealtype Omega : {1e-3, 1e-2, 0.1, 0.5}) EXPECT_GT(Rho("G4_A54", Omega), 1.0);
}

TEST(StabilityLimit, FindsTheFifthDegreeSetUnstableForEveryStepContraryToThePapersClaim) {
  // The paper claims Omega_max ~ 0.6 for (4/5, 1, 1, 1). The step map (which reproduces the
  // paper's Table 6 pendulum errors) has rho - 1 ~ (4/15) Omega^2 > 0 for every Omega.
  EXPECT_EQ(Limit("G5"), 0.0);
  EXPECT_NEAR(Rho("G5", 0.01) - 1, 4.0 / 15.0 * 1e-4, 1e-7);
  EXPECT_GT(Rho("G5", 0.3), 1.02);
}

std::vector<std::vector<std::string>> ReadCsv(const std::string& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << path;
  std::vector<std::vector<std::string>> rows;
  std::string line;
  bool header = true;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (header) {
      header = false;
      continue;
    }
    std::vector<std::string> row;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) row.push_back(cell);
    rows.push_back(row);
  }
  return rows;
}

TEST(SpectralRadius, ReproducesThePapersTable5ForTheUnstableFourthDegreeSet) {
  const auto rows = ReadCsv(std::string(CEODE_TEST_DATA_DIR) + "/paper_table5.csv");
  ASSERT_EQ(rows.size(), 3u);
  for (const auto& r : rows) {
    const sunrealtype rho = Rho("G4_A54", std::stod(r[0]));
    // Agreement to every digit the paper prints (7 or 8 decimals): within half a unit of
    // its last digit, which is also better than the 6 digits asked for.
    const size_t decimals = r[1].size() - r[1].find('.') - 1;
    EXPECT_NEAR(rho, std::stod(r[1]), 0.5 * std::pow(10.0, -static_cast<double>(decimals)))
        << "Omega = " << r[0];
    EXPECT_NEAR(rho, std::stod(r[1]), 5e-7) << "Omega = " << r[0];
  }
}

TEST(SpectralRadius, DropsBelowOneWithDampingForAStableThirdDegreeSet) {
  for (const char* name : {"G3_CD", "G3_A43", "G3_A2"}) {
    for (sunrealtype Omega : {0.01, 0.1, 0.5, 1.0}) {
      const sunrealtype undamped = Rho(name, Omega, 0);
      const sunrealtype light = Rho(name, Omega, 0.02);
      const sunrealtype heavy = Rho(name, Omega, 0.1);
      EXPECT_LE(undamped, 1 + 1e-12) << name;
      EXPECT_LT(light, undamped) << name << " Omega " << Omega;
      EXPECT_LT(heavy, light) << name << " Omega " << Omega;
    }
    // The exact decay per step is exp(-xi Omega); the radius follows it for small Omega.
    EXPECT_NEAR(Rho(name, 0.01, 0.05), std::exp(-0.05 * 0.01), 1e-6) << name;
    EXPECT_NEAR(Limit(name, 0.05), Limit(name, 0), 1e-6) << name;
  }
}

TEST(SpectralRadius, ShowsThatDampingPushesTheFourthDegreeSpuriousRootOutside) {
  // With gamma = 1/2 the jerk recurrence has a root at -1; the implicit velocity coupling
  // of a damped problem moves it outside by about (2/3) xi Omega: every h is unstable.
  EXPECT_NEAR(Rho("G4_A34", 1e-3, 0.05) - 1, 2.0 / 3.0 * 0.05 * 1e-3, 1e-7);
  EXPECT_EQ(Limit("G4_A34", 0.05), 0.0);
}

TEST(SpectralRadii, AgreeWithOnePointAtATime) {
  const Set s = Named("G4_A34");
  const std::vector<sunrealtype> Om = {0.05, 0.7, 1.7, 1.8};
  std::vector<sunrealtype> rho(Om.size());
  ASSERT_EQ(CEodeSpectralRadii(s.degree, s.p, 0, 4, Om.data(), rho.data()), CE_SUCCESS);
  for (size_t i = 0; i < Om.size(); ++i) EXPECT_DOUBLE_EQ(rho[i], Rho("G4_A34", Om[i]));
}

// Velocity Verlet with damping, derived by hand on the state (x(t), v(t-h), a(t-h)), h = 1:
//   a = -W^2 x - 2 xi W v,  v = v0 + (a0 + a)/2,  x(t+h) = x + v + a/2.
// Rows x(t+h), v(t), a(t) as functions of (x, v0, a0).
void VerletByHand(double W, double xi, double B[3][3]) {
  const double s = 1 + xi * W;  // a (1 + xi W) = -W^2 x - 2 xi W (v0 + a0/2)
  const double a[3] = {-W * W / s, -2 * xi * W / s, -xi * W / s};
  const double v0[3] = {0, 1, 0.5};
  for (int j = 0; j < 3; ++j) {
    B[2][j] = a[j];
    B[1][j] = v0[j] + 0.5 * a[j];
    B[0][j] = (j == 0 ? 1 : 0) + B[1][j] + 0.5 * a[j];
  }
}

TEST(AmplificationMatrix, AgreesWithAHandDerivedVelocityVerletMap) {
  const Set s = Named("G3_CD");
  for (double xi : {0.0, 0.1}) {
    for (double W : {0.3, 1.0, 1.9}) {
      sunrealtype A[9];
      ASSERT_EQ(CEodeAmplificationMatrix(3, s.p, W, xi, A), CE_SUCCESS);
      double B[3][3];
      VerletByHand(W, xi, B);
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
          EXPECT_NEAR(A[3 * i + j], B[i][j], 1e-13) << "W " << W << " xi " << xi;
        }
      }
    }
  }
}

// x'' = -x, one degree of freedom.
int Oscillator(sunrealtype, N_Vector x, N_Vector, N_Vector f, void*) {
  N_VScale(-1, x, f);
  return 0;
}

struct Captured {
  std::string msg;
  int flag = 0;
};

void Capture(int flag, const char*, const char*, char* msg, void* data) {
  auto* c = static_cast<Captured*>(data);
  c->flag = flag;
  c->msg = msg;
}

class GuardRun : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(SUNContext_Create(SUN_COMM_NULL, &ctx_), 0);
    x_ = N_VNew_Serial(1, ctx_);
    v_ = N_VNew_Serial(1, ctx_);
    NV_Ith_S(x_, 0) = 1;
    NV_Ith_S(v_, 0) = 0;
    mem_ = CEodeCreate(ctx_);
    ASSERT_EQ(CEodeInit(mem_, Oscillator, 0, x_, v_), CE_SUCCESS);
    ASSERT_EQ(CEodeSetErrHandlerFn(mem_, Capture, &captured_), CE_SUCCESS);
  }
  void TearDown() override {
    CEodeFree(&mem_);
    N_VDestroy(x_);
    N_VDestroy(v_);
    SUNContext_Free(&ctx_);
  }
  SUNContext ctx_ = nullptr;
  N_Vector x_ = nullptr;
  N_Vector v_ = nullptr;
  void* mem_ = nullptr;
  Captured captured_;
};

// The guard looks the named sets' limits up in the library's table instead of scanning their
// spectrum at every start: the step it gives (omega_max = 1 given, safety 1) must be the limit
// CEodeStabilityLimit computes, to the last bits a recomputation on another build may move.
class NamedSetGuard : public GuardRun, public ::testing::WithParamInterface<int> {};

TEST_P(NamedSetGuard, GivesTheStepOfTheComputedStabilityLimit) {
  const char* name = CEodeGetMethodName(GetParam());
  ASSERT_NE(name, nullptr);
  ASSERT_EQ(CEodeSetMethodByName(mem_, name), CE_SUCCESS);
  ASSERT_EQ(CEodeSetMaxFrequency(mem_, 1.0), CE_SUCCESS);
  sunrealtype hmax = -1;
  ASSERT_EQ(CEodeGetStableStep(mem_, 1, &hmax), CE_SUCCESS);
  const sunrealtype computed = Limit(name);
  EXPECT_NEAR(hmax, computed, 1e-12 * computed) << name;
}

INSTANTIATE_TEST_SUITE_P(EveryNamedSet, NamedSetGuard, ::testing::Range(0, CEodeGetNumMethods()),
                         [](const ::testing::TestParamInfo<int>& p) {
                           return std::string(CEodeGetMethodName(p.param));
                         });

TEST_F(GuardRun, PastTheLimitWithTheGuardOffEndsUnstableWithFiniteOutput) {
  ASSERT_EQ(CEodeSetMethodByName(mem_, "G3_CD"), CE_SUCCESS);
  ASSERT_EQ(CEodeSetFixedStep(mem_, 2.1), CE_SUCCESS);
  ASSERT_EQ(CEodeSetStabilityGuard(mem_, CE_GUARD_OFF, 0), CE_SUCCESS);
  sunrealtype t = 0;
  const int flag = CEodeEvolve(mem_, 1e6, x_, v_, &t, CE_NORMAL);
  EXPECT_EQ(flag, CE_UNSTABLE);
  EXPECT_TRUE(std::isfinite(NV_Ith_S(x_, 0)));
  EXPECT_TRUE(std::isfinite(NV_Ith_S(v_, 0)));
  EXPECT_GT(t, 0);
  EXPECT_LT(t, 1e6);
  EXPECT_NE(captured_.msg.find("step"), std::string::npos) << captured_.msg;
  EXPECT_NE(captured_.msg.find("stability limit"), std::string::npos) << captured_.msg;
}

TEST_F(GuardRun, RefusesAtTheStartAndNamesTheLimit) {
  ASSERT_EQ(CEodeSetMethodByName(mem_, "G3_CD"), CE_SUCCESS);
  ASSERT_EQ(CEodeSetFixedStep(mem_, 2.1), CE_SUCCESS);
  ASSERT_EQ(CEodeSetStabilityGuard(mem_, CE_GUARD_REFUSE, 0), CE_SUCCESS);
  sunrealtype t = -1;
  EXPECT_EQ(CEodeEvolve(mem_, 100, x_, v_, &t, CE_NORMAL), CE_UNSTABLE);
  EXPECT_EQ(t, 0);
  EXPECT_EQ(NV_Ith_S(x_, 0), 1);
  EXPECT_TRUE(std::isfinite(NV_Ith_S(v_, 0)));
  EXPECT_NE(captured_.msg.find("Omega_max = 2"), std::string::npos) << captured_.msg;
  EXPECT_NE(captured_.msg.find("h <= 1.98"), std::string::npos) << captured_.msg;  // 0.99 * 2
  sunrealtype omega = 0;
  ASSERT_EQ(CEodeGetMaxFrequencyEstimate(mem_, &omega), CE_SUCCESS);
  EXPECT_NEAR(omega, 1.0, 1e-4);
  // Calling again does not slip past the refusal.
  EXPECT_EQ(CEodeEvolve(mem_, 100, x_, v_, &t, CE_NORMAL), CE_UNSTABLE);
  long int nst = -1;
  CEodeGetNumSteps(mem_, &nst);
  EXPECT_EQ(nst, 0);
}

TEST_F(GuardRun, WarnsButRunsAndTrustsTheUsersFrequency) {
  ASSERT_EQ(CEodeSetMethodByName(mem_, "G3_CD"), CE_SUCCESS);
  ASSERT_EQ(CEodeSetFixedStep(mem_, 0.5), CE_SUCCESS);
  ASSERT_EQ(CEodeSetMaxFrequency(mem_, 5.0), CE_SUCCESS);  // 0.5 * 5 = 2.5 > 2
  ASSERT_EQ(CEodeSetStabilityGuard(mem_, CE_GUARD_WARN, 0), CE_SUCCESS);
  sunrealtype t = 0;
  EXPECT_EQ(CEodeEvolve(mem_, 10, x_, v_, &t, CE_NORMAL), CE_SUCCESS);
  EXPECT_EQ(captured_.flag, CE_WARNING);
  EXPECT_NE(captured_.msg.find("CEodeSetMaxFrequency"), std::string::npos) << captured_.msg;
  sunrealtype omega = 0;
  CEodeGetMaxFrequencyEstimate(mem_, &omega);
  EXPECT_EQ(omega, 5.0);
}

TEST_F(GuardRun, StaysSilentInsideTheLimit) {
  ASSERT_EQ(CEodeSetMethodByName(mem_, "G4_A34"), CE_SUCCESS);
  ASSERT_EQ(CEodeSetFixedStep(mem_, 1.7), CE_SUCCESS);
  ASSERT_EQ(CEodeSetStabilityGuard(mem_, CE_GUARD_REFUSE, 10), CE_SUCCESS);
  sunrealtype t = 0;
  EXPECT_EQ(CEodeEvolve(mem_, 200, x_, v_, &t, CE_NORMAL), CE_SUCCESS);
  EXPECT_TRUE(captured_.msg.empty()) << captured_.msg;
}

// A fixed-fixed chain of n unit masses with springs k_i spanning 1 .. 1e4.
struct Chain {
  int n;
  std::vector<double> k;  // n + 1 springs
};

int ChainRhs(sunrealtype, N_Vector x, N_Vector, N_Vector f, void* data) {
  const auto* c = static_cast<const Chain*>(data);
  const double* xd = N_VGetArrayPointer(x);
  double* fd = N_VGetArrayPointer(f);
  for (int i = 0; i < c->n; ++i) {
    const double left = i > 0 ? xd[i - 1] : 0;
    const double right = i + 1 < c->n ? xd[i + 1] : 0;
    fd[i] = -c->k[i] * (xd[i] - left) + c->k[i + 1] * (right - xd[i]);
  }
  return 0;
}

// Largest eigenvalue of the chain's stiffness matrix by Sturm-sequence bisection.
double TopEigenvalue(const Chain& c) {
  auto count_below = [&](double lam) {  // eigenvalues < lam = negative LDL^T pivots
    int neg = 0;
    double d = 1;
    for (int i = 0; i < c.n; ++i) {
      const double off = i > 0 ? c.k[i] : 0;
      d = (c.k[i] + c.k[i + 1] - lam) - (i > 0 ? off * off / d : 0);
      if (d == 0) d = -1e-300;
      if (d < 0) ++neg;
    }
    return neg;
  };
  double lo = 0;
  double hi = 0;
  for (int i = 0; i < c.n; ++i) hi = std::max(hi, 2 * (c.k[i] + c.k[i + 1]));  // Gershgorin
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    (count_below(mid) < c.n ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

TEST(StabilityGuard, EstimatesTheTopFrequencyOfASpringChainWithinTwoPercent) {
  Chain c{40, {}};
  for (int i = 0; i <= c.n; ++i) c.k.push_back(std::pow(1e4, static_cast<double>(i) / c.n));
  const double omega_exact = std::sqrt(TopEigenvalue(c));
  SUNContext ctx = nullptr;
  ASSERT_EQ(SUNContext_Create(SUN_COMM_NULL, &ctx), 0);
  N_Vector x = N_VNew_Serial(c.n, ctx);
  N_Vector v = N_VNew_Serial(c.n, ctx);
  for (int i = 0; i < c.n; ++i) NV_Ith_S(x, i) = std::sin(0.3 * i);
  N_VConst(0, v);
  void* mem = CEodeCreate(ctx);
  ASSERT_EQ(CEodeInit(mem, ChainRhs, 0, x, v), CE_SUCCESS);
  CEodeSetUserData(mem, &c);
  CEodeSetErrFile(mem, nullptr);
  CEodeSetFixedStep(mem, 1e-3);
  CEodeSetStabilityGuard(mem, CE_GUARD_WARN, 0);
  sunrealtype t = 0;
  ASSERT_EQ(CEodeEvolve(mem, 1e-3, x, v, &t, CE_ONE_STEP), CE_SUCCESS);
  sunrealtype omega = 0;
  ASSERT_EQ(CEodeGetMaxFrequencyEstimate(mem, &omega), CE_SUCCESS);
  EXPECT_NEAR(omega / omega_exact, 1.0, 0.02) << omega << " vs " << omega_exact;
  CEodeFree(&mem);
  N_VDestroy(x);
  N_VDestroy(v);
  SUNContext_Free(&ctx);
}

TEST(StabilityApi, RejectsBadArgumentsWithIllInput) {
  const Set s = Named("G3_CD");
  sunrealtype r = 0;
  sunrealtype A[9];
  const sunrealtype nan = std::nan("");
  EXPECT_EQ(CEodeSpectralRadius(2, s.p, 1, 0, &r), CE_ILL_INPUT);
  EXPECT_EQ(CEodeSpectralRadius(9, s.p, 1, 0, &r), CE_ILL_INPUT);
  EXPECT_EQ(CEodeSpectralRadius(3, nullptr, 1, 0, &r), CE_ILL_INPUT);
  EXPECT_EQ(CEodeSpectralRadius(3, s.p, -1, 0, &r), CE_ILL_INPUT);
  EXPECT_EQ(CEodeSpectralRadius(3, s.p, nan, 0, &r), CE_ILL_INPUT);
  EXPECT_EQ(CEodeSpectralRadius(3, s.p, 1, -0.1, &r), CE_ILL_INPUT);
  EXPECT_EQ(CEodeSpectralRadius(3, s.p, 1, 0, nullptr), CE_ILL_INPUT);
  const sunrealtype zero_beta[2] = {1, 0};
  EXPECT_EQ(CEodeSpectralRadius(3, zero_beta, 1, 0, &r), CE_ILL_INPUT);
  EXPECT_EQ(CEodeStabilityLimit(3, s.p, 0, nullptr), CE_ILL_INPUT);
  EXPECT_EQ(CEodeStabilityLimit(1, s.p, 0, &r), CE_ILL_INPUT);
  EXPECT_EQ(CEodeAmplificationMatrix(3, s.p, 1, 0, nullptr), CE_ILL_INPUT);
  EXPECT_EQ(CEodeAmplificationMatrix(3, s.p, nan, 0, A), CE_ILL_INPUT);
  const sunrealtype Om[1] = {-2};
  EXPECT_EQ(CEodeSpectralRadii(3, s.p, 0, 1, Om, &r), CE_ILL_INPUT);
  EXPECT_EQ(CEodeSpectralRadii(3, s.p, 0, -1, Om, &r), CE_ILL_INPUT);

  SUNContext ctx = nullptr;
  ASSERT_EQ(SUNContext_Create(SUN_COMM_NULL, &ctx), 0);
  void* mem = CEodeCreate(ctx);
  CEodeSetErrFile(mem, nullptr);
  EXPECT_EQ(CEodeSetStabilityGuard(mem, 7, 0), CE_ILL_INPUT);
  EXPECT_EQ(CEodeSetStabilityGuard(mem, CE_GUARD_WARN, -1), CE_ILL_INPUT);
  EXPECT_EQ(CEodeSetMaxFrequency(mem, -1), CE_ILL_INPUT);
  EXPECT_EQ(CEodeSetMaxFrequency(mem, nan), CE_ILL_INPUT);
  EXPECT_EQ(CEodeGetMaxFrequencyEstimate(mem, nullptr), CE_ILL_INPUT);
  CEodeFree(&mem);
  SUNContext_Free(&ctx);
}

}  // namespace
