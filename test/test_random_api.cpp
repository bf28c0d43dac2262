// Random API sequences (fixed seeds, so every failure replays): every exported function of
// include/ceode/*.h (and the implementation toggles of ceode_testing.h) in any order, each argument
// drawn per parameter from plausible values and hostile ones: NaN, +-Inf, huge, negative, zero,
// NULL pointers, vectors of the wrong length or with non-finite entries, objects of other sizes.
// After every call the sequence checks
//   - no crash (the sanitizer build runs this test: an out-of-bounds access is a failure);
//   - no CE_SUCCESS (nor CE_TSTOP_RETURN, CE_WARNING) with a non-finite output: time, x, v, dense
//     output, statistics;
//   - every failure of a call on a memory carries a message (the error handler receives it);
// and, at random points and at its end, that the memory stays usable: a canonical setup on the
// same memory integrates x'' = -x from (1, 0.5) to t = 1 within 1e-5 of cos 1 + 0.5 sin 1.
// CEODE_FUZZ_SEEDS, CEODE_FUZZ_FIRST_SEED and CEODE_FUZZ_OPS widen a campaign (the defaults keep
// the test short under the sanitizers); CEODE_FUZZ_TRACE=1 prints every call of a replayed seed.
#include <arkode/arkode_mristep.h>
#include <ceode/ceode_stability.h>
#include <ceode/ceode_stepper.h>
#include <gtest/gtest.h>
#include <nvector/nvector_manyvector.h>
#include <sunlinsol/sunlinsol_band.h>
#include <sunlinsol/sunlinsol_klu.h>
#include <sunlinsol/sunlinsol_spgmr.h>
#include <sunmatrix/sunmatrix_band.h>
#include <sunmatrix/sunmatrix_sparse.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>
#include <sunnonlinsol/sunnonlinsol_newton.h>
#if SUNDIALS_VERSION_MAJOR >= 7
#include <sunadaptcontroller/sunadaptcontroller_soderlind.h>
#endif

#include <cctype>
#include <cfloat>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "ceode_testing.h"  // CEodeSetFusedKernel, CEodeSetSchurComplement, ...
#include "test_util.hpp"

namespace {

using namespace ceode_test;  // the handles and helpers of test_util.hpp

long EnvLong(const char* name, long fallback) {
  const char* s = std::getenv(name);
  return s != nullptr && *s != '\0' ? std::strtol(s, nullptr, 10) : fallback;
}

// What the callbacks do, changed by the sequence: damping c, failing returns, NaN values.
struct Data {
  sunrealtype c = 0;
  int rhs_ret = 0;
  bool rhs_nan = false;
  int jac_ret = 0;
  int mass_ret = 0;
  int constr_ret = 0;
  int ewt_ret = 0;
  sunrealtype schedule_h = SUN_RCONST(1e-2);
};
const Data kDefaultData;
const Data& D(void* data) { return data != nullptr ? *static_cast<Data*>(data) : kDefaultData; }

// x'' = -x - c x' (any length).
int Rhs(sunrealtype, N_Vector x, N_Vector v, N_Vector f, void* data) {
  const Data& d = D(data);
  N_VLinearSum(-1, x, -d.c, v, f);
  if (d.rhs_nan) N_VConst(NAN, f);
  return d.rhs_ret;
}

// Writes value on the diagonal of a dense, band or sparse (CSC, nnz >= n) matrix.
void Diagonal(SUNMatrix M, sunrealtype value) {
  switch (SUNMatGetID(M)) {
    case SUNMATRIX_DENSE:
      for (sunindextype j = 0; j < SUNDenseMatrix_Columns(M) && j < SUNDenseMatrix_Rows(M); ++j)
        SUNDenseMatrix_Column(M, j)[j] = value;
      break;
    case SUNMATRIX_BAND:
      for (sunindextype j = 0; j < SUNBandMatrix_Columns(M); ++j)
        SUNBandMatrix_Column(M, j)[0] = value;
      break;
    case SUNMATRIX_SPARSE: {
      const sunindextype n = std::min(SUNSparseMatrix_Rows(M), SUNSparseMatrix_Columns(M));
      if (SUNSparseMatrix_NNZ(M) < n) break;
      sunindextype* ptr = SUNSparseMatrix_IndexPointers(M);
      sunindextype* idx = SUNSparseMatrix_IndexValues(M);
      sunrealtype* val = SUNSparseMatrix_Data(M);
      for (sunindextype j = 0; j < n; ++j) {
        ptr[j] = j;
        idx[j] = j;
        val[j] = value;
      }
      for (sunindextype j = n; j <= SUNSparseMatrix_NP(M); ++j) ptr[j] = n;
      break;
    }
    default:
      break;
  }
}

int Mass(sunrealtype, N_Vector, SUNMatrix M, void* data, N_Vector, N_Vector, N_Vector) {
  Diagonal(M, 2);
  return D(data).mass_ret;
}

int VelJac(sunrealtype, N_Vector, N_Vector, N_Vector, SUNMatrix J, void* data, N_Vector, N_Vector,
           N_Vector) {
  Diagonal(J, -D(data).c);
  return D(data).jac_ret;
}

// phi_0 = |x|^2 - 1 and, for a template of two, phi_1 = x_0 - x_{n-1} (dependent for n = 1).
int Phi(sunrealtype, N_Vector x, N_Vector phi, void* data) {
  const sunindextype n = N_VGetLength(x);
  NV_Ith_S(phi, 0) = N_VDotProd(x, x) - 1;
  if (N_VGetLength(phi) > 1) NV_Ith_S(phi, 1) = NV_Ith_S(x, 0) - NV_Ith_S(x, n - 1);
  return D(data).constr_ret;
}

int ConstrJac(sunrealtype, N_Vector x, SUNMatrix G, void* data) {
  if (SUNMatGetID(G) != SUNMATRIX_DENSE) return -1;  // a callback that supports dense only
  const sunindextype n = N_VGetLength(x);
  SUNMatZero(G);
  for (sunindextype j = 0; j < n; ++j) SM_ELEMENT_D(G, 0, j) = 2 * NV_Ith_S(x, j);
  if (SUNDenseMatrix_Rows(G) > 1) {
    SM_ELEMENT_D(G, 1, 0) += 1;
    SM_ELEMENT_D(G, 1, n - 1) -= 1;
  }
  return D(data).constr_ret;
}

int Ewt(N_Vector x, N_Vector ewt, void* data) {
  N_VAbs(x, ewt);
  N_VScale(SUN_RCONST(1e-6), ewt, ewt);
  N_VAddConst(ewt, SUN_RCONST(1e-8), ewt);
  N_VInv(ewt, ewt);
  return D(data).ewt_ret;
}

sunrealtype Schedule(sunrealtype, long int, void* data) { return D(data).schedule_h; }

// The halves [x; v] of a serial vector of length 2n or of a ManyVector of two parts.
bool Halves(N_Vector y, sunrealtype** x, sunrealtype** v, sunindextype* n) {
  if (N_VGetVectorID(y) == SUNDIALS_NVEC_MANYVECTOR) {
    if (N_VGetNumSubvectors_ManyVector(y) != 2) return false;
    *x = N_VGetSubvectorArrayPointer_ManyVector(y, 0);
    *v = N_VGetSubvectorArrayPointer_ManyVector(y, 1);
    *n = N_VGetLength(N_VGetSubvector_ManyVector(y, 0));
    return N_VGetLength(N_VGetSubvector_ManyVector(y, 1)) == *n;
  }
  *n = N_VGetLength(y) / 2;
  *x = N_VGetArrayPointer(y);
  *v = *x + *n;
  return N_VGetLength(y) % 2 == 0;
}

// y' = [v; -x - c v], the first-order form of Rhs.
int FirstOrderRhs(sunrealtype, N_Vector y, N_Vector ydot, void* data) {
  sunrealtype *x = nullptr, *v = nullptr, *dx = nullptr, *dv = nullptr;
  sunindextype n = 0, m = 0;
  if (!Halves(y, &x, &v, &n) || !Halves(ydot, &dx, &dv, &m) || n != m) return -1;
  for (sunindextype i = 0; i < n; ++i) {
    dx[i] = v[i];
    dv[i] = -x[i] - D(data).c * v[i];
  }
  return D(data).rhs_ret;
}

int SlowZero(sunrealtype, N_Vector, N_Vector ydot, void*) {
  N_VConst(0, ydot);
  return 0;
}

// Receives every message of the memory: the check that each failure carries one.
struct Recorder {
  long count = 0;
  std::string last;
  static void Handler(int, const char*, const char*, char* msg, void* data) {
    auto* r = static_cast<Recorder*>(data);
    ++r->count;
    r->last = msg != nullptr ? msg : "";
  }
};

std::string Show(sunrealtype value) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.17g", static_cast<double>(value));
  return buf;
}

