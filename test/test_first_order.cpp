// The first-order adapter (CEodeInitFirstOrder / CEodeEvolveFirstOrder): an
// unchanged ARKODE-style F(t, y, ydot) with y = [x; v] must give the numbers of the
// native second-order form f(t, x, v) = a, on a ManyVector and on a serial 2n, and
// refuse what it cannot do with a flag and a message.
#include <nvector/nvector_manyvector.h>
#include <nvector/nvector_openmp.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <string>
#include <vector>

#include "test_util.hpp"

namespace {

using namespace ceode_test;  // the handles and helpers of test_util.hpp

// A damped chain of N unit masses between fixed walls:
//   x_i'' = k (x_{i-1} - 2 x_i + x_{i+1}) - c v_i.
struct Chain {
  sunindextype n = 12;
  sunrealtype k = 40;
  sunrealtype c = 0;
  sunrealtype xdot_scale = 1;  // != 1: a first half that is not v (bad input)
  long int calls = 0;
};

void Accel(const Chain& p, const sunrealtype* x, const sunrealtype* v, sunrealtype* a) {
  for (sunindextype i = 0; i < p.n; ++i) {
    const sunrealtype left = i > 0 ? x[i - 1] : 0;
    const sunrealtype right = i + 1 < p.n ? x[i + 1] : 0;
    a[i] = p.k * (left - 2 * x[i] + right) - p.c * v[i];
  }
}

int Native(sunrealtype /*t*/, N_Vector x, N_Vector v, N_Vector a, void* data) {
  Accel(*static_cast<Chain*>(data), N_VGetArrayPointer(x), N_VGetArrayPointer(v),
        N_VGetArrayPointer(a));
  return 0;
}

// ARKODE style on a ManyVector [x; v].
int FirstOrderMany(sunrealtype /*t*/, N_Vector y, N_Vector ydot, void* data) {
  auto* p = static_cast<Chain*>(data);
  ++p->calls;
  N_Vector x = N_VGetSubvector_ManyVector(y, 0);
  N_Vector v = N_VGetSubvector_ManyVector(y, 1);
  N_VScale(p->xdot_scale, v, N_VGetSubvector_ManyVector(ydot, 0));
  Accel(*p, N_VGetArrayPointer(x), N_VGetArrayPointer(v),
        N_VGetArrayPointer(N_VGetSubvector_ManyVector(ydot, 1)));
  return 0;
}

// ARKODE style on a serial vector of length 2n.
int FirstOrderSerial(sunrealtype /*t*/, N_Vector y, N_Vector ydot, void* data) {
  auto* p = static_cast<Chain*>(data);
  ++p->calls;
  const sunrealtype* yd = N_VGetArrayPointer(y);
  sunrealtype* dd = N_VGetArrayPointer(ydot);
  for (sunindextype i = 0; i < p->n; ++i) dd[i] = p->xdot_scale * yd[p->n + i];
  Accel(*p, yd, yd + p->n, dd + p->n);
  return 0;
}

void Initial(const Chain& p, sunrealtype* x, sunrealtype* v) {
  for (sunindextype i = 0; i < p.n; ++i) {
    x[i] = std::sin(SUN_RCONST(0.3) * static_cast<sunrealtype>(i + 1));
    v[i] = i == 0 ? SUN_RCONST(0.5) : 0;
  }
}

enum class Form { kNative, kManyVector, kSerial };

struct Case {
  const char* method;
  bool damped;            // velocity-dependent: Newton with a dense linear solver
  bool adaptive = false;  // tolerances instead of the fixed step
};

struct Outcome {
  int flag = CE_SUCCESS;
  std::vector<sunrealtype> samples;  // x then v at every output
  long int nst = 0;
  long int nfe = 0;
};

// The run of one form; every failure ends it with its flag.
class Runner {
 public:
  Runner(Form form, const Case& c) : form_(form), case_(c) {
    prob_.c = c.damped ? SUN_RCONST(0.8) : 0;
    const sunindextype n = prob_.n;
    x_ = SerialVector(n, ctx_);
    v_ = SerialVector(n, ctx_);
    Initial(prob_, N_VGetArrayPointer(x_.get()), N_VGetArrayPointer(v_.get()));
    if (form == Form::kManyVector) {
      N_Vector parts[2] = {x_.get(), v_.get()};
      y_.reset(N_VNew_ManyVector(2, parts, ctx_));
    } else if (form == Form::kSerial) {
      y_ = SerialVector(2 * n, ctx_);
      Initial(prob_, N_VGetArrayPointer(y_.get()), N_VGetArrayPointer(y_.get()) + n);
    }
    mem_.reset(CEodeCreate(ctx_));
  }

