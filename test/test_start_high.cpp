// The consistent start for degrees >= 6 (src/ceode_start.cpp): the error of every start
// derivative D_3 .. D_7 of G8_O8, against its exact Taylor coefficients, must fall at least as
// fast as h^(2R+3-k) (R = 3 for an order-8 set of degree 8), as fast as an order-8 set needs
// (docs/theory.md section 6.3): on the damped driven pendulum (f reads the velocity: d - 3 = 5
// sweeps, of half widths 1, 2, 2, 3, 3) and on a driven pendulum without damping, declared velocity
// independent (each sweep moves the errors two derivatives up: (d - 2) / 2 = 3 sweeps, of half
// widths 1, 2, 3).
//
// This test drives the internal StartDerivatives directly (through ceode_impl.hpp): the public
// API never exposes the history at t0.
#include <ceode/ceode.h>
#include <gtest/gtest.h>
#include <nvector/nvector_serial.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "../src/ceode_impl.hpp"
#include "test_util.hpp"

namespace {

using ceode_test::FitOrder;

int Driven(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, void* /*data*/) {
  NV_Ith_S(f, 0) = -9.81 * std::cos(NV_Ith_S(x, 0)) - 0.5 * NV_Ith_S(v, 0) + std::sin(2 * t);
  return 0;
}

int Undamped(sunrealtype t, N_Vector x, N_Vector /*v*/, N_Vector f, void* /*data*/) {
  NV_Ith_S(f, 0) = -9.81 * std::cos(NV_Ith_S(x, 0)) + std::sin(2 * t) + 0.5 * std::cos(3 * t);
  return 0;
}

// One problem: theta'' = f, theta(0) = theta'(0) = 0, and theta^(k)(0) from the
// Taylor-coefficient recursion (sin/cos of a series, in 40-digit arithmetic, 17 digits printed):
//   th[n+2] = (-9.81 c[n] - b (n+1) th[n+1] + [forcing]_n) / ((n+2)(n+1)),
//   n s[n] = sum_k k th[k] c[n-k],  n c[n] = -sum_k k th[k] s[n-k].
struct Case {
  const char* name;
  CEodeRhsFn f;
  bool vel_dependent;
  long start_evals;  // 2r for each sweep of half width r
  double exact[8];
};

const Case kCases[] = {
    {"DampedDriven",
     Driven,
     true,
     2 + 4 + 4 + 6 + 6,
     {0, 0, -9.81, 6.905, -3.4525, -6.27375, 2835.365298, -8030.785354}},
    {"UndampedVelocityIndependent",
     Undamped,
     false,
     2 + 4 + 6,
     {0, 0, -9.31, 2, -4.5, -8, 2591.377623, -1794.622}},
};

// D_3 .. D_7 after the start with step h; *nfe: f evaluations the start took.
std::vector<double> StartErrors(const Case& c, sunrealtype h, long* nfe) {
  ceode_test::Context ctx;
  ceode_test::Vector x = ceode_test::SerialVector(1, ctx, 0);
  ceode_test::Vector v = ceode_test::SerialVector(1, ctx, 0);
  ceode_test::Mem mem(CEodeCreate(ctx));
  ceode_test::Matrix A(SUNDenseMatrix(1, 1, ctx));
  ceode_test::LinearSolver LS(SUNLinSol_Dense(x.get(), A.get(), ctx));
  EXPECT_EQ(CEodeInit(mem.get(), c.f, 0, x.get(), v.get()), CE_SUCCESS);
  EXPECT_EQ(CEodeSetMethodByName(mem.get(), "G8_O8"), CE_SUCCESS);
  EXPECT_EQ(CEodeSetFixedStep(mem.get(), h), CE_SUCCESS);
  if (c.vel_dependent) {
    EXPECT_EQ(CEodeSetVelocityDependence(mem.get(), SUNTRUE), CE_SUCCESS);
    EXPECT_EQ(CEodeSetLinearSolver(mem.get(), LS.get(), A.get()), CE_SUCCESS);
  }
  sunrealtype t = 0;
  EXPECT_EQ(CEodeEvolve(mem.get(), h, x.get(), v.get(), &t, CE_ONE_STEP), CE_SUCCESS);
  // Back to t0 with every vector allocated: rerun the start there.
  auto* ce = static_cast<CEodeMemRec*>(mem.get());
  N_VConst(0, ce->xcur);
  N_VConst(0, ce->D[1]);
  EXPECT_EQ(ceode::EvalAccel(ce, 0, ce->xcur, ce->D[1], ce->D[2], "test"), CE_SUCCESS);
  const long nfe0 = ce->nfe;
  EXPECT_EQ(ceode::StartDerivatives(ce, 0, ce->xnew, ce->vtmp, ce->atmp,
                                    [&](sunrealtype ts, N_Vector xs, N_Vector vs, N_Vector as) {
                                      return ceode::EvalAccel(ce, ts, xs, vs, as, "test");
                                    }),
            CE_SUCCESS);
  *nfe = ce->nfe - nfe0;
  std::vector<double> err;
  for (int k = 3; k < 8; ++k) err.push_back(std::fabs(NV_Ith_S(ce->D[k], 0) - c.exact[k]));
  return err;
}

class HighDegreeStart : public ::testing::TestWithParam<Case> {};

TEST_P(HighDegreeStart, DeliversEveryDerivativeToTheOrderAnEighthOrderSetNeeds) {
  const Case& c = GetParam();
  const std::vector<double> hs = {0.05, 0.025, 0.0125};
  std::vector<std::vector<double>> err(5);
  for (double h : hs) {
    long nfe = 0;
    const std::vector<double> e = StartErrors(c, h, &nfe);
    EXPECT_EQ(nfe, c.start_evals);
    std::printf("[ start    ] %s h = %-7g", c.name, h);
    for (int k = 0; k < 5; ++k) {
      err[k].push_back(e[k]);
      std::printf("  |dD%d| %.2e", k + 3, e[k]);
    }
    std::printf("\n");
  }
  for (int k = 3; k < 8; ++k) {
    const double order = FitOrder(hs, err[k - 3]);
    std::printf("[ start    ] %s D%d error ~ h^%.2f (needed for order 8: h^%d)\n", c.name, k, order,
                9 - k);
    EXPECT_GT(order, 9 - k - 0.5) << "D" << k;  // 2R + 3 - k with R = 3
  }
}

// The start's evaluations through the public API (CEodeGetNumStartRhsEvals): a_0 and 2r for each
// sweep of half width r, the last sweep's R = 2 for the sets of degree 6 and 3 for degrees 7 and
// 8, the earlier ones as narrow as the set's order p allows, ceil((p - 2 - g(S - i)) / 2) for
// sweep i of S with a gain g of 2 (f does not read the velocity) or 1 (docs/theory.md 6.3).
struct StartCost {
  const char* set;
  bool vel_dependent;
  bool tolerances;  // error control: its first step's size comes from the same a_0
  long nfe;
};

void PrintTo(const StartCost& c, std::ostream* os) {
  *os << c.set << (c.vel_dependent ? " velocity dependent" : "")
      << (c.tolerances ? " with tolerances" : "") << ": " << c.nfe;
}

long StartEvaluations(const StartCost& c) {
  ceode_test::Context ctx;
  ceode_test::Vector x = ceode_test::SerialVector(1, ctx, 0);
  ceode_test::Vector v = ceode_test::SerialVector(1, ctx, 0);
  ceode_test::Mem mem(CEodeCreate(ctx));
  ceode_test::Matrix A(SUNDenseMatrix(1, 1, ctx));
  ceode_test::LinearSolver LS(SUNLinSol_Dense(x.get(), A.get(), ctx));
  EXPECT_EQ(CEodeInit(mem.get(), c.vel_dependent ? Driven : Undamped, 0, x.get(), v.get()),
            CE_SUCCESS);
  EXPECT_EQ(CEodeSetMethodByName(mem.get(), c.set), CE_SUCCESS);
  EXPECT_EQ(CEodeSetVelocityDependence(mem.get(), c.vel_dependent ? SUNTRUE : SUNFALSE),
            CE_SUCCESS);
  if (c.vel_dependent) EXPECT_EQ(CEodeSetLinearSolver(mem.get(), LS.get(), A.get()), CE_SUCCESS);
  if (c.tolerances) {
    EXPECT_EQ(CEodeSStolerances(mem.get(), 1e-8, 1e-8), CE_SUCCESS);
  } else {
    EXPECT_EQ(CEodeSetFixedStep(mem.get(), 0.01), CE_SUCCESS);
  }
  sunrealtype t = 0;
  EXPECT_EQ(CEodeEvolve(mem.get(), 1, x.get(), v.get(), &t, CE_ONE_STEP), CE_SUCCESS);
  long nfe = -1;
  EXPECT_EQ(CEodeGetNumStartRhsEvals(mem.get(), &nfe), CE_SUCCESS);
  return nfe;
}

class HighDegreeStartCost : public ::testing::TestWithParam<StartCost> {};

TEST_P(HighDegreeStartCost, IsTheInitialAccelerationAndTheSweepsOfTheSetsStencil) {
  EXPECT_EQ(StartEvaluations(GetParam()), GetParam().nfe);
}

const StartCost kStartCosts[] = {{"G6_O5", false, false, 1 + 2 + 4},
                                 {"G6_O6", false, false, 1 + 2 + 4},
                                 {"G7_O7", false, false, 1 + 4 + 6},
                                 {"G8_O8", false, false, 1 + 2 + 4 + 6},
                                 {"G6_O6", true, false, 1 + 2 + 4 + 4},
                                 {"G7_O7", true, false, 1 + 2 + 4 + 4 + 6},
                                 {"G8_O8", true, false, 1 + 2 + 4 + 4 + 6 + 6},
                                 {"G3_CD", false, true, 1},
                                 {"G8_O8", false, true, 1 + 2 + 4 + 6}};

INSTANTIATE_TEST_SUITE_P(Sets, HighDegreeStartCost, ::testing::ValuesIn(kStartCosts),
                         [](const ::testing::TestParamInfo<StartCost>& i) {
                           return std::string(i.param.set) +
                                  (i.param.vel_dependent ? "_VelocityDependent" : "") +
                                  (i.param.tolerances ? "_WithTolerances" : "");
                         });

INSTANTIATE_TEST_SUITE_P(Pendulums, HighDegreeStart, ::testing::ValuesIn(kCases),
                         [](const ::testing::TestParamInfo<Case>& i) { return i.param.name; });

}  // namespace