bool AllFinite(N_Vector y) {
  if (y == nullptr) return true;
  if (N_VGetVectorID(y) == SUNDIALS_NVEC_MANYVECTOR) {
    for (sunindextype k = 0; k < N_VGetNumSubvectors_ManyVector(y); ++k)
      if (!AllFinite(N_VGetSubvector_ManyVector(y, k))) return false;
    return true;
  }
  for (sunindextype i = 0; i < N_VGetLength(y); ++i) {
    if (!std::isfinite(NV_Ith_S(y, i))) return false;
  }
  return true;
}

struct NlsDeleter {
  void operator()(SUNNonlinearSolver s) const { SUNNonlinSolFree(s); }
};
using NonlinearSolver = std::unique_ptr<std::remove_pointer_t<SUNNonlinearSolver>, NlsDeleter>;

constexpr sunindextype kMaxSize = 5;  // objects of sizes 1..5: n up to 4, n + nc up to 5 (and 6)

// The objects a sequence attaches, of every size, alive for its whole length (the memory is
// declared after them, so it is freed first).
struct Objects {
  std::vector<Vector> vecs;  // vecs[k]: length k + 1
  std::vector<Matrix> dense, band, sparse, mass_dense, mass_band, mass_sparse, K;
  std::vector<LinearSolver> ls_dense, ls_band, ls_sparse, ls_spgmr, ls_mismatched;
  std::vector<NonlinearSolver> newton, fixed;
  std::vector<Vector> templates;  // constraint templates of length 1 and 2
  explicit Objects(SUNContext ctx) {
    for (sunindextype n = 1; n <= kMaxSize + 1; ++n) {
      vecs.push_back(SerialVector(n, ctx, 1));
      N_Vector y = vecs.back().get();
      dense.emplace_back(SUNDenseMatrix(n, n, ctx));
      band.emplace_back(SUNBandMatrix(n, 1, 1, ctx));
      sparse.emplace_back(SUNSparseMatrix(n, n, n * n, CSC_MAT, ctx));
      mass_dense.emplace_back(SUNDenseMatrix(n, n, ctx));
      mass_band.emplace_back(SUNBandMatrix(n, 0, 0, ctx));
      mass_sparse.emplace_back(SUNSparseMatrix(n, n, n, CSC_MAT, ctx));
      ls_dense.emplace_back(SUNLinSol_Dense(y, dense.back().get(), ctx));
      ls_band.emplace_back(SUNLinSol_Band(y, band.back().get(), ctx));
      ls_sparse.emplace_back(SUNLinSol_KLU(y, sparse.back().get(), ctx));
      ls_spgmr.emplace_back(SUNLinSol_SPGMR(y, SUN_PREC_NONE, 0, ctx));
      newton.emplace_back(SUNNonlinSol_Newton(y, ctx));
      fixed.emplace_back(SUNNonlinSol_FixedPoint(y, 0, ctx));
    }
    for (sunindextype n = 1; n <= 2; ++n) templates.push_back(SerialVector(n, ctx));
    // A solver created for a smaller matrix than the one it is attached with.
    ls_mismatched.emplace_back(SUNLinSol_Dense(vecs[1].get(), dense[1].get(), ctx));
  }
};

class Sequence {
 public:
  explicit Sequence(std::uint32_t seed) : seed_(seed), rng_(seed), obj_(ctx_) {
    mem_.reset(CEodeCreate(ctx_));
    sink_ = std::tmpfile();
    Listen();
  }
  ~Sequence() {
    mem_.reset();
    if (sink_ != nullptr) std::fclose(sink_);
  }
  Sequence(const Sequence&) = delete;
  Sequence& operator=(const Sequence&) = delete;

  // Runs `ops` random calls, then the canonical run; the violations are in violations().
  void Run(int ops) {
    op_ = -1;
    Canonical();  // from a working setup, so that the calls reach real integrations
    RichSetup();
    for (op_ = 0; op_ < ops; ++op_) Step();
    op_ = ops;
    Canonical();
  }
  const std::vector<std::string>& violations() const { return violations_; }
  long evolve_successes() const { return evolve_ok_; }
  long canonical_runs() const { return canonical_; }

 private:
  // ---- argument draws: plausible values most of the time, a hostile one otherwise ----------

  int Int(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }
  bool Chance(int one_in) { return Int(1, one_in) == 1; }
  template <typename T>
  T Pick(std::initializer_list<T> values) {
    return *(values.begin() + Int(0, static_cast<int>(values.size()) - 1));
  }
  sunrealtype Hostile() {
    return Pick<sunrealtype>({NAN, INFINITY, -INFINITY, 0, SUN_RCONST(-0.0), -1, 1e300, -1e300,
                              DBL_MAX, 5e-324, 1e-300});
  }
  sunrealtype Real(std::initializer_list<sunrealtype> good) {
    return Chance(6) ? Hostile() : Pick<sunrealtype>(good);
  }
  int IntArg(std::initializer_list<int> good) {
    return Chance(6) ? Pick<int>({INT_MIN, -1, 0, 1, 3, 100, INT_MAX}) : Pick<int>(good);
  }
  long LongArg(std::initializer_list<long> good) {
    return Chance(6) ? Pick<long>({LONG_MIN, -1, 0, 1, LONG_MAX}) : Pick<long>(good);
  }
  sunbooleantype Bool() {
    return Chance(6) ? Pick<sunbooleantype>({2, -1}) : (Chance(2) ? SUNTRUE : SUNFALSE);
  }
  void* MemArg() { return Chance(40) ? nullptr : mem_.get(); }
  // A vector for a parameter of length len: that length, one more or one less, NULL, or with a
  // NaN or an infinite entry. Kept until the next operation.
  N_Vector Vec(sunindextype len, sunrealtype value = 1) {
    const int kind = Int(0, 17);
    if (kind == 14) return nullptr;
    sunindextype m = len;
    if (kind == 15) m = len + 1;
    if (kind == 16) m = len > 1 ? len - 1 : len + 2;
    tmp_.push_back(SerialVector(std::max<sunindextype>(m, 1), ctx_, value));
    N_Vector y = tmp_.back().get();
    if (kind == 17) NV_Ith_S(y, 0) = Chance(2) ? NAN : INFINITY;
    return y;
  }
  sunindextype Size() { return Int(1, static_cast<int>(kMaxSize)); }
  sunindextype N() const { return n_ > 0 ? n_ : 2; }

  // ---- the checks ---------------------------------------------------------------------------