  Outcome Go() {
    Outcome r;
    auto ok = [&r](int flag) {
      if (flag < 0 && r.flag == CE_SUCCESS) r.flag = flag;
      return flag >= 0;
    };
    bool good = ok(Init()) && ok(CEodeSetUserData(mem_.get(), &prob_)) &&
                ok(CEodeSetMethodByName(mem_.get(), case_.method)) &&
                ok(case_.adaptive ? CEodeSStolerances(mem_.get(), 1e-8, 1e-8)
                                  : CEodeSetFixedStep(mem_.get(), SUN_RCONST(0.01))) &&
                ok(CEodeSetStabilityGuard(mem_.get(), CE_GUARD_OFF, 0));
    if (good && case_.damped) {
      A_.reset(SUNDenseMatrix(prob_.n, prob_.n, ctx_));
      LS_.reset(SUNLinSol_Dense(x_.get(), A_.get(), ctx_));
      good = ok(CEodeSetVelocityDependence(mem_.get(), SUNTRUE)) &&
             ok(CEodeSetLinearSolver(mem_.get(), LS_.get(), A_.get()));
    }
    for (int k = 1; good && k <= 10; ++k) {
      sunrealtype t = 0;
      good = ok(Evolve(SUN_RCONST(0.25) * k, &t));
      Record(&r);
    }
    CEodeGetNumSteps(mem_.get(), &r.nst);
    CEodeGetNumRhsEvals(mem_.get(), &r.nfe);
    return r;
  }

  void* mem() { return mem_.get(); }
  N_Vector y() { return y_.get(); }
  Chain& prob() { return prob_; }
  SUNContext ctx() { return ctx_; }

  int Init() {
    switch (form_) {
      case Form::kNative:
        return CEodeInit(mem_.get(), Native, 0, x_.get(), v_.get());
      case Form::kManyVector:
        return CEodeInitFirstOrder(mem_.get(), FirstOrderMany, 0, y_.get());
      case Form::kSerial:
        return CEodeInitFirstOrder(mem_.get(), FirstOrderSerial, 0, y_.get());
    }
    return CE_ILL_INPUT;
  }

 private:
  int Evolve(sunrealtype tout, sunrealtype* t) {
    if (form_ == Form::kNative) {
      return CEodeEvolve(mem_.get(), tout, x_.get(), v_.get(), t, CE_NORMAL);
    }
    return CEodeEvolveFirstOrder(mem_.get(), tout, y_.get(), t, CE_NORMAL);
  }
  void Record(Outcome* r) {
    const sunindextype n = prob_.n;
    const sunrealtype* x = N_VGetArrayPointer(x_.get());
    const sunrealtype* v = N_VGetArrayPointer(v_.get());
    if (form_ == Form::kSerial) {
      x = N_VGetArrayPointer(y_.get());
      v = x + n;
    }
    r->samples.insert(r->samples.end(), x, x + n);
    r->samples.insert(r->samples.end(), v, v + n);
  }

