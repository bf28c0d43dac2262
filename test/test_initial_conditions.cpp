// Consistent initial conditions of a constrained problem: the first start's check of x0 against
// Phi(x, t0) = 0 and of v0 against G v = -Phi_t (CE_INCONSISTENT_IC and its message), and
// CEodeCalcIC's projection (docs/theory.md section 8.5).
//
// Problems: the Cartesian pendulum x = (p, q), M = I, f = (0, -g), Phi = p^2 + q^2 - L^2, whose
// minimum-norm projections are known in closed form (x radially onto the circle, v onto its
// tangent); a driven slider Phi = x_0 - A sin(w t) for the time derivative of Phi.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "test_util.hpp"

namespace {

using ceode_test::Contains;
using ceode_test::Context;
using ceode_test::Mem;
using ceode_test::SerialVector;
using ceode_test::Vector;

constexpr double kG = 9.81;
constexpr double kUround = 2.220446049250313e-16;

int PendulumRhs(sunrealtype, N_Vector, N_Vector, N_Vector f, void*) {
  N_VGetArrayPointer(f)[0] = 0;
  N_VGetArrayPointer(f)[1] = -kG;
  return 0;
}

// bias shifts the circle's Phi by a constant: bias < -L^2 leaves no real solution.
struct Circle {
  double bias = -1;  // Phi = p^2 + q^2 + bias, L = 1
};

int CirclePhi(sunrealtype, N_Vector x, N_Vector phi, void* ud) {
  const double* xd = N_VGetArrayPointer(x);
  N_VGetArrayPointer(phi)[0] = xd[0] * xd[0] + xd[1] * xd[1] + static_cast<Circle*>(ud)->bias;
  return 0;
}

int CircleJac(sunrealtype, N_Vector x, SUNMatrix G, void*) {
  const double* xd = N_VGetArrayPointer(x);
  SUNDenseMatrix_Column(G, 0)[0] = 2 * xd[0];
  SUNDenseMatrix_Column(G, 1)[0] = 2 * xd[1];
  return 0;
}

// A pendulum memory at (p, q), (vp, vq), G5_ONES at h = 1e-3, messages kept (not printed).
struct PendulumStart {
  Context ctx;
  Circle circle;
  Vector x, v, tmpl;
  Mem mem;
  PendulumStart(double p, double q, double vp, double vq)
      : x(SerialVector(2, ctx)),
        v(SerialVector(2, ctx)),
        tmpl(SerialVector(1, ctx)),
        mem(CEodeCreate(ctx)) {
    double* xd = N_VGetArrayPointer(x.get());
    double* vd = N_VGetArrayPointer(v.get());
    xd[0] = p;
    xd[1] = q;
    vd[0] = vp;
    vd[1] = vq;
    CEodeSetErrFile(mem.get(), nullptr);
    EXPECT_EQ(CEodeInit(mem.get(), PendulumRhs, 0, x.get(), v.get()), CE_SUCCESS);
    EXPECT_EQ(CEodeSetUserData(mem.get(), &circle), CE_SUCCESS);
    EXPECT_EQ(CEodeSetMethodByName(mem.get(), "G5_ONES"), CE_SUCCESS);
    EXPECT_EQ(CEodeSetFixedStep(mem.get(), 1e-3), CE_SUCCESS);
    EXPECT_EQ(CEodeSetConstraints(mem.get(), tmpl.get(), CirclePhi, CircleJac), CE_SUCCESS);
  }
  int Evolve(double tout) {
    sunrealtype t = 0;
    return CEodeEvolve(mem.get(), tout, x.get(), v.get(), &t, CE_NORMAL);
  }
  std::string Message() const {
    const char* msg = nullptr;
    CEodeGetLastErrorMessage(mem.get(), &msg);
    return msg != nullptr ? msg : "";
  }
};

TEST(InitialConsistency, AnOffConstraintPositionIsRefusedNamingTheConstraintTheDistanceAndCalcIC) {
  PendulumStart s(1.1, 0, 0, 0);  // Phi_0 = 0.21, |G_0| = 2.2
  EXPECT_EQ(s.Evolve(0.01), CE_INCONSISTENT_IC);
  const std::string msg = s.Message();
  EXPECT_TRUE(Contains(msg, "x0 is off the position constraints")) << msg;
  EXPECT_TRUE(Contains(msg, "Phi_0(x0, t0) = 0.21 puts it 0.0955 from the constraint surface"))
      << msg;
  EXPECT_TRUE(Contains(msg, "CEodeCalcIC(mem, CE_IC_POSITION | CE_IC_VELOCITY)")) << msg;
  EXPECT_FALSE(Contains(msg, "velocity constraint")) << msg;  // v0 = 0 satisfies G v = 0
  EXPECT_FALSE(Contains(msg, "reduce h")) << msg;
  long int nst = -1;
  CEodeGetNumSteps(s.mem.get(), &nst);
  EXPECT_EQ(nst, 0);
  EXPECT_EQ(N_VGetArrayPointer(s.x.get())[0], 1.1);  // the outputs are left alone
  EXPECT_EQ(s.Evolve(0.01), CE_INCONSISTENT_IC);     // and stays refused until projected
}

TEST(InitialConsistency, AVelocityAcrossTheConstraintIsRefusedNamingTheVelocityConstraint) {
  const double th = 0.3;
  PendulumStart s(std::sin(th), -std::cos(th), 1, 0.5);  // on the circle, v not tangent
  EXPECT_EQ(s.Evolve(0.01), CE_INCONSISTENT_IC);
  const std::string msg = s.Message();
  EXPECT_TRUE(Contains(msg, "v0 violates the velocity constraint G v = -Phi_t: component 0"))
      << msg;
  // G v = 2 (p vp + q vq), |G| = 2: the velocity across the circle is p vp + q vq
  char across[32];
  std::snprintf(across, sizeof(across), "a velocity of %.3g",
                std::fabs(std::sin(th) - 0.5 * std::cos(th)));
  EXPECT_TRUE(Contains(msg, across)) << msg;
  EXPECT_TRUE(Contains(msg, "CEodeCalcIC(mem, CE_IC_VELOCITY)")) << msg;
  EXPECT_FALSE(Contains(msg, "position constraints")) << msg;
}

TEST(InitialConsistency, APositionAndAVelocityBothOffAreNamedInOneMessage) {
  PendulumStart s(1.1, -0.2, 0.3, 0.5);
  EXPECT_EQ(s.Evolve(0.01), CE_INCONSISTENT_IC);
  const std::string msg = s.Message();
  EXPECT_TRUE(Contains(msg, "x0 is off the position constraints")) << msg;
  EXPECT_TRUE(Contains(msg, "v0 violates the velocity constraint")) << msg;
  EXPECT_TRUE(Contains(msg, "CEodeCalcIC(mem, CE_IC_POSITION | CE_IC_VELOCITY)")) << msg;
  // after CEodeReInit at a consistent state the check passes and the run starts
  Vector x = SerialVector(2, s.ctx), v = SerialVector(2, s.ctx);
  N_VGetArrayPointer(x.get())[1] = -1;
  N_VGetArrayPointer(v.get())[0] = 0.5;  // tangent at the bottom
  ASSERT_EQ(CEodeReInit(s.mem.get(), 0, x.get(), v.get()), CE_SUCCESS);
  EXPECT_EQ(s.Evolve(0.01), CE_SUCCESS) << s.Message();
}

// The threshold is sqrt(uround) |x0|_max = 1.49e-8 here: an offset of 1e-10 (round-off of data
// computed in double precision is 1e-16) starts, one of 1e-7 is refused.
TEST(InitialConsistency, AcceptsOffsetsBelowSqrtUroundAndRefusesThoseAbove) {
  PendulumStart near(1 + 1e-10, 0, 0, 0);
  EXPECT_EQ(near.Evolve(0.01), CE_SUCCESS) << near.Message();
  PendulumStart off(1 + 1e-7, 0, 0, 0);
  EXPECT_EQ(off.Evolve(0.01), CE_INCONSISTENT_IC);
  PendulumStart rounded(std::sin(0.7), -std::cos(0.7), std::cos(0.7), std::sin(0.7));
  EXPECT_EQ(rounded.Evolve(0.01), CE_SUCCESS) << rounded.Message();
}

// The closed form: x* = x0 / |x0| (Gauss-Newton's minimum-norm corrections stay on the ray),
// v* = v0 - (v0 . n) n with n = x*; both to a few ulps.
TEST(CalcIC, MovesAnOffConstraintPendulumStartOntoPhiAndGvAndReportsTheMove) {
  const double p0 = 1.1, q0 = -0.2, vp0 = 0.3, vq0 = 0.5;
  PendulumStart s(p0, q0, vp0, vq0);
  ASSERT_EQ(CEodeCalcIC(s.mem.get(), CE_IC_POSITION | CE_IC_VELOCITY), CE_SUCCESS) << s.Message();
  Vector x = SerialVector(2, s.ctx), v = SerialVector(2, s.ctx);
  ASSERT_EQ(CEodeGetConsistentIC(s.mem.get(), x.get(), v.get()), CE_SUCCESS);
  const double* xd = N_VGetArrayPointer(x.get());
  const double* vd = N_VGetArrayPointer(v.get());
  const double phi = xd[0] * xd[0] + xd[1] * xd[1] - 1;
  const double gv = 2 * (xd[0] * vd[0] + xd[1] * vd[1]);
  std::printf("[ calcic   ] Phi %.2e, G v %.2e\n", phi, gv);
  EXPECT_LE(std::fabs(phi), 4 * kUround);
  EXPECT_LE(std::fabs(gv), 4 * kUround);
  const double r = std::hypot(p0, q0), np = p0 / r, nq = q0 / r;
  EXPECT_NEAR(xd[0], np, 2 * kUround);
  EXPECT_NEAR(xd[1], nq, 2 * kUround);
  const double vn = vp0 * np + vq0 * nq;
  EXPECT_NEAR(vd[0], vp0 - vn * np, 4 * kUround);
  EXPECT_NEAR(vd[1], vq0 - vn * nq, 4 * kUround);
  sunrealtype dx = 0, dv = 0;
  ASSERT_EQ(CEodeGetICCorrection(s.mem.get(), &dx, &dv), CE_SUCCESS);
  std::printf("[ calcic   ] moved x by %.6g, v by %.6g\n", dx, dv);
  EXPECT_NEAR(dx, std::max(std::fabs(p0 - np), std::fabs(q0 - nq)), 4 * kUround);
  EXPECT_NEAR(dv, std::fabs(vn) * std::max(std::fabs(np), std::fabs(nq)), 4 * kUround);
  // The projected start integrates; the position constraint stays at round-off.
  ASSERT_EQ(s.Evolve(1), CE_SUCCESS) << s.Message();
  const double* xe = N_VGetArrayPointer(s.x.get());
  EXPECT_LE(std::fabs(xe[0] * xe[0] + xe[1] * xe[1] - 1), 1e-14);
}

TEST(CalcIC, ProjectsOnlyWhatItIsAskedAndTheCheckStillSeesTheRest) {
  PendulumStart s(1.1, -0.2, 0.3, 0.5);
  ASSERT_EQ(CEodeCalcIC(s.mem.get(), CE_IC_POSITION), CE_SUCCESS);
  sunrealtype dx = 0, dv = -1;
  CEodeGetICCorrection(s.mem.get(), &dx, &dv);
  EXPECT_GT(dx, 0.05);
  EXPECT_EQ(dv, 0);
  EXPECT_EQ(s.Evolve(0.01), CE_INCONSISTENT_IC);
  EXPECT_TRUE(Contains(s.Message(), "velocity constraint")) << s.Message();
  EXPECT_FALSE(Contains(s.Message(), "position constraints")) << s.Message();
  ASSERT_EQ(CEodeCalcIC(s.mem.get(), CE_IC_VELOCITY), CE_SUCCESS);
  EXPECT_EQ(s.Evolve(0.01), CE_SUCCESS) << s.Message();
}

TEST(CalcIC, AProjectionWithoutASolutionFailsAndLeavesTheStateAsItWas) {
  PendulumStart s(1.1, -0.2, 0.3, 0.5);
  s.circle.bias = 1;  // p^2 + q^2 + 1 = 0 has no real solution
  EXPECT_EQ(CEodeCalcIC(s.mem.get(), CE_IC_POSITION | CE_IC_VELOCITY), CE_CONV_FAILURE);
  EXPECT_TRUE(Contains(s.Message(), "did not converge")) << s.Message();
  Vector x = SerialVector(2, s.ctx), v = SerialVector(2, s.ctx);
  ASSERT_EQ(CEodeGetConsistentIC(s.mem.get(), x.get(), v.get()), CE_SUCCESS);
  EXPECT_EQ(N_VGetArrayPointer(x.get())[0], 1.1);
  EXPECT_EQ(N_VGetArrayPointer(x.get())[1], -0.2);
  EXPECT_EQ(N_VGetArrayPointer(v.get())[1], 0.5);
  s.circle.bias = -1;  // the memory stays usable
  EXPECT_EQ(CEodeCalcIC(s.mem.get(), CE_IC_POSITION | CE_IC_VELOCITY), CE_SUCCESS);
  EXPECT_EQ(s.Evolve(0.01), CE_SUCCESS) << s.Message();
}

TEST(CalcIC, RefusesBadArgumentsWithAClearMessage) {
  PendulumStart s(1.1, -0.2, 0.3, 0.5);
  for (int what : {0, 4, -1}) {
    EXPECT_EQ(CEodeCalcIC(s.mem.get(), what), CE_ILL_INPUT);
    EXPECT_TRUE(Contains(s.Message(), "CE_IC_POSITION, CE_IC_VELOCITY or both")) << s.Message();
  }
  EXPECT_EQ(CEodeCalcIC(nullptr, CE_IC_POSITION), CE_MEM_NULL);
  EXPECT_EQ(CEodeGetICCorrection(s.mem.get(), nullptr, nullptr), CE_ILL_INPUT);
  EXPECT_EQ(CEodeGetConsistentIC(s.mem.get(), nullptr, s.v.get()), CE_ILL_INPUT);
  ASSERT_EQ(CEodeSetConstraints(s.mem.get(), nullptr, nullptr, nullptr), CE_SUCCESS);
  EXPECT_EQ(CEodeCalcIC(s.mem.get(), CE_IC_POSITION), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(s.Message(), "No constraints are set")) << s.Message();
  Context ctx;
  Mem fresh(CEodeCreate(ctx));
  CEodeSetErrFile(fresh.get(), nullptr);
  EXPECT_EQ(CEodeCalcIC(fresh.get(), CE_IC_POSITION), CE_NO_MALLOC);
}

// A driven slider: x_0 = A sin(w t), x_1 free (x_1'' = -x_1). At t0 = 0 the constraint asks for
// x_0' = A w: a start at rest is refused, CEodeCalcIC gives the driving speed (Phi_t by fourth-
// order differences: error of order (w s)^4 + eps / s, s = eps^(1/5) 100 h).
constexpr double kAmp = 0.2, kOmega = 3;

int SliderRhs(sunrealtype, N_Vector x, N_Vector, N_Vector f, void*) {
  N_VGetArrayPointer(f)[0] = 0;
  N_VGetArrayPointer(f)[1] = -N_VGetArrayPointer(x)[1];
  return 0;
}
int SliderPhi(sunrealtype t, N_Vector x, N_Vector phi, void*) {
  N_VGetArrayPointer(phi)[0] = N_VGetArrayPointer(x)[0] - kAmp * std::sin(kOmega * t);
  return 0;
}
int SliderJac(sunrealtype, N_Vector, SUNMatrix G, void*) {
  SUNDenseMatrix_Column(G, 0)[0] = 1;
  return 0;
}

TEST(CalcIC, GivesADrivenConstraintItsDrivingSpeed) {
  Context ctx;
  Vector x = SerialVector(2, ctx), v = SerialVector(2, ctx), tmpl = SerialVector(1, ctx);
  N_VGetArrayPointer(x.get())[1] = 1;
  Mem mem(CEodeCreate(ctx));
  CEodeSetErrFile(mem.get(), nullptr);
  ASSERT_EQ(CEodeInit(mem.get(), SliderRhs, 0, x.get(), v.get()), CE_SUCCESS);
  ASSERT_EQ(CEodeSetFixedStep(mem.get(), 1e-3), CE_SUCCESS);
  ASSERT_EQ(CEodeSetConstraints(mem.get(), tmpl.get(), SliderPhi, SliderJac), CE_SUCCESS);
  sunrealtype t = 0;
  EXPECT_EQ(CEodeEvolve(mem.get(), 0.01, x.get(), v.get(), &t, CE_NORMAL), CE_INCONSISTENT_IC);
  ASSERT_EQ(CEodeCalcIC(mem.get(), CE_IC_VELOCITY), CE_SUCCESS);
  Vector xc = SerialVector(2, ctx), vc = SerialVector(2, ctx);
  ASSERT_EQ(CEodeGetConsistentIC(mem.get(), xc.get(), vc.get()), CE_SUCCESS);
  std::printf("[ calcic   ] driving speed %.17g (exact %.17g)\n", N_VGetArrayPointer(vc.get())[0],
              kAmp * kOmega);
  EXPECT_NEAR(N_VGetArrayPointer(vc.get())[0], kAmp * kOmega, 1e-11);
  EXPECT_EQ(N_VGetArrayPointer(vc.get())[1], 0);  // the free coordinate is not moved
  ASSERT_EQ(CEodeEvolve(mem.get(), 1, x.get(), v.get(), &t, CE_NORMAL), CE_SUCCESS);
  EXPECT_NEAR(N_VGetArrayPointer(x.get())[0], kAmp * std::sin(kOmega * 1.0), 1e-13);
}

}  // namespace