  void Violation(const std::string& what) {
    violations_.push_back("seed " + std::to_string(seed_) + ", op " + std::to_string(op_) + " (" +
                          name_ + "): " + what);
  }
  // One call; a failure on a memory must have reached the error handler with a message.
  int Call(const char* name, void* mem, const std::function<int()>& call) {
    name_ = name;
    if (trace_) std::fprintf(stderr, "seed %u op %d: %s\n", seed_, op_, name);
    const long before = rec_.count;
    const int flag = call();
    if (trace_) std::fprintf(stderr, "  -> %d %s\n", flag, flag < 0 ? rec_.last.c_str() : "");
    if (flag < 0 && mem != nullptr && (rec_.count == before || rec_.last.empty())) {
      Violation("flag " + std::to_string(flag) + " without a message");
    }
    return flag;
  }
  bool Ok(int flag) const { return flag >= 0; }
  void Finite(int flag, const char* what, const sunrealtype& value) {
    if (Ok(flag) && !std::isfinite(value)) Violation(std::string(what) + " is not finite");
  }
  void Finite(int flag, const char* what, N_Vector y) {
    if (Ok(flag) && !AllFinite(y)) Violation(std::string(what) + " is not finite");
  }
  void NonNegative(int flag, const char* what, const long& value) {
    if (Ok(flag) && value < 0) Violation(std::string(what) + " is negative");
  }
  void Listen() {
    if (mem_) CEodeSetErrHandlerFn(mem_.get(), Recorder::Handler, &rec_);
  }

  // ---- operations ---------------------------------------------------------------------------

  void Step();
  void AfterOp();
  void Init();
  void ReInit();
  void FirstOrder();
  void Method();
  void Toggles();
  void StepOptions();
  void Tolerances();
  void Velocity();
  void MassOp();
  void LinearSolverOp();
  void NonlinearSolverOp();
  void Callbacks();
  void Constraints();
  void InitialConditions();
  void Guard();
  void ErrorOutput();
  void Evolve();
  void GetDky();
  void Solution();
  void Counters();
  void Utilities();
  void Version();
  void Stability();
  void FrequencyBound();
  void Stepper();
#ifdef CEODE_HAVE_SUNSTEPPER
  void SunStepperCalls(SUNStepper st);
#endif
  void Lifecycle();
  void Canonical();
  void RichSetup();
  void SetOutputs(sunindextype n);

  std::uint32_t seed_;
  std::mt19937 rng_;
  Context ctx_;
  Objects obj_;
  Data data_;
  Recorder rec_;
  Mem mem_;
  FILE* sink_ = nullptr;
  bool trace_ = EnvLong("CEODE_FUZZ_TRACE", 0) != 0;  // each call's name to stderr, to replay one
#if SUNDIALS_VERSION_MAJOR >= 7
  struct ControllerDeleter {
    void operator()(SUNAdaptController C) const { SUNAdaptController_Destroy(C); }
  };
  std::unique_ptr<std::remove_pointer_t<SUNAdaptController>, ControllerDeleter> controller_;
#endif
  sunindextype n_ = 0;  // the problem's size after a successful CEodeInit (0: none)
  sunindextype nc_ = 0;
  Vector x_, v_;  // output vectors of the problem's length
  std::vector<Vector> tmp_;
  int op_ = 0;
  std::string name_;
  std::vector<std::string> violations_;
  long evolve_ok_ = 0;
  long canonical_ = 0;
};

void Sequence::Step() {
  tmp_.clear();
  using Op = void (Sequence::*)();
  static const Op ops[] = {&Sequence::Init,
                           &Sequence::ReInit,
                           &Sequence::FirstOrder,
                           &Sequence::Method,
                           &Sequence::Toggles,
                           &Sequence::StepOptions,
                           &Sequence::Tolerances,
                           &Sequence::Velocity,
                           &Sequence::MassOp,
                           &Sequence::LinearSolverOp,
                           &Sequence::NonlinearSolverOp,
                           &Sequence::Callbacks,
                           &Sequence::Constraints,
                           &Sequence::Guard,
                           &Sequence::ErrorOutput,
                           &Sequence::GetDky,
                           &Sequence::Solution,
                           &Sequence::Counters,
                           &Sequence::Utilities,
                           &Sequence::Stability,
                           &Sequence::FrequencyBound,
                           &Sequence::Stepper,
                           &Sequence::Lifecycle,
                           &Sequence::Canonical,
                           &Sequence::Evolve,
                           &Sequence::Evolve,
                           &Sequence::Evolve,
                           &Sequence::Evolve,
                           &Sequence::Evolve,
                           &Sequence::Evolve};
  const int k = Int(0, static_cast<int>(std::size(ops)) - 1);
  if (ops[k] == &Sequence::Canonical && !Chance(4)) return;  // an occasional check mid-sequence
  (this->*ops[k])();
  if (ops[k] == &Sequence::Canonical) RichSetup();
  AfterOp();
}

// After every operation, whatever it was: the memory's time, step and counters are finite.
void Sequence::AfterOp() {
  void* m = mem_.get();
  sunrealtype t = NAN, h = NAN;
  long nst = -1, nfe = -1;
  Finite(CEodeGetCurrentTime(m, &t), "the current time after the operation", t);
  Finite(CEodeGetCurrentStep(m, &h), "the current step after the operation", h);
  NonNegative(CEodeGetNumSteps(m, &nst), "the step count after the operation", nst);
  NonNegative(CEodeGetNumRhsEvals(m, &nfe), "the f count after the operation", nfe);
  const char* msg = nullptr;
  if (CEodeGetLastErrorMessage(m, &msg) != CE_SUCCESS || msg == nullptr)
    Violation("no last message string after the operation");
}

void Sequence::SetOutputs(sunindextype n) {
  n_ = n;
  x_ = SerialVector(n, ctx_);
  v_ = SerialVector(n, ctx_);
}

void Sequence::Init() {
  const sunindextype n = Int(1, 4);
  void* m = MemArg();
  N_Vector x0 = Vec(n, Pick<sunrealtype>({0, 1, -2, 1e100}));
  N_Vector v0 = Vec(n, Pick<sunrealtype>({0, 0.5, 1e3}));
  const int flag = Call("CEodeInit", m, [&] {
    return CEodeInit(m, Chance(20) ? nullptr : Rhs, Real({0, 1, -5, 1e20}), x0, v0);
  });
  if (flag == CE_SUCCESS) {
    SetOutputs(n);
    nc_ = 0;
  }
}

void Sequence::ReInit() {
  void* m = MemArg();
  const sunrealtype t0 = Real({0, 2, -1});
  Call("CEodeReInit", m, [&] { return CEodeReInit(m, t0, Vec(N(), 1), Vec(N(), 0.5)); });
  sunrealtype t = NAN;
  Finite(Call("CEodeGetCurrentTime", m, [&] { return CEodeGetCurrentTime(m, &t); }), "tcur", t);
}

// The first-order adapter: y = [x; v] as a serial vector of 2n or a ManyVector of two parts.
void Sequence::FirstOrder() {
  void* m = MemArg();
  const sunindextype n = n_ > 0 && Chance(2) ? n_ : Int(1, 3);
  N_Vector y = Vec(2 * n, Pick<sunrealtype>({0, 1, 0.5}));
  if (Chance(3)) {
    N_Vector parts[2] = {Vec(n), Vec(n, 0.5)};
    if (parts[0] != nullptr && parts[1] != nullptr) {
      tmp_.emplace_back(N_VNew_ManyVector(2, parts, ctx_));
      y = tmp_.back().get();
    }
  }
  const sunrealtype t0 = Real({0, 1});
  int flag = 0;
  switch (Int(0, 2)) {
    case 0:
      flag = Call("CEodeInitFirstOrder", m, [&] {
        return CEodeInitFirstOrder(m, Chance(20) ? nullptr : FirstOrderRhs, t0, y);
      });
      if (flag == CE_SUCCESS) {
        SetOutputs(N_VGetLength(y) / 2);
        nc_ = 0;
      }
      break;
    case 1:
      Call("CEodeReInitFirstOrder", m, [&] { return CEodeReInitFirstOrder(m, t0, y); });
      break;
    default: {
      sunrealtype tcur = 0, t = NAN;
      CEodeGetCurrentTime(mem_.get(), &tcur);
      const sunrealtype tout = tcur + Real({0, 0.01, 0.3});
      if (!(std::fabs(tout - tcur) <= 3)) CEodeSetMaxNumSteps(mem_.get(), 3000);  // as Evolve
      flag = Call("CEodeEvolveFirstOrder", m, [&] {
        return CEodeEvolveFirstOrder(m, tout, y, Chance(20) ? nullptr : &t,
                                     Pick<int>({CE_NORMAL, CE_ONE_STEP, 0}));
      });
      Finite(flag, "yout", y);
      Finite(flag, "tret", t);
      break;
    }
  }
}

