// Generic vectors (design.md): the same run on NVECTOR_SERIAL and NVECTOR_OPENMP
// gives the same numbers.
#include <gtest/gtest.h>
#include <nvector/nvector_openmp.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "ceode_impl.hpp"
#include "test_util.hpp"

namespace {

using ceode_test::Context;
using ceode_test::DampedChain;
using ceode_test::DampedForced;
using ceode_test::LinearSolver;
using ceode_test::Matrix;
using ceode_test::Mem;
using ceode_test::Vector;

using VectorFactory = std::function<N_Vector(sunindextype, SUNContext)>;

N_Vector MakeSerial(sunindextype n, SUNContext ctx) { return N_VNew_Serial(n, ctx); }
// Two threads: the reductions (norms, dot products) really are split.
N_Vector MakeOpenMP(sunindextype n, SUNContext ctx) { return N_VNew_OpenMP(n, 2, ctx); }

struct Samples {
  int flag = CE_SUCCESS;
  std::vector<sunrealtype> values;
  long int nst = 0;
  long int nni = 0;
};

void Append(N_Vector x, N_Vector v, sunindextype n, std::vector<sunrealtype>* out) {
  const sunrealtype* xd = N_VGetArrayPointer(x);
  const sunrealtype* vd = N_VGetArrayPointer(v);
  out->insert(out->end(), xd, xd + n);
  out->insert(out->end(), vd, vd + n);
}

// A long spring chain (n = 64) on the explicit path or with its nonlinear
// dampers on the implicit path (Newton + dense, DQ Jacobian); outputs at
// arbitrary times exercise the interpolant as well.
Samples RunChain(const VectorFactory& make, const char* method, bool implicit) {
  Samples s;
  Context ctx;
  DampedChain prob;
  prob.n = implicit ? 16 : 64;
  prob.damped = implicit;
  const sunindextype n = prob.n;
  Vector x(make(n, ctx));
  Vector v(make(n, ctx));
  prob.Initial(x.get(), v.get());
  Mem mem(CEodeCreate(ctx));
  Matrix A;
  LinearSolver LS;
  auto ok = [&s](int flag) {
    if (flag < 0 && s.flag == CE_SUCCESS) s.flag = flag;
    return flag >= 0;
  };
  bool good = ok(CEodeInit(mem.get(), DampedChain::Rhs, 0, x.get(), v.get())) &&
              ok(CEodeSetUserData(mem.get(), &prob)) &&
              ok(CEodeSetMethodByName(mem.get(), method)) &&
              ok(CEodeSetFixedStep(mem.get(), SUN_RCONST(2e-3)));
  if (good && implicit) {
    A.reset(SUNDenseMatrix(n, n, ctx));
    LS.reset(SUNLinSol_Dense(x.get(), A.get(), ctx));
    good = ok(CEodeSetVelocityDependence(mem.get(), SUNTRUE)) &&
           ok(CEodeSetLinearSolver(mem.get(), LS.get(), A.get()));
  }
  // On the explicit G3 run the stability guard runs too: its power iteration
  // uses dot products, split across threads. Elsewhere it is off (its stability
  // sweep is slow under the sanitizers and is not the subject here).
  if (good) good = ok(CEodeSetErrFile(mem.get(), nullptr));
  if (good && (implicit || std::strcmp(method, "G3_CD") != 0)) {
    good = ok(CEodeSetStabilityGuard(mem.get(), CE_GUARD_OFF, 0));
  }
  // About 100 steps: OpenMP threads spin between parallel regions, which is slow
  // on a loaded machine, and more steps would prove nothing more.
  for (int k = 1; good && k <= 10; ++k) {
    sunrealtype t = 0;
    good = ok(CEodeEvolve(mem.get(), SUN_RCONST(0.0213) * k, x.get(), v.get(), &t, CE_NORMAL));
    Append(x.get(), v.get(), n, &s.values);
  }
  CEodeGetNumSteps(mem.get(), &s.nst);
  CEodeGetNumNonlinSolvIters(mem.get(), &s.nni);
  return s;
}

struct Comparison {
  sunrealtype max_rel = 0;
  bool bitwise = true;
};

Comparison Compare(const Samples& a, const Samples& b) {
  Comparison c;
  sunrealtype scale = 0;
  for (sunrealtype x : a.values) scale = std::max(scale, std::fabs(x));
  for (size_t i = 0; i < a.values.size() && i < b.values.size(); ++i) {
    c.max_rel = std::max(c.max_rel, std::fabs(a.values[i] - b.values[i]) / scale);
    if (std::memcmp(&a.values[i], &b.values[i], sizeof(sunrealtype)) != 0) c.bitwise = false;
  }
  return c;
}

struct Case {
  const char* method;
  bool implicit;
  const char* label;
};

// Printable parameter (gtest prints it in test listings).
void PrintTo(const Case& c, std::ostream* os) {
  *os << c.method << (c.implicit ? ", implicit (Newton, dense)" : ", explicit");
}

class SerialAndOpenMP : public ::testing::TestWithParam<Case> {};

TEST_P(SerialAndOpenMP, GiveTheSameNumbers) {
  const Case& c = GetParam();
  const Samples serial = RunChain(MakeSerial, c.method, c.implicit);
  const Samples openmp = RunChain(MakeOpenMP, c.method, c.implicit);
  ASSERT_EQ(serial.flag, CE_SUCCESS);
  ASSERT_EQ(openmp.flag, CE_SUCCESS);
  ASSERT_EQ(serial.values.size(), openmp.values.size());
  ASSERT_FALSE(serial.values.empty());
  EXPECT_EQ(serial.nst, openmp.nst);
  EXPECT_EQ(serial.nni, openmp.nni);
  const Comparison cmp = Compare(serial, openmp);
  std::printf("[ vectors  ] %-7s %-8s max relative difference = %.3e (%s)\n", c.method,
              c.implicit ? "implicit" : "explicit", cmp.max_rel,
              cmp.bitwise ? "bitwise identical" : "not bitwise identical");
  RecordProperty("bitwise", cmp.bitwise ? "yes" : "no");
  // Element-wise operations are exact on both; only reductions (norms in the
  // Newton convergence test) may round differently when split across threads.
  EXPECT_LE(cmp.max_rel, 1e-14);
}

INSTANTIATE_TEST_SUITE_P(
    Chain, SerialAndOpenMP,
    ::testing::Values(Case{"G3_CD", false, "G3CentralDifferencesExplicit"},
                      Case{"G4_A34", false, "G4AlphaThreeQuartersExplicit"},
                      Case{"G5", false, "G5Explicit"},
                      Case{"G4_A34", true, "G4AlphaThreeQuartersImplicitNewtonDense"},
                      Case{"G5", true, "G5ImplicitNewtonDense"}),
    [](const ::testing::TestParamInfo<Case>& info) { return std::string(info.param.label); });

// The scalar damped oscillator through generic operations only (no array access in f).
TEST(SerialAndOpenMP, GiveTheSameNumbersOnTheDampedForcedOscillatorWithFixedPoint) {
  auto run = [](const VectorFactory& make) {
    Samples s;
    Context ctx;
    DampedForced prob;
    Vector x(make(1, ctx));
    Vector v(make(1, ctx));
    N_VConst(prob.x0, x.get());
    N_VConst(prob.v0, v.get());
    Mem mem(CEodeCreate(ctx));
    EXPECT_EQ(CEodeInit(mem.get(), prob.Rhs(), 0, x.get(), v.get()), CE_SUCCESS);
    EXPECT_EQ(CEodeSetUserData(mem.get(), &prob), CE_SUCCESS);
    EXPECT_EQ(CEodeSetMethodByName(mem.get(), "G5"), CE_SUCCESS);
    EXPECT_EQ(CEodeSetFixedStep(mem.get(), SUN_RCONST(0.01)), CE_SUCCESS);
    EXPECT_EQ(CEodeSetVelocityDependence(mem.get(), SUNTRUE), CE_SUCCESS);
    EXPECT_EQ(CEodeSetErrFile(mem.get(), nullptr), CE_SUCCESS);
    EXPECT_EQ(CEodeSetStabilityGuard(mem.get(), CE_GUARD_OFF, 0), CE_SUCCESS);
    for (int k = 1; k <= 10; ++k) {
      sunrealtype t = 0;
      s.flag = CEodeEvolve(mem.get(), SUN_RCONST(0.077) * k, x.get(), v.get(), &t, CE_NORMAL);
      if (s.flag != CE_SUCCESS) break;
      Append(x.get(), v.get(), 1, &s.values);
    }
    return s;
  };
  const Samples serial = run(MakeSerial);
  const Samples openmp = run(MakeOpenMP);
  ASSERT_EQ(serial.flag, CE_SUCCESS);
  ASSERT_EQ(openmp.flag, CE_SUCCESS);
  const Comparison cmp = Compare(serial, openmp);
  std::printf("[ vectors  ] G5 scalar fixed point: max relative difference = %.3e (%s)\n",
              cmp.max_rel, cmp.bitwise ? "bitwise identical" : "not bitwise identical");
  EXPECT_LE(cmp.max_rel, 1e-14);
}

// The vectors a memory makes for itself (ceode::CloneVector): a serial template gives a serial
// vector in one allocation that any caller (SUNDIALS' solvers, the user's f) may clone, clone
// empty, fill and destroy as any NVECTOR_SERIAL vector; the sanitizer pass checks the frees.
TEST(MemoryVectors, AreSerialVectorsThatCloneAndDestroyAsAnyOther) {
  Context ctx;
  Vector tmpl(N_VNew_Serial(5, ctx));
  ASSERT_EQ(N_VEnableFusedOps_Serial(tmpl.get(), SUNTRUE), 0);
  N_VConst(1, tmpl.get());
  N_Vector v = ceode::CloneVector(tmpl.get());
  ASSERT_NE(v, nullptr);
  EXPECT_EQ(N_VGetVectorID(v), SUNDIALS_NVEC_SERIAL);
  EXPECT_EQ(N_VGetLength(v), 5);
  EXPECT_NE(N_VGetArrayPointer(v), N_VGetArrayPointer(tmpl.get()));
  EXPECT_EQ(v->ops->nvlinearcombination, tmpl.get()->ops->nvlinearcombination);
  EXPECT_EQ(v->sunctx, tmpl.get()->sunctx);
  for (int i = 0; i < 5; ++i) N_VGetArrayPointer(v)[i] = i;
  N_VLinearSum(1, tmpl.get(), 2, v, v);
  EXPECT_EQ(N_VGetArrayPointer(v)[4], 9);
  N_Vector w = N_VClone(v);
  ASSERT_NE(w, nullptr);
  EXPECT_EQ(N_VGetLength(w), 5);
  EXPECT_NE(N_VGetArrayPointer(w), N_VGetArrayPointer(v));
  N_VScale(2, v, w);
  EXPECT_EQ(N_VGetArrayPointer(w)[4], 18);
  N_Vector e = N_VCloneEmpty(w);
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(N_VGetArrayPointer(e), nullptr);
  sunrealtype buf[5] = {};
  N_VSetArrayPointer(buf, e);
  N_VConst(3, e);
  EXPECT_EQ(buf[2], 3);
  N_VDestroy(e);
  N_VDestroy(w);
  N_VDestroy(v);
  Vector empty(N_VNew_Serial(0, ctx));
  N_Vector z = ceode::CloneVector(empty.get());
  ASSERT_NE(z, nullptr);
  EXPECT_EQ(N_VGetLength(z), 0);
  N_VDestroy(z);
}

// Vectors of other types are N_VClone's own.
TEST(MemoryVectors, OfOtherTypesAreTheTypesOwnClones) {
  Context ctx;
  Vector tmpl(MakeOpenMP(4, ctx));
  N_Vector v = ceode::CloneVector(tmpl.get());
  ASSERT_NE(v, nullptr);
  EXPECT_EQ(N_VGetVectorID(v), SUNDIALS_NVEC_OPENMP);
  EXPECT_EQ(v->ops->nvclone, tmpl.get()->ops->nvclone);
  EXPECT_EQ(v->ops->nvdestroy, tmpl.get()->ops->nvdestroy);
  N_VDestroy(v);
}

}  // namespace
