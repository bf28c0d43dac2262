// ceode.Integrator: creation, options and statistics over CEODE's C API. Every C call goes
// through Check, which turns a negative flag into ceode.CEodeError.
#include "integrator.hpp"

#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <algorithm>
#include <cmath>

namespace ceode_py {

namespace {

N_Vector NewVector(const RealArray& a, SUNContext ctx) {
  N_Vector v = N_VNew_Serial(a.shape(0), ctx);
  if (v == nullptr) throw std::bad_alloc();
  std::copy(a.data(), a.data() + a.shape(0), N_VGetArrayPointer(v));
  return v;
}

int GuardMode(const std::string& mode) {
  if (mode == "off") return CE_GUARD_OFF;
  if (mode == "warn") return CE_GUARD_WARN;
  if (mode == "refuse") return CE_GUARD_REFUSE;
  throw py::value_error("stability guard mode \"" + mode +
                        "\": use \"off\", \"warn\" or \"refuse\".");
}

}  // namespace

void ErrHandler(int code, const char* module, const char* function, char* msg, void* data) {
  (void)module;
  auto* self = static_cast<Integrator*>(data);
  try {  // nothing may escape into C
    if (code == CE_WARNING) {
      self->warnings_.push_back(std::string(function) + ": " + msg);
    } else {
      self->last_error_ = msg;
    }
  } catch (...) {
  }
}

Integrator::Integrator(py::object f, double t0, py::handle x0, py::handle v0, py::handle method) {
  try {
    Create(std::move(f), t0, x0, v0);
    SetMethod(method);
  } catch (...) {
    Close();
    throw;
  }
}

void Integrator::Create(py::object f, double t0, py::handle x0, py::handle v0) {
  cb_ = std::make_unique<CallbackData>();
  if (py::isinstance<LinearStructure>(f)) {
    cb_->structure = f.cast<std::shared_ptr<LinearStructure>>();
  } else if (PyCallable_Check(f.ptr())) {
    cb_->rhs = f;
  } else {
    throw py::type_error("f must be a callable f(t, x, v, out) or a ceode.LinearStructure.");
  }
  const sunindextype n = cb_->structure ? cb_->structure->size() : -1;
  RealArray x = AsVector(x0, "x0", n);
  RealArray v = AsVector(v0, "v0", x.shape(0));
  if (!std::isfinite(t0)) throw py::value_error("t0 must be finite.");
  cb_->n = x.shape(0);
#if SUNDIALS_VERSION_MAJOR >= 7
  if (SUNContext_Create(SUN_COMM_NULL, &ctx_) != 0) throw std::bad_alloc();
#else
  if (SUNContext_Create(nullptr, &ctx_) != 0) throw std::bad_alloc();
#endif
  x_ = NewVector(x, ctx_);
  v_ = NewVector(v, ctx_);
  mem_ = CEodeCreate(ctx_);
  if (mem_ == nullptr) throw std::bad_alloc();
  Check(CEodeSetErrHandlerFn(mem_, ErrHandler, this));
  Check(CEodeInit(mem_, RhsFn, t0, x_, v_));
  Check(CEodeSetUserData(mem_, cb_.get()));
  t_ = t0;
  if (cb_->structure) AttachStructure();
}

void Integrator::AttachStructure() {
  const LinearStructure& s = *cb_->structure;
  if (s.damped()) Check(CEodeSetVelJacFn(mem_, StructureVelJac));
  if (!s.lumped()) {
    cb_->mass.kind = MassSpec::kSparse;
    cb_->mass.sparse = s.sparse_mass();
    solvers_dirty_ = true;
    return;
  }
  // f returns M^{-1} force: the guard's Lanczos needs the masses for a bound.
  N_Vector m = N_VNew_Serial(cb_->n, ctx_);
  if (m == nullptr) throw std::bad_alloc();
  std::copy(s.lumped_mass().begin(), s.lumped_mass().end(), N_VGetArrayPointer(m));
  const int flag = CEodeSetGuardMass(mem_, m);
  N_VDestroy(m);
  Check(flag);
}

void Integrator::Close() {
  if (busy_) throw std::runtime_error("close() cannot be called from the integrator's callbacks.");
  FreeAll();
}

void Integrator::FreeAll() noexcept {
  if (mem_ != nullptr) CEodeFree(&mem_);
  solvers_.Free();
  if (x_ != nullptr) N_VDestroy(x_);
  if (v_ != nullptr) N_VDestroy(v_);
  x_ = v_ = nullptr;
  if (ctx_ != nullptr) SUNContext_Free(&ctx_);
  ctx_ = nullptr;
  if (cb_) {
    cb_->in.Clear();
    cb_->out.Clear();
  }
}

void* Integrator::mem() {
  if (mem_ == nullptr) RaiseCEodeError(CE_MEM_NULL, "The integrator is closed.");
  if (busy_) {
    throw std::runtime_error("The integrator is running: its callbacks cannot call its methods.");
  }
  return mem_;
}

void Integrator::SetMethod(py::handle method) {
  const MethodSpec s = ParseMethod(method);
  if (!s.name.empty()) {
    Check(CEodeSetMethodByName(mem(), s.name.c_str()));
  } else {
    Check(CEodeSetMethod(mem(), s.degree, s.params.data()));
  }
}

void Integrator::SetFixedStep(double h) { Check(CEodeSetFixedStep(mem(), h)); }

void Integrator::SetTolerances(double rtol, py::handle atol) {
  py::array scalar = py::array::ensure(atol);
  if (scalar && scalar.ndim() == 0) {  // a Python or numpy number
    Check(CEodeSStolerances(mem(), rtol,
                            py::float_(py::reinterpret_borrow<py::object>(atol)).cast<double>()));
    return;
  }
  RealArray a = AsVector(atol, "atol", cb_->n);
  N_Vector av = NewVector(a, ctx_);
  const int flag = CEodeSVtolerances(mem(), rtol, av);
  N_VDestroy(av);
  Check(flag);
}

void Integrator::SetVelocityDependence(bool depends) {
  Check(CEodeSetVelocityDependence(mem(), depends ? SUNTRUE : SUNFALSE));
}

void Integrator::SetStabilityGuard(const std::string& mode, py::handle omega_max, long every) {
  const int m = GuardMode(mode);
  const double omega = omega_max.is_none() ? 0.0 : omega_max.cast<double>();
  Check(CEodeSetStabilityGuard(mem(), m, every));
  Check(CEodeSetMaxFrequency(mem(), omega));
}

double Integrator::GetStableStep(double safety) {
  Prepare();
  sunrealtype h = 0.0;
  int flag = 0;
  {
    BusyScope busy(this);  // the estimate evaluates f
    flag = CEodeGetStableStep(mem_, safety, &h);
  }
  Check(flag);
  return h;
}

// Gershgorin's guaranteed bound on omega_max of a LinearStructure (CEodeGetFrequencyBound):
// K as a CSR SUNSparseMatrix, the lumped masses (or M = I for a sparse M's structure: refused).
double Integrator::GetFrequencyBound() {
  mem();
  if (!cb_->structure || !cb_->structure->lumped()) {
    throw py::value_error("get_frequency_bound needs a LinearStructure with lumped masses.");
  }
  const Csr& K = cb_->structure->stiffness();
  SUNMatrix Km =
      SUNSparseMatrix(K.rows, K.cols, std::max<sunindextype>(1, K.val.size()), CSR_MAT, ctx_);
  N_Vector m = N_VNew_Serial(cb_->n, ctx_);
  if (Km == nullptr || m == nullptr || CopyCsr(K, Km) != 0) {
    if (Km != nullptr) SUNMatDestroy(Km);
    if (m != nullptr) N_VDestroy(m);
    throw std::bad_alloc();
  }
  const std::vector<sunrealtype>& mass = cb_->structure->lumped_mass();
  std::copy(mass.begin(), mass.end(), N_VGetArrayPointer(m));
  sunrealtype omega = 0.0;
  const int flag = CEodeGetFrequencyBound(mem_, Km, m, &omega);
  SUNMatDestroy(Km);
  N_VDestroy(m);
  Check(flag);
  return omega;
}

void Integrator::SetMass(py::handle M, py::handle constant) {
  mem();
  if (cb_->structure) throw py::value_error("a LinearStructure brings its own mass matrix.");
  MassSpec spec = ParseMass(M, constant, cb_->n, t_, CopyVector(x_));
  cb_->mass = std::move(spec);
  solvers_dirty_ = true;
}

void Integrator::SetConstraints(py::object phi, py::object G, long nc) {
  mem();
  if (phi.is_none() && G.is_none()) {
    Check(CEodeSetConstraints(mem(), nullptr, nullptr, nullptr));
    cb_->constr = ConstraintSpec();
    solvers_dirty_ = true;
    return;
  }
  if (!PyCallable_Check(phi.ptr()) || !PyCallable_Check(G.ptr())) {
    throw py::type_error("phi and G must be callables phi(t, x, out) and G(t, x, out).");
  }
  if (nc < 1) throw py::value_error("nc (the number of constraints) must be >= 1.");
  if (cb_->structure && cb_->structure->lumped()) {
    // f returns M^{-1} force there, and the constraint forces G^T lambda need M itself
    throw py::value_error(
        "constraints with a LinearStructure need M as a sparse matrix (scipy.sparse.diags(m)), "
        "not lumped masses.");
  }
  N_Vector tmpl = N_VNew_Serial(nc, ctx_);
  if (tmpl == nullptr) throw std::bad_alloc();
  const int flag = CEodeSetConstraints(mem(), tmpl, PhiFn, PhiJacFn);
  N_VDestroy(tmpl);
  Check(flag);
  cb_->constr = ConstraintSpec{nc, std::move(phi), std::move(G)};
  solvers_dirty_ = true;
}

void Integrator::SetLinearSolver(const std::string& kind) {
  mem();
  if (kind != "dense") throw py::value_error("linear solver \"" + kind + "\": use \"dense\".");
  cb_->dense_solver = true;
  solvers_dirty_ = true;
}

void Integrator::SetImplicitMode(const std::string& mode) {
  int m = CE_IMPLICIT_AUTO;
  if (mode == "newton") {
    m = CE_IMPLICIT_NEWTON;
  } else if (mode == "pc") {
    m = CE_IMPLICIT_PC;
  } else if (mode != "auto") {
    throw py::value_error("implicit mode \"" + mode + "\": use \"auto\", \"newton\" or \"pc\".");
  }
  Check(CEodeSetImplicitMode(mem(), m));
}

// f affine in x' with df/dx' = diag(c): the step's exact one-evaluation solve. None removes it.
void Integrator::SetVelJacDiagonal(py::handle c) {
  if (c.is_none()) {
    Check(CEodeSetVelJacDiagonal(mem(), nullptr));
    return;
  }
  RealArray a = AsVector(c, "c", cb_->n);
  N_Vector cv = NewVector(a, ctx_);
  const int flag = CEodeSetVelJacDiagonal(mem(), cv);
  N_VDestroy(cv);
  Check(flag);
}

void Integrator::SetZeroStart(bool on) { Check(CEodeSetZeroStart(mem(), on ? SUNTRUE : SUNFALSE)); }
void Integrator::SetStopTime(double tstop) { Check(CEodeSetStopTime(mem(), tstop)); }
void Integrator::SetMaxNumSteps(long mxsteps) { Check(CEodeSetMaxNumSteps(mem(), mxsteps)); }

py::dict Integrator::Stats() {
  using Getter = int (*)(void*, long*);
  static const std::pair<const char*, Getter> kCounters[] = {
      {"steps", CEodeGetNumSteps},
      {"rhs_evals", CEodeGetNumRhsEvals},
      {"start_rhs_evals", CEodeGetNumStartRhsEvals},
      {"nonlin_iters", CEodeGetNumNonlinSolvIters},
      {"nonlin_conv_fails", CEodeGetNumNonlinSolvConvFails},
      {"lin_setups", CEodeGetNumLinSolvSetups},
      {"lin_solves", CEodeGetNumLinSolves},
      {"jac_evals", CEodeGetNumJacEvals},
      {"rhs_evals_jac_dq", CEodeGetNumRhsEvalsJacDQ},
      {"mass_evals", CEodeGetNumMassEvals},
      {"constr_evals", CEodeGetNumConstrEvals},
      {"constr_jac_evals", CEodeGetNumConstrJacEvals},
      {"err_test_fails", CEodeGetNumErrTestFails},
      {"stable_step_limited", CEodeGetNumStableStepLimited},
      {"pc_steps", CEodeGetNumPCSteps},
      {"pc_corrections", CEodeGetNumPCCorrections},
  };
  py::dict d;
  for (const auto& [name, get] : kCounters) {
    long value = 0;
    Check(get(mem(), &value));
    d[name] = value;
  }
  long gf = 0, gm = 0, gl = 0;
  Check(CEodeGetGuardStats(mem(), &gf, &gm, &gl));
  d["guard_rhs_evals"] = gf;
  d["guard_mass_evals"] = gm;
  d["guard_lin_setups"] = gl;
  long npc = 0, nnls = 0, ncoupling = 0;
  sunrealtype coupling = 0.0;
  Check(CEodeGetImplicitStats(mem(), &npc, &nnls, &ncoupling, &coupling));
  d["nls_steps"] = nnls;
  d["coupling_rhs_evals"] = ncoupling;
  d["python_calls"] = cb_->python_calls;
  d["time"] = t_;
  return d;
}

}  // namespace ceode_py