void Sequence::Method() {
  void* m = MemArg();
  if (Chance(2)) {
    const int idx = Int(-1, CEodeGetNumMethods());
    const char* name =
        Chance(8) ? Pick<const char*>({nullptr, "", "G9_NONE"}) : CEodeGetMethodName(idx);
    Call("CEodeSetMethodByName", m, [&] { return CEodeSetMethodByName(m, name); });
    return;
  }
  std::vector<sunrealtype> p(9);
  for (auto& q : p) q = Real({0.25, 0.5, 1, 4.0 / 3, 2, 1.0 / 3});
  const int degree = Chance(6) ? IntArg({2, 9}) : Int(3, 8);
  Call("CEodeSetMethod", m,
       [&] { return CEodeSetMethod(m, degree, Chance(15) ? nullptr : p.data()); });
}

void Sequence::Toggles() {
  void* m = MemArg();
  switch (Int(0, 4)) {
    case 0:
      Call("CEodeSetZeroStart", m, [&] { return CEodeSetZeroStart(m, Bool()); });
      break;
    case 1:
      Call("CEodeSetCompensatedSummation", m,
           [&] { return CEodeSetCompensatedSummation(m, Bool()); });
      break;
    case 2:
      Call("CEodeSetFusedKernel", m, [&] { return CEodeSetFusedKernel(m, Bool()); });
      break;
    case 3:
      Call("CEodeSetInPlaceUpdate", m, [&] { return CEodeSetInPlaceUpdate(m, Bool()); });
      break;
    default:
      Call("CEodeSetSchurComplement", m, [&] { return CEodeSetSchurComplement(m, Bool()); });
      break;
  }
}

void Sequence::StepOptions() {
  void* m = MemArg();
  sunrealtype tcur = 0;
  CEodeGetCurrentTime(mem_.get(), &tcur);
  switch (Int(0, 5)) {
    case 0:
      Call("CEodeSetFixedStep", m, [&] {
        return CEodeSetFixedStep(m, Real({1e-3, 1e-2, 0.1, 0.3, 1e-150}));
      });
      break;
    case 1:
      Call("CEodeSetStopTime", m, [&] {
        return CEodeSetStopTime(m, tcur + Real({0.05, 0.5, -1}));
      });
      break;
    case 2:
      Call("CEodeClearStopTime", m, [&] { return CEodeClearStopTime(m); });
      break;
    case 3:
      Call("CEodeSetMaxNumSteps", m, [&] {
        return CEodeSetMaxNumSteps(
            m, Chance(6) ? Pick<long>({LONG_MIN, -1, 0, 1}) : Pick<long>({500, 3000}));
      });
      break;
    case 4:
      Call("CEodeSetUserData", m,
           [&] { return CEodeSetUserData(m, Chance(4) ? nullptr : &data_); });
      break;
    default:
      Call("CEodeSetStepSchedule", m, [&] {
        return CEodeSetStepSchedule(m, Chance(3) ? nullptr : Schedule,
                                    Chance(4) ? nullptr : &data_);
      });
      break;
  }
}

void Sequence::Tolerances() {
  void* m = MemArg();
  switch (Int(0, 9)) {
    case 0:
      Call("CEodeSStolerances", m, [&] {
        return CEodeSStolerances(m, Real({1e-6, 1e-3}), Real({1e-8, 0}));
      });
      break;
    case 1:
      Call("CEodeSVtolerances", m, [&] {
        return CEodeSVtolerances(m, Real({1e-6, 1e-4}), Vec(N(), 1e-8));
      });
      break;
    case 2:
      Call("CEodeWFtolerances", m, [&] { return CEodeWFtolerances(m, Chance(5) ? nullptr : Ewt); });
      break;
    case 3:
      Call("CEodeSetInitStep", m, [&] { return CEodeSetInitStep(m, Real({0, 1e-4, 1e-2})); });
      break;
    case 4:
      Call("CEodeSetMinStep", m, [&] { return CEodeSetMinStep(m, Real({0, 1e-8, 1e-3})); });
      break;
    case 5:
      Call("CEodeSetMaxStep", m, [&] { return CEodeSetMaxStep(m, Real({0, 0.1, 1e-3})); });
      break;
    case 6:
      Call("CEodeSetMaxErrTestFails", m, [&] {
        return CEodeSetMaxErrTestFails(m, IntArg({3, 7}));
      });
      break;
    case 7:
      Call("CEodeSetAdaptivityMethod", m, [&] {
        return CEodeSetAdaptivityMethod(m, IntArg({CE_ADAPT_PI, CE_ADAPT_H211B}));
      });
      break;
    case 8:
      Call("CEodeSetFixedStepBounds", m, [&] {
        return CEodeSetFixedStepBounds(m, Real({1, 0.97, 0.5}), Real({1, 1.2, 1.5}));
      });
      break;
    default:
#if SUNDIALS_VERSION_MAJOR >= 7
      if (!controller_) controller_.reset(SUNAdaptController_PI(ctx_));
      Call("CEodeSetAdaptController", m,
           [&] { return CEodeSetAdaptController(m, Chance(2) ? nullptr : controller_.get()); });
#endif
      break;
  }
}

void Sequence::Velocity() {
  void* m = MemArg();
  switch (Int(0, 7)) {
    case 0:
      Call("CEodeSetVelocityMode", m, [&] {
        return CEodeSetVelocityMode(m, static_cast<CEodeVelocityMode>(IntArg({0, 1, 2})));
      });
      break;
    case 1:
      Call("CEodeSetVelocityDependence", m, [&] { return CEodeSetVelocityDependence(m, Bool()); });
      break;
    case 2:
      Call("CEodeSetImplicitMode", m, [&] {
        return CEodeSetImplicitMode(m,
                                    IntArg({CE_IMPLICIT_NEWTON, CE_IMPLICIT_PC, CE_IMPLICIT_AUTO}));
      });
      break;
    case 3:
      Call("CEodeSetPCCorrections", m, [&] { return CEodeSetPCCorrections(m, IntArg({0, 1, 2})); });
      break;
    case 4:
      Call("CEodeSetMaxNonlinIters", m, [&] { return CEodeSetMaxNonlinIters(m, IntArg({3, 10})); });
      break;
    case 5:
      Call("CEodeSetNonlinTolerances", m, [&] {
        return CEodeSetNonlinTolerances(m, Real({1e-10, 1e-6}), Real({0, 1e-12}));
      });
      break;
    case 6:
      Call("CEodeSetVelJacDiagonal", m, [&] {
        return CEodeSetVelJacDiagonal(m, Vec(N(), Real({-0.5, 0, 0.2})));
      });
      break;
    default:
      Call("CEodeSetJacEvalFrequency", m, [&] {
        return CEodeSetJacEvalFrequency(m, LongArg({1, 20}));
      });
      break;
  }
}

void Sequence::MassOp() {
  void* m = MemArg();
  const sunindextype k = Size() - 1;
  SUNMatrix M = Pick<SUNMatrix>(
      {obj_.mass_dense[k].get(), obj_.mass_band[k].get(), obj_.mass_sparse[k].get(), nullptr});
  const bool fn = Chance(6) ? M == nullptr : M != nullptr;  // a mismatch now and then
  Call("CEodeSetMassFn", m, [&] { return CEodeSetMassFn(m, fn ? Mass : nullptr, M, Bool()); });
}