  Form form_;
  Case case_;
  Context ctx_;
  Chain prob_;
  Vector x_;
  Vector v_;
  Vector y_;
  Mem mem_;
  Matrix A_;
  LinearSolver LS_;
};

class FirstOrderAdapter : public ::testing::TestWithParam<std::tuple<Case, Form>> {};

TEST_P(FirstOrderAdapter, GivesTheNumbersAndCountersOfTheNativeForm) {
  const Case c = std::get<0>(GetParam());
  const Outcome native = Runner(Form::kNative, c).Go();
  const Outcome adapted = Runner(std::get<1>(GetParam()), c).Go();
  ASSERT_EQ(native.flag, CE_SUCCESS) << ceode_test::FlagName(native.flag);
  ASSERT_EQ(adapted.flag, CE_SUCCESS) << ceode_test::FlagName(adapted.flag);
  ASSERT_EQ(native.samples.size(), adapted.samples.size());
  sunrealtype diff = 0;
  for (size_t i = 0; i < native.samples.size(); ++i) {
    diff = std::max(diff, std::fabs(native.samples[i] - adapted.samples[i]));
  }
  // Both forms evaluate the same acceleration formula on the same states.
  EXPECT_LE(diff, SUN_RCONST(1e-14));
  EXPECT_EQ(native.nst, adapted.nst);
  EXPECT_EQ(native.nfe, adapted.nfe);
}

std::string CaseName(const ::testing::TestParamInfo<std::tuple<Case, Form>>& info) {
  const Case c = std::get<0>(info.param);
  const Form f = std::get<1>(info.param);
  return std::string(c.method) + (c.damped ? "_DampedNewton" : "_Undamped") +
         (c.adaptive ? "_Tolerances" : "") + (f == Form::kManyVector ? "_ManyVector" : "_Serial2n");
}

INSTANTIATE_TEST_SUITE_P(
    SpringChain, FirstOrderAdapter,
    ::testing::Combine(::testing::Values(Case{"G3_CD", false}, Case{"G4_A34", false},
                                         Case{"G4_A34", true}, Case{"G5", true},
                                         Case{"G6_O5", false, true}, Case{"G4_A34", true, true}),
                       ::testing::Values(Form::kManyVector, Form::kSerial)),
    CaseName);

std::string LastMessage(void* mem) {
  const char* msg = nullptr;
  CEodeGetLastErrorMessage(mem, &msg);
  return msg != nullptr ? msg : "";
}

TEST(FirstOrderAdapterInput, RefusesAFirstHalfThatIsNotTheVelocity) {
  for (Form form : {Form::kManyVector, Form::kSerial}) {
    Runner run(form, Case{"G4_A34", false});
    run.prob().xdot_scale = 2;  // x' = 2 v: a generalised velocity
    CEodeSetErrFile(run.mem(), nullptr);
    const Outcome r = run.Go();
    EXPECT_EQ(r.flag, CE_ILL_INPUT);
    EXPECT_NE(LastMessage(run.mem()).find("not v"), std::string::npos) << LastMessage(run.mem());
    EXPECT_NE(LastMessage(run.mem()).find("native form"), std::string::npos);
    EXPECT_EQ(r.nst, 0);
  }
}

TEST(FirstOrderAdapterInput, RefusesAGeneralisedVelocityEvenWhenStartingAtRest) {
  Runner run(Form::kSerial, Case{"G4_A34", false});
  N_VConst(0, run.y());
  run.prob().xdot_scale = 2;
  CEodeSetErrFile(run.mem(), nullptr);
  EXPECT_EQ(run.Go().flag, CE_ILL_INPUT);
  EXPECT_NE(LastMessage(run.mem()).find("not v"), std::string::npos) << LastMessage(run.mem());
}

TEST(FirstOrderAdapterInput, RefusesBadlyShapedVectorsWithAMessage) {
  Context ctx;
  Mem mem(CEodeCreate(ctx));
  CEodeSetErrFile(mem.get(), nullptr);
  Vector a = SerialVector(3, ctx, 1);
  Vector b = SerialVector(4, ctx, 1);
  Vector c = SerialVector(3, ctx, 1);
  N_Vector three[3] = {a.get(), c.get(), c.get()};
  Vector mv3(N_VNew_ManyVector(3, three, ctx));
  EXPECT_EQ(CEodeInitFirstOrder(mem.get(), FirstOrderMany, 0, mv3.get()), CE_ILL_INPUT);
  EXPECT_NE(LastMessage(mem.get()).find("3 parts"), std::string::npos) << LastMessage(mem.get());
  N_Vector unequal[2] = {a.get(), b.get()};
  Vector mv2(N_VNew_ManyVector(2, unequal, ctx));
  EXPECT_EQ(CEodeInitFirstOrder(mem.get(), FirstOrderMany, 0, mv2.get()), CE_ILL_INPUT);
  EXPECT_NE(LastMessage(mem.get()).find("lengths 3 and 4"), std::string::npos);
  EXPECT_EQ(CEodeInitFirstOrder(mem.get(), FirstOrderSerial, 0, a.get()), CE_ILL_INPUT);
  EXPECT_NE(LastMessage(mem.get()).find("even"), std::string::npos) << LastMessage(mem.get());
  Vector omp(N_VNew_OpenMP(4, 1, ctx));
  N_VConst(0, omp.get());
  EXPECT_EQ(CEodeInitFirstOrder(mem.get(), FirstOrderSerial, 0, omp.get()), CE_ILL_INPUT);
  EXPECT_NE(LastMessage(mem.get()).find("NVECTOR_MANYVECTOR"), std::string::npos);
  EXPECT_EQ(CEodeInitFirstOrder(mem.get(), FirstOrderSerial, 0, nullptr), CE_ILL_INPUT);
  EXPECT_EQ(CEodeInitFirstOrder(mem.get(), nullptr, 0, b.get()), CE_ILL_INPUT);
  EXPECT_EQ(CEodeInitFirstOrder(nullptr, FirstOrderSerial, 0, b.get()), CE_MEM_NULL);
  // A good init, then an output vector of another shape.
  ASSERT_EQ(CEodeInitFirstOrder(mem.get(), FirstOrderSerial, 0, b.get()), CE_SUCCESS);
  Vector wrong = SerialVector(6, ctx);
  sunrealtype t = 0;
  EXPECT_EQ(CEodeEvolveFirstOrder(mem.get(), 1, wrong.get(), &t, CE_NORMAL), CE_ILL_INPUT);
  EXPECT_NE(LastMessage(mem.get()).find("not shaped like y0"), std::string::npos);
  EXPECT_EQ(CEodeReInitFirstOrder(mem.get(), 0, mv2.get()), CE_ILL_INPUT);
}

TEST(FirstOrderAdapterInput, EvolveAndReInitNeedAFirstOrderInit) {
  Context ctx;
  Chain prob;
  Vector x = SerialVector(prob.n, ctx);
  Vector v = SerialVector(prob.n, ctx);
  Vector y = SerialVector(2 * prob.n, ctx);
  Mem mem(CEodeCreate(ctx));
  CEodeSetErrFile(mem.get(), nullptr);
  sunrealtype t = 0;
  EXPECT_EQ(CEodeEvolveFirstOrder(mem.get(), 1, y.get(), &t, CE_NORMAL), CE_NO_MALLOC);
  ASSERT_EQ(CEodeInit(mem.get(), Native, 0, x.get(), v.get()), CE_SUCCESS);
  EXPECT_EQ(CEodeEvolveFirstOrder(mem.get(), 1, y.get(), &t, CE_NORMAL), CE_NO_MALLOC);
  EXPECT_NE(LastMessage(mem.get()).find("CEodeInitFirstOrder"), std::string::npos);
  EXPECT_EQ(CEodeReInitFirstOrder(mem.get(), 0, y.get()), CE_NO_MALLOC);
}

TEST(FirstOrderAdapterInput, UserDataReachesFAndANativeInitRestoresIt) {
  Runner run(Form::kSerial, Case{"G4_A34", false});
  ASSERT_EQ(run.Go().flag, CE_SUCCESS);
  EXPECT_GT(run.prob().calls, 0);  // CEodeSetUserData after the init reached F
  Chain other;
  Vector x = SerialVector(other.n, run.ctx());
  Vector v = SerialVector(other.n, run.ctx());
  Initial(other, N_VGetArrayPointer(x.get()), N_VGetArrayPointer(v.get()));
  ASSERT_EQ(CEodeInit(run.mem(), Native, 0, x.get(), v.get()), CE_SUCCESS);
  sunrealtype t = 0;
  // The native f gets the user's pointer again, not the adapter's.
  EXPECT_EQ(CEodeEvolve(run.mem(), 0.5, x.get(), v.get(), &t, CE_NORMAL), CE_SUCCESS);
  EXPECT_TRUE(std::isfinite(NV_Ith_S(x.get(), 0)));
}

TEST(FirstOrderAdapterInput, ReInitRepeatsTheRunExactly) {
  Runner run(Form::kManyVector, Case{"G4_A34", true});
  const Outcome first = run.Go();
  ASSERT_EQ(first.flag, CE_SUCCESS);
  Chain& p = run.prob();
  N_Vector x = N_VGetSubvector_ManyVector(run.y(), 0);
  N_Vector v = N_VGetSubvector_ManyVector(run.y(), 1);
  Initial(p, N_VGetArrayPointer(x), N_VGetArrayPointer(v));
  ASSERT_EQ(CEodeReInitFirstOrder(run.mem(), 0, run.y()), CE_SUCCESS);
  sunrealtype t = 0;
  for (int k = 1; k <= 10; ++k) {
    ASSERT_EQ(CEodeEvolveFirstOrder(run.mem(), SUN_RCONST(0.25) * k, run.y(), &t, CE_NORMAL),
              CE_SUCCESS);
  }
  const size_t n = static_cast<size_t>(p.n);
  const size_t last = first.samples.size() - 2 * n;
  for (size_t i = 0; i < n; ++i) {
    EXPECT_EQ(NV_Ith_S(x, i), first.samples[last + i]);
    EXPECT_EQ(NV_Ith_S(v, i), first.samples[last + n + i]);
  }
}

}  // namespace
