// ceode.Integrator: evolve, evolve_many, reinit and the error path. A callback's exception
// reaches the caller as itself, with the CEodeError of the stopped call as its __context__.
#include <nvector/nvector_serial.h>

#include <cmath>
#include <string>

#include "integrator.hpp"

namespace ceode_py {

std::string Integrator::Message() {
  std::string msg;
  msg.swap(last_error_);
  const char* last = nullptr;
  if (msg.empty() && mem_ != nullptr && CEodeGetLastErrorMessage(mem_, &last) == CE_SUCCESS) {
    msg = last;
  }
  return msg;
}

void Integrator::RaisePending(int flag) {
  std::unique_ptr<py::error_already_set> err = std::move(cb_->pending);
  warnings_.clear();
  std::string msg = flag < 0 ? Message() : "A callback raised an exception.";
  py::object cee = MakeCEodeError(flag < 0 ? flag : CE_RHSFUNC_FAIL, msg);
  py::setattr(err->value(), "__context__", cee);
  err->restore();
  throw py::error_already_set();
}

void Integrator::Check(int flag) {
  if (cb_ && cb_->pending) RaisePending(flag);
  if (flag >= 0) {
    last_error_.clear();
    EmitWarnings(&warnings_);
    return;
  }
  std::string msg = Message();
  try {  // the warnings that led up to the failure explain it
    EmitWarnings(&warnings_);
  } catch (py::error_already_set&) {  // warnings raised as errors: the CEodeError is the one
  }
  RaiseCEodeError(flag, msg);
}

bool Integrator::PythonFree() const {
  return cb_->structure && !cb_->structure->has_force() && cb_->mass.callable.is_none() &&
         cb_->constr.nc == 0;
}

void Integrator::Prepare() {
  mem();
  if (!solvers_dirty_) return;
  Check(AttachSolvers(mem_, ctx_, *cb_, &solvers_));
  solvers_dirty_ = false;
}

int Integrator::EvolveOnce(double tout, int itask) {
  sunrealtype tret = t_;
  int flag = 0;
  BusyScope busy(this);
  if (PythonFree()) {
    py::gil_scoped_release nogil;  // no Python is called: other threads may run
    flag = CEodeEvolve(mem_, tout, x_, v_, &tret, itask);
  } else {
    flag = CEodeEvolve(mem_, tout, x_, v_, &tret, itask);
  }
  t_ = tret;
  last_flag_ = flag;
  return flag;
}

py::tuple Integrator::Evolve(double tout, bool one_step) {
  Prepare();
  if (!std::isfinite(tout)) throw py::value_error("tout must be finite.");
  Check(EvolveOnce(tout, one_step ? CE_ONE_STEP : CE_NORMAL));
  return py::make_tuple(t_, CopyVector(x_), CopyVector(v_));
}

py::tuple Integrator::EvolveMany(py::handle times) {
  Prepare();
  RealArray ts = AsVector(times, "times", -1);
  const py::ssize_t m = ts.shape(0), n = cb_->n;
  for (py::ssize_t i = 0; i < m; ++i) {
    if (!std::isfinite(ts.at(i))) throw py::value_error("times must be finite.");
    if (i > 0 && ts.at(i) < ts.at(i - 1)) throw py::value_error("times must not decrease.");
  }
  py::array_t<sunrealtype> X({m, n}), V({m, n});
  for (py::ssize_t i = 0; i < m; ++i) {
    Check(EvolveOnce(ts.at(i), CE_NORMAL));
    std::copy(N_VGetArrayPointer(x_), N_VGetArrayPointer(x_) + n, X.mutable_data(i, 0));
    std::copy(N_VGetArrayPointer(v_), N_VGetArrayPointer(v_) + n, V.mutable_data(i, 0));
  }
  return py::make_tuple(X, V);
}

void Integrator::Reinit(double t0, py::handle x0, py::handle v0) {
  mem();
  RealArray x = AsVector(x0, "x0", cb_->n);
  RealArray v = AsVector(v0, "v0", cb_->n);
  if (!std::isfinite(t0)) throw py::value_error("t0 must be finite.");
  std::copy(x.data(), x.data() + cb_->n, N_VGetArrayPointer(x_));
  std::copy(v.data(), v.data() + cb_->n, N_VGetArrayPointer(v_));
  cb_->pending.reset();
  cb_->python_calls = 0;
  last_error_.clear();
  warnings_.clear();
  Check(CEodeReInit(mem_, t0, x_, v_));
  t_ = t0;
}

py::array_t<sunrealtype> Integrator::Accel() {
  mem();
  N_Vector a = N_VClone(x_);
  if (a == nullptr) throw std::bad_alloc();
  const int flag = CEodeGetAccel(mem(), a);
  py::array_t<sunrealtype> out = CopyVector(a);
  N_VDestroy(a);
  Check(flag);
  return out;
}

py::array_t<sunrealtype> Integrator::Multipliers() {
  mem();
  if (cb_->constr.nc == 0) throw py::value_error("no constraints are set.");
  N_Vector lam = N_VNew_Serial(cb_->constr.nc, ctx_);
  if (lam == nullptr) throw std::bad_alloc();
  const int flag = CEodeGetMultipliers(mem(), lam);
  py::array_t<sunrealtype> out = CopyVector(lam);
  N_VDestroy(lam);
  Check(flag);
  return out;
}

int Integrator::Traverse(visitproc visit, void* arg) {
  if (!cb_) return 0;
  for (PyObject* o : {cb_->rhs.ptr(), cb_->mass.callable.ptr(), cb_->constr.phi.ptr(),
                      cb_->constr.jac.ptr(), cb_->roots.ptr()}) {
    const int r = o != nullptr ? visit(o, arg) : 0;
    if (r != 0) return r;
  }
  return 0;
}

void Integrator::ClearReferences() {
  if (!cb_) return;
  cb_->roots = py::none();
  cb_->rhs = py::none();
  cb_->mass.callable = py::none();
  cb_->constr.phi = py::none();
  cb_->constr.jac = py::none();
}

}  // namespace ceode_py