void Sequence::LinearSolverOp() {
  void* m = MemArg();
  const sunindextype k = Size() - 1;
  const sunindextype j = Chance(4) ? Size() - 1 : k;  // a matrix of another size now and then
  SUNLinearSolver LS = nullptr;
  SUNMatrix A = nullptr;
  switch (Int(0, 5)) {
    case 0:
      LS = obj_.ls_dense[k].get(), A = obj_.dense[j].get();
      break;
    case 1:
      LS = obj_.ls_band[k].get(), A = obj_.band[j].get();
      break;
    case 2:
      LS = obj_.ls_sparse[k].get(), A = obj_.sparse[j].get();
      break;
    case 3:
      LS = obj_.ls_spgmr[k].get();
      break;
    case 4:
      LS = obj_.ls_mismatched[0].get(), A = obj_.dense[Int(0, 4)].get();
      break;
    default:
      LS = Chance(2) ? nullptr : obj_.ls_dense[k].get();
      A = Chance(2) ? nullptr : obj_.band[j].get();  // a wrong type or no matrix
      break;
  }
  Call("CEodeSetLinearSolver", m, [&] { return CEodeSetLinearSolver(m, LS, A); });
}

void Sequence::NonlinearSolverOp() {
  void* m = MemArg();
  const sunindextype k = Size() - 1;
  SUNNonlinearSolver NLS =
      Pick<SUNNonlinearSolver>({obj_.newton[k].get(), obj_.fixed[k].get(), nullptr});
  Call("CEodeSetNonlinearSolver", m, [&] { return CEodeSetNonlinearSolver(m, NLS); });
}

// The callbacks themselves: the velocity Jacobian, and what every callback returns.
void Sequence::Callbacks() {
  void* m = MemArg();
  switch (Int(0, 2)) {
    case 0:
      Call("CEodeSetVelJacFn", m,
           [&] { return CEodeSetVelJacFn(m, Chance(3) ? nullptr : VelJac); });
      break;
    case 1:
      data_.c = Pick<sunrealtype>({0, 0.1, 1, 50});
      data_.rhs_nan = Chance(30);
      data_.rhs_ret = Chance(20) ? Pick<int>({-1, 1}) : 0;
      break;
    default:
      data_.jac_ret = Chance(3) ? Pick<int>({-1, 1}) : 0;
      data_.mass_ret = Chance(10) ? Pick<int>({-1, 1}) : 0;
      data_.constr_ret = Chance(10) ? Pick<int>({-1, 1}) : 0;
      data_.ewt_ret = Chance(10) ? -1 : 0;
      data_.schedule_h = Real({1e-3, 1e-2, 0.05});
      break;
  }
}

void Sequence::Constraints() {
  void* m = MemArg();
  const int kind = Int(0, 5);
  N_Vector tmpl = kind < 3 ? obj_.templates[kind % 2].get() : nullptr;
  if (kind == 2) tmpl = Vec(1);  // NULL, or of a wrong length, or with NaN
  const bool remove = kind == 3;
  CEodeConstrFn phi = remove || Chance(8) ? nullptr : Phi;
  CEodeConstrJacFn G = remove || Chance(8) ? nullptr : ConstrJac;
  const int flag =
      Call("CEodeSetConstraints", m, [&] { return CEodeSetConstraints(m, tmpl, phi, G); });
  if (flag == CE_SUCCESS && m != nullptr) nc_ = tmpl != nullptr ? N_VGetLength(tmpl) : 0;
  if (Chance(2)) InitialConditions();
}

// The consistent start: the projection, how far it moved x0 and v0, and the projected values.
void Sequence::InitialConditions() {
  void* m = MemArg();
  switch (Int(0, 2)) {
    case 0:
      Call("CEodeCalcIC", m, [&] {
        return CEodeCalcIC(
            m, IntArg({CE_IC_POSITION, CE_IC_VELOCITY, CE_IC_POSITION | CE_IC_VELOCITY}));
      });
      break;
    case 1: {
      sunrealtype dx = NAN, dv = NAN;
      const int flag = Call("CEodeGetICCorrection", m, [&] {
        return CEodeGetICCorrection(m, Chance(20) ? nullptr : &dx, Chance(20) ? nullptr : &dv);
      });
      Finite(flag, "the position correction", dx);
      Finite(flag, "the velocity correction", dv);
      break;
    }
    default: {
      N_Vector x0 = Vec(N()), v0 = Vec(N());
      const int flag =
          Call("CEodeGetConsistentIC", m, [&] { return CEodeGetConsistentIC(m, x0, v0); });
      Finite(flag, "the consistent x0", x0);
      Finite(flag, "the consistent v0", v0);
      break;
    }
  }
}

void Sequence::Guard() {
  void* m = MemArg();
  switch (Int(0, 6)) {
    case 0:
      Call("CEodeSetStabilityGuard", m, [&] {
        return CEodeSetStabilityGuard(
            m, IntArg({CE_GUARD_OFF, CE_GUARD_WARN, CE_GUARD_REFUSE}),
            Chance(6) ? Pick<long>({LONG_MIN, -1, LONG_MAX}) : Pick<long>({0, 200, 1000}));
      });
      break;
    case 1:
      Call("CEodeSetMaxFrequency", m, [&] { return CEodeSetMaxFrequency(m, Real({0, 1, 100})); });
      break;
    case 2:
      Call("CEodeSetGuardMass", m, [&] {
        return CEodeSetGuardMass(m, Vec(N(), Real({1, 2, 0.5})));
      });
      break;
    case 3: {
      sunrealtype h = NAN;
      const int flag = Call("CEodeGetStableStep", m, [&] {
        return CEodeGetStableStep(m, Real({0, 0.5, 1}), Chance(20) ? nullptr : &h);
      });
      Finite(flag, "hmax", h);
      break;
    }
    case 5:
      Call("CEodeSetGuardReuse", m, [&] { return CEodeSetGuardReuse(m, Bool()); });
      break;
    case 4: {
      sunrealtype w = NAN;
      Finite(Call("CEodeGetMaxFrequencyEstimate", m,
                  [&] { return CEodeGetMaxFrequencyEstimate(m, Chance(20) ? nullptr : &w); }),
             "omega_max", w);
      break;
    }
    default: {
      long a = -1, b = -1, c = -1;
      const int flag = Call("CEodeGetGuardStats", m, [&] {
        return CEodeGetGuardStats(m, &a, Chance(20) ? nullptr : &b, &c);
      });
      NonNegative(flag, "guard nfevals", a);
      NonNegative(flag, "guard nmevals", b);
      NonNegative(flag, "guard nlinsetups", c);
      break;
    }
  }
}

// The error handler and file themselves; the recorder listens again afterwards.
void Sequence::ErrorOutput() {
  void* m = MemArg();
  if (Chance(2)) {
    Call("CEodeSetErrHandlerFn", m, [&] { return CEodeSetErrHandlerFn(m, nullptr, nullptr); });
  } else {
    Call("CEodeSetErrFile", m, [&] { return CEodeSetErrFile(m, Chance(2) ? nullptr : sink_); });
  }
  // Without a handler (or a file) the message is still kept for CEodeGetLastErrorMessage.
  if (m != nullptr && CEodeSetInitStep(m, NAN) < 0) {
    const char* msg = nullptr;
    CEodeGetLastErrorMessage(m, &msg);
    if (msg == nullptr || std::string(msg).find("hin") == std::string::npos)
      Violation("a failure without a handler kept no message");
  }
  Listen();
}

void Sequence::Evolve() {
  if (n_ == 0 && !Chance(10)) return;
  void* m = MemArg();
  sunrealtype tcur = 0, t = NAN;
  CEodeGetCurrentTime(mem_.get(), &tcur);
  const sunrealtype tout = tcur + Real({0, 1e-4, 0.01, 0.3, 1, 2, -1});
  // A far tout under the default limit (5e8 steps, restored by a limit <= 0) would run for hours.
  if (!(std::fabs(tout - tcur) <= 3)) CEodeSetMaxNumSteps(mem_.get(), 3000);
  N_Vector xo = Chance(10) ? Vec(N()) : x_.get();
  N_Vector vo = Chance(10) ? Vec(N()) : v_.get();
  const int itask = Chance(10) ? IntArg({0, 3}) : (Chance(4) ? CE_ONE_STEP : CE_NORMAL);
  const int flag = Call("CEodeEvolve", m, [&] {
    return CEodeEvolve(m, tout, xo, vo, Chance(30) ? nullptr : &t, itask);
  });
  Finite(flag, "xout", xo);
  Finite(flag, "vout", vo);
  Finite(flag, "tret", t);
  if (Ok(flag)) ++evolve_ok_;
}

void Sequence::GetDky() {
  void* m = MemArg();
  sunrealtype tcur = 0, h = 0;
  CEodeGetCurrentTime(mem_.get(), &tcur);
  CEodeGetCurrentStep(mem_.get(), &h);
  const sunrealtype t = tcur + h * Real({0, 0.5, 1, -0.5, 2});
  N_Vector dky = Vec(N());
  Finite(Call("CEodeGetDky", m,
              [&] {
                return CEodeGetDky(m, t, IntArg({0, 1, 2, 3, 8}), dky);
              }),
         "dky", dky);
}

void Sequence::Solution() {
  void* m = MemArg();
  sunrealtype r = NAN;
  sunrealtype* out = Chance(20) ? nullptr : &r;
  switch (Int(0, 7)) {
    case 0: {
      N_Vector a = Vec(N());
      Finite(Call("CEodeGetAccel", m, [&] { return CEodeGetAccel(m, a); }), "accel", a);
      break;
    }
    case 1: {
      N_Vector lam = Vec(nc_ > 0 ? nc_ : 1);
      Finite(Call("CEodeGetMultipliers", m, [&] { return CEodeGetMultipliers(m, lam); }), "lambda",
             lam);
      break;
    }
    case 2:
      Finite(Call("CEodeGetCurrentTime", m, [&] { return CEodeGetCurrentTime(m, out); }), "tcur",
             r);
      break;
    case 3:
      Finite(Call("CEodeGetCurrentStep", m, [&] { return CEodeGetCurrentStep(m, out); }), "hcur",
             r);
      break;
    case 4:
      Finite(Call("CEodeGetLastStep", m, [&] { return CEodeGetLastStep(m, out); }), "hlast", r);
      break;
    case 5:
      Finite(Call("CEodeGetActualInitStep", m, [&] { return CEodeGetActualInitStep(m, out); }),
             "hinused", r);
      break;
    case 6: {
      N_Vector w = Vec(N());
      Finite(Call("CEodeGetErrWeights", m, [&] { return CEodeGetErrWeights(m, w); }), "eweight", w);
      break;
    }
    default: {
      N_Vector e = Vec(N());
      Finite(Call("CEodeGetEstLocalErrors", m, [&] { return CEodeGetEstLocalErrors(m, e); }), "ele",
             e);
      break;
    }
  }
}

void Sequence::Counters() {
  using Getter = int (*)(void*, long int*);
  static const std::pair<const char*, Getter> getters[] = {
      {"CEodeGetNumSteps", CEodeGetNumSteps},
      {"CEodeGetNumRhsEvals", CEodeGetNumRhsEvals},
      {"CEodeGetNumStartRhsEvals", CEodeGetNumStartRhsEvals},
      {"CEodeGetNumNonlinSolvIters", CEodeGetNumNonlinSolvIters},
      {"CEodeGetNumNonlinSolvConvFails", CEodeGetNumNonlinSolvConvFails},
      {"CEodeGetNumLinSolvSetups", CEodeGetNumLinSolvSetups},
      {"CEodeGetNumLinSolves", CEodeGetNumLinSolves},
      {"CEodeGetNumJacEvals", CEodeGetNumJacEvals},
      {"CEodeGetNumRhsEvalsJacDQ", CEodeGetNumRhsEvalsJacDQ},
      {"CEodeGetNumMassEvals", CEodeGetNumMassEvals},
      {"CEodeGetNumConstrEvals", CEodeGetNumConstrEvals},
      {"CEodeGetNumConstrJacEvals", CEodeGetNumConstrJacEvals},
      {"CEodeGetNumErrTestFails", CEodeGetNumErrTestFails},
      {"CEodeGetNumStableStepLimited", CEodeGetNumStableStepLimited},
      {"CEodeGetNumInnerRestarts", CEodeGetNumInnerRestarts},
      {"CEodeGetNumPCSteps", CEodeGetNumPCSteps},
      {"CEodeGetNumPCCorrections", CEodeGetNumPCCorrections},
      {"CEodeGetNumGEvals", CEodeGetNumGEvals}};
  void* m = MemArg();
  for (const auto& [name, get] : getters) {
    long value = -1;
    long* out = Chance(30) ? nullptr : &value;
    NonNegative(Call(name, m, [&] { return get(m, out); }), name, value);
  }
  long a = -1, b = -1, c = -1;
  sunrealtype coupling = NAN;
  const int flag = Call("CEodeGetImplicitStats", m, [&] {
    return CEodeGetImplicitStats(m, &a, &b, Chance(20) ? nullptr : &c, &coupling);
  });
  NonNegative(flag, "npcsteps", a);
  NonNegative(flag, "nnlssteps", b);
  NonNegative(flag, "nfecoupling", c);
  Finite(flag, "coupling", coupling);
}

void Sequence::Utilities() {
  void* m = MemArg();
  switch (Int(0, 4)) {
    case 0: {
      sunrealtype p[8] = {NAN, NAN, NAN, NAN, NAN, NAN, NAN, NAN};
      int degree = -1;
      const char* name = Chance(5) ? Pick<const char*>({nullptr, "", "none"})
                                   : CEodeGetMethodName(Int(0, CEodeGetNumMethods() - 1));
      const int maxp = IntArg({2, 7, 8});
      const bool withp = !Chance(20);  // NULL params: the degree only
      const int flag = CEodeGetMethodParams(name, Chance(20) ? nullptr : &degree,
                                            withp ? p : nullptr, std::min(maxp, 8));
      for (int i = 0; Ok(flag) && withp && i + 1 < degree && i < std::min(maxp, 8); ++i)
        Finite(flag, "method params", p[i]);
      break;
    }
    case 1: {
      char* name = CEodeGetReturnFlagName(LongArg({0, -2, -20, 1, 99}));
      if (name == nullptr) Violation("CEodeGetReturnFlagName returned NULL");
      std::free(name);
      break;
    }
    case 4:
      Version();
      break;
    case 2:
      Call("CEodePrintAllStats", m, [&] {
        return CEodePrintAllStats(
            m, Chance(8) ? nullptr : sink_,
            static_cast<SUNOutputFormat>(IntArg({SUN_OUTPUTFORMAT_TABLE, SUN_OUTPUTFORMAT_CSV})));
      });
      break;
    default: {
      const char* msg = nullptr;
      const int flag = Call("CEodeGetLastErrorMessage", m, [&] {
        return CEodeGetLastErrorMessage(m, Chance(20) ? nullptr : &msg);
      });
      if (Ok(flag) && msg == nullptr) Violation("a NULL message with success");
      break;
    }
  }
}

// The version queries take no memory: a short or absent buffer is refused, never overrun.
void Sequence::Version() {
  char buf[32];
  const int len = IntArg({0, 4, 8, 32});
  char* out = Chance(10) ? nullptr : buf;
  const int cap = std::min(len, static_cast<int>(sizeof buf));
  if (Chance(2)) {
    const int flag = CEodeGetVersion(out, cap);
    if (flag == 0 && (out == nullptr || std::memchr(buf, 0, cap) == nullptr))
      Violation("CEodeGetVersion succeeded without a terminated string");
    return;
  }
  int major = -1, minor = -1, patch = -1;
  const int flag = CEodeGetVersionNumber(Chance(20) ? nullptr : &major, &minor, &patch, out, cap);
  if (flag == 0 && (major < 0 || minor < 0 || patch < 0))
    Violation("CEodeGetVersionNumber succeeded with a negative number");
}

// The stability analysis (no memory: failures print to stderr, outputs must be finite).
void Sequence::Stability() {
  const int degree = Chance(6) ? IntArg({2, 9}) : Int(3, 8);
  sunrealtype p[8];
  for (auto& q : p) q = Real({0.25, 0.5, 1, 4.0 / 3, 2});
  const sunrealtype* params = Chance(20) ? nullptr : p;
  const sunrealtype Omega = Real({0.1, 1, 2.5}), xi = Real({0, 0.05, 1});
  sunrealtype r = NAN, A[64], Om[3] = {Real({0.5, 1}), 0.1, Real({2, 3})}, rho[3];
  int ox = -1, ov = -1, flag = 0;
  const int which = Int(0, 6);
  static const char* const names[] = {"CEodeSpectralRadius",      "CEodeStabilityLimit",
                                      "CEodeAmplificationMatrix", "CEodeSpectralRadii",
                                      "CEodeMethodOrder",         "CEodeMethodErrorCoeffs",
                                      "CEodeMethodErrorConstant"};
  name_ = std::string(names[which]) + " (degree " + std::to_string(degree) + ", params";
  for (int i = 0; params != nullptr && i + 1 < degree && i < 8; ++i) name_ += " " + Show(p[i]);
  name_ += ", Omega " + Show(Omega) + ", xi " + Show(xi) + ")";
  switch (which) {
    case 0:
      Finite(CEodeSpectralRadius(degree, params, Omega, xi, &r), "rho", r);
      break;
    case 1:
      Finite(CEodeStabilityLimit(degree, params, xi, &r), "Omega_max", r);
      break;
    case 2:
      flag = CEodeAmplificationMatrix(degree, params, Omega, xi, Chance(20) ? nullptr : A);
      for (int i = 0; Ok(flag) && i < degree * degree && i < 64; ++i)
        Finite(flag, "amplification", A[i]);
      break;
    case 3:
      ox = Pick<int>({3, 0, -1});
      flag = CEodeSpectralRadii(degree, params, xi, ox, Om, rho);
      for (int i = 0; Ok(flag) && i < ox; ++i) Finite(flag, "radii", rho[i]);
      break;
    case 4:
      CEodeMethodOrder(degree, params, &ox, Chance(20) ? nullptr : &ov);
      break;
    case 5: {
      sunrealtype cx[6], cv[6];
      const int count = Pick<int>({4, 6, 0, -1});
      flag = CEodeMethodErrorCoeffs(degree, params, count, cx, Chance(20) ? nullptr : cv);
      for (int i = 0; Ok(flag) && i < count; ++i) Finite(flag, "error coefficients", cx[i]);
      break;
    }
    default:
      Finite(CEodeMethodErrorConstant(degree, params, &ox, &r), "error constant", r);
      break;
  }
}

void Sequence::FrequencyBound() {
  void* m = MemArg();
  const sunindextype k = Size() - 1;
  SUNMatrix K = Pick<SUNMatrix>(
      {obj_.mass_dense[k].get(), obj_.band[k].get(), obj_.mass_sparse[k].get(), nullptr});
  if (K != nullptr) {
    SUNMatZero(K);
    if (SUNMatGetID(K) != SUNMATRIX_SPARSE || Chance(2)) Diagonal(K, Real({4, 1, -3}));
  }
  N_Vector mass = Chance(3) ? nullptr : Vec(k + 1, Real({1, 2}));
  sunrealtype w = NAN;
  Finite(Call("CEodeGetFrequencyBound", m,
              [&] { return CEodeGetFrequencyBound(m, K, mass, Chance(20) ? nullptr : &w); }),
         "omega_bound", w);
}

// The inner stepper: created, run by MRIStep over a short slow step when there is a problem,
// freed; and its restart counter.
void Sequence::Stepper() {
  void* m = MemArg();
  CEodeSetMaxNumSteps(mem_.get(), 3000);  // the stepper's fuzzed times may lie far ahead
  MRIStepInnerStepper inner = nullptr;
  const int flag = Call("CEodeCreateMRIStepInnerStepper", m, [&] {
    return CEodeCreateMRIStepInnerStepper(m, Chance(20) ? nullptr : &inner);
  });
  if (Ok(flag) && inner != nullptr && n_ > 0) {
    Vector xs = SerialVector(n_, ctx_, 1), vs = SerialVector(n_, ctx_, 0.5);
    N_Vector parts[2] = {xs.get(), vs.get()};
    Vector y(N_VNew_ManyVector(2, parts, ctx_));
    void* mri = MRIStepCreate(SlowZero, nullptr, 0, y.get(), inner, ctx_);
    if (mri != nullptr) {
      MRIStepSetFixedStep(mri, Pick<sunrealtype>({0.05, 0.1}));
      MRIStepSetMaxNumSteps(mri, 50);
      sunrealtype t = NAN;
      const int rv = MRIStepEvolve(mri, Real({0.1, 0.2}), y.get(), &t, ARK_NORMAL);
      if (rv >= 0 && (!AllFinite(y.get()) || !std::isfinite(t)))
        Violation("MRIStepEvolve succeeded with a non-finite state");
      MRIStepFree(&mri);
    }
    Listen();  // MRIStep's failures are reported by ARKODE too
  }
  Call("CEodeFreeMRIStepInnerStepper", nullptr,
       [&] { return CEodeFreeMRIStepInnerStepper(Chance(20) ? nullptr : &inner); });
  if (inner != nullptr) CEodeFreeMRIStepInnerStepper(&inner);
#ifdef CEODE_HAVE_SUNSTEPPER
  SUNStepper st = nullptr;
  const int sflag = Call("CEodeCreateSUNStepper", m,
                         [&] { return CEodeCreateSUNStepper(m, Chance(20) ? nullptr : &st); });
  if (Ok(sflag) && st != nullptr) {
    SunStepperCalls(st);
    SUNStepper_Destroy(&st);
  }
#endif
}

#ifdef CEODE_HAVE_SUNSTEPPER
// The SUNStepper's operations with fuzzed arguments on [x; v] ManyVectors of the problem's size
// (or another); whatever succeeds must return a finite state and time.
void Sequence::SunStepperCalls(SUNStepper st) {
  const sunindextype n = Chance(6) ? Size() : N();
  N_Vector parts[2] = {Vec(n), Vec(n, 0.5)};
  N_Vector y = nullptr;
  if (parts[0] != nullptr && parts[1] != nullptr) {
    tmp_.emplace_back(N_VNew_ManyVector(2, parts, ctx_));
    y = tmp_.back().get();
  }
  sunrealtype t = NAN;
  for (int i = 0; i < 4; ++i) {
    int rv = 0;
    switch (Int(0, 5)) {
      case 0:
        rv = SUNStepper_Reset(st, Real({0, 1}), y);
        break;
      case 1:
        rv = SUNStepper_SetStopTime(st, Real({0.1, 1}));
        break;
      case 2:
        rv = SUNStepper_SetStepDirection(st, Real({1, -1}));
        break;
      case 3: {
        N_Vector forcing[2] = {Vec(2 * n), Vec(2 * n)};
        rv = SUNStepper_SetForcing(st, Real({0, 1}), Real({1, 0.5}), forcing, Int(0, 2));
        break;
      }
      case 4:
        rv = SUNStepper_FullRhs(st, Real({0, 1}), y, y, SUN_FULLRHS_START);
        break;
      default:
        rv = SUNStepper_Evolve(st, Real({0.01, 0.1}), y, &t);
        if (rv == 0 && (!AllFinite(y) || !std::isfinite(t)))
          Violation("SUNStepper_Evolve succeeded with a non-finite state or time");
        break;
    }
    (void)rv;
  }
  Listen();
}
#endif

// Creation and destruction with hostile arguments; the sequence's own memory is not freed.
void Sequence::Lifecycle() {
  void* none = CEodeCreate(nullptr);
  if (none != nullptr) Violation("CEodeCreate(NULL) returned a memory");
  CEodeFree(nullptr);
  CEodeFree(&none);
  void* other = CEodeCreate(ctx_);
  if (other == nullptr) Violation("CEodeCreate failed");
  CEodeFree(&other);
  if (other != nullptr) Violation("CEodeFree did not clear the pointer");
}

// The memory stays usable: a canonical setup on it integrates x'' = -x from (1, 0.5) to t = 1
// within 1e-5 of the exact cos 1 + 0.5 sin 1 (h = 1e-3, G3_CD: error about 1e-7).
void Sequence::Canonical() {
  void* m = mem_.get();
  name_ = "canonical run";
  Vector x0 = SerialVector(2, ctx_, 1), v0 = SerialVector(2, ctx_, SUN_RCONST(0.5));
  int flag = CEodeInit(m, Rhs, 0, x0.get(), v0.get());
  const int setup[] = {
    flag,
    CEodeSetUserData(m, nullptr),
    CEodeSetMethodByName(m, "G3_CD"),
    CEodeSetFixedStep(m, SUN_RCONST(1e-3)),
    CEodeSetConstraints(m, nullptr, nullptr, nullptr),
    CEodeSetMassFn(m, nullptr, nullptr, SUNTRUE),
    CEodeSetLinearSolver(m, obj_.ls_dense[1].get(), obj_.dense[1].get()),
    CEodeSetVelJacFn(m, nullptr),
    CEodeSetVelJacDiagonal(m, nullptr),
    CEodeSetVelocityMode(m, CE_VELOCITY_INDEPENDENT),
    CEodeSetStabilityGuard(m, CE_GUARD_OFF, 0),
    CEodeSetMaxFrequency(m, 0),
    CEodeSetGuardMass(m, nullptr),
    CEodeSetGuardReuse(m, SUNFALSE),
    CEodeClearStopTime(m),
    CEodeSetMaxNumSteps(m, 5000),
    CEodeSetZeroStart(m, SUNFALSE),
    CEodeSetStepSchedule(m, nullptr, nullptr),
#if SUNDIALS_VERSION_MAJOR >= 7
    CEodeSetAdaptController(m, nullptr),
#endif
  };
  for (const int f : setup) {
    if (f != CE_SUCCESS)
      Violation("canonical setup refused: " + std::to_string(f) + ": " + rec_.last);
  }
  SetOutputs(2);
  nc_ = 0;
  sunrealtype t = NAN;
  flag = CEodeEvolve(m, 1, x_.get(), v_.get(), &t, CE_NORMAL);
  ++canonical_;
  const sunrealtype exact = std::cos(1.0) + 0.5 * std::sin(1.0);
  if (flag != CE_SUCCESS) {
    Violation("canonical run failed: " + std::to_string(flag) + ": " + rec_.last);
  } else if (t != 1 || !(std::fabs(NV_Ith_S(x_.get(), 0) - exact) < 1e-5) ||
             !(std::fabs(NV_Ith_S(x_.get(), 1) - exact) < 1e-5)) {
    Violation("canonical run gave x = " + std::to_string(NV_Ith_S(x_.get(), 0)) +
              " at t = " + std::to_string(t) + ", exact " + std::to_string(exact));
  }
}

// A valid configuration beyond the canonical one for n = 2, so that the sequence's calls also
// meet the implicit step, the mass matrix, constraints (on the unit circle) and error control.
void Sequence::RichSetup() {
  void* m = mem_.get();
  CEodeSetUserData(m, &data_);
  data_ = Data{};
  if (Chance(2)) {
    data_.c = Pick<sunrealtype>({0.1, 50});
    CEodeSetVelocityDependence(m, SUNTRUE);
    CEodeSetImplicitMode(m, Pick<int>({CE_IMPLICIT_NEWTON, CE_IMPLICIT_PC, CE_IMPLICIT_AUTO}));
    if (Chance(2)) CEodeSetVelJacFn(m, VelJac);
  }
  if (Chance(3)) CEodeSetMassFn(m, Mass, obj_.mass_dense[1].get(), Bool());
  if (Chance(3)) {
    const sunrealtype r = std::sqrt(SUN_RCONST(0.5));
    N_VConst(r, x_.get());
    NV_Ith_S(v_.get(), 0) = SUN_RCONST(0.5);
    NV_Ith_S(v_.get(), 1) = SUN_RCONST(-0.5);
    CEodeReInit(m, 0, x_.get(), v_.get());
    CEodeSetConstraints(m, obj_.templates[0].get(), Phi, ConstrJac);
    CEodeSetLinearSolver(m, obj_.ls_dense[2].get(), obj_.dense[2].get());
    CEodeSetSchurComplement(m, Bool());
    nc_ = 1;
  }
  if (Chance(4)) CEodeSStolerances(m, SUN_RCONST(1e-6), SUN_RCONST(1e-8));
}

TEST(RandomApiSequences, KeepEveryInvariantUnderArgumentFuzzingOfEveryEntryPoint) {
  const long seeds = EnvLong("CEODE_FUZZ_SEEDS", 100);
  const long first = EnvLong("CEODE_FUZZ_FIRST_SEED", 1);
  const int ops = static_cast<int>(EnvLong("CEODE_FUZZ_OPS", 80));
  long evolve_ok = 0, canonical = 0, failed_seeds = 0;
  std::vector<std::string> all;
  for (long seed = first; seed < first + seeds; ++seed) {
    Sequence seq(static_cast<std::uint32_t>(seed));
    seq.Run(ops);
    evolve_ok += seq.evolve_successes();
    canonical += seq.canonical_runs();
    if (!seq.violations().empty()) ++failed_seeds;
    for (const auto& v : seq.violations()) all.push_back(v);
  }
  for (size_t i = 0; i < all.size() && i < 40; ++i) ADD_FAILURE() << all[i];
  EXPECT_EQ(all.size(), 0u) << failed_seeds << " seeds with violations";
  std::printf(
      "seeds %ld..%ld, %d ops each: %ld successful Evolve calls, %ld canonical runs, "
      "%zu violations in %ld seeds\n",
      first, first + seeds - 1, ops, evolve_ok, canonical, all.size(), failed_seeds);
  // The sequences must reach real integrations, or they would test nothing but refusals.
  EXPECT_GT(evolve_ok, 2 * seeds) << evolve_ok;
  EXPECT_GE(canonical, seeds);
}

}  // namespace

namespace {

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// Whether text names the function (a call or a function pointer), not only a longer name.
bool Names(const std::string& text, const std::string& name) {
  for (size_t at = text.find(name); at != std::string::npos; at = text.find(name, at + 1)) {
    const size_t end = at + name.size();
    if (end == text.size() ||
        !(std::isalnum(static_cast<unsigned char>(text[end])) || text[end] == '_'))
      return true;
  }
  return false;
}

}  // namespace

// Every function the public headers export is called by a randomised API test (this one or the
// root functions' own): a new entry point cannot miss the fuzzing.
TEST(RandomApiSequences, CallEveryFunctionThePublicHeadersExport) {
  const std::string root = CEODE_SOURCE_DIR;
  const std::string tests = ReadText(root + "/test/test_random_api.cpp") +
                            ReadText(root + "/test/test_random_api_roots.cpp");
  const std::regex exported(R"(SUNDIALS_EXPORT[^;(]*\b(CEode\w+)\s*\()");
  std::set<std::string> names;
  for (const char* header : {"ceode.h", "ceode_stability.h", "ceode_stepper.h"}) {
    const std::string text = ReadText(root + "/include/ceode/" + header);
    ASSERT_FALSE(text.empty()) << header;
    for (std::sregex_iterator it(text.begin(), text.end(), exported), end; it != end; ++it)
      names.insert((*it)[1].str());
  }
  EXPECT_GT(names.size(), 80u);  // the headers were read and parsed
  for (const std::string& name : names) {
    EXPECT_TRUE(Names(tests, name)) << name << " is exported but no randomised API test calls it";
  }
}
