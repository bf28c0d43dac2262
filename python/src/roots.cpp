// Root finding (events), as CVODE's: g(t, x, v, gout) writes the nrtfn event functions into a
// view of CEODE's own array; evolve stops at the earliest root (last_flag == CE_ROOT_RETURN)
// and root_info() tells which functions crossed zero and in which direction.
#include <string>

#include "integrator.hpp"

namespace ceode_py {

int RootFn(sunrealtype t, N_Vector x, N_Vector v, sunrealtype* gout, void* user_data) {
  auto* cb = static_cast<CallbackData*>(user_data);
  return cb->Guard([&] {
    ++cb->python_calls;
    cb->roots(t, cb->in.Vector(N_VGetArrayPointer(x), cb->n),
              cb->in.Vector(N_VGetArrayPointer(v), cb->n), cb->out.Vector(gout, cb->nroots));
  });
}

void Integrator::SetRoots(py::object g, int nrtfn, py::handle direction) {
  mem();
  if (g.is_none() || nrtfn == 0) {
    Check(CEodeRootInit(mem_, 0, nullptr));
    cb_->roots = py::none();
    cb_->nroots = 0;
    return;
  }
  if (!PyCallable_Check(g.ptr())) throw py::type_error("g must be a callable g(t, x, v, gout).");
  if (nrtfn < 0) throw py::value_error("nrtfn must be >= 0.");
  std::vector<int> dir;
  if (!direction.is_none()) {
    py::array_t<int, py::array::c_style | py::array::forcecast> d =
        py::array_t<int, py::array::c_style | py::array::forcecast>::ensure(direction);
    if (!d || d.ndim() != 1 || d.shape(0) != nrtfn) {
      throw py::value_error("direction must hold nrtfn = " + std::to_string(nrtfn) +
                            " values of -1, 0 or +1.");
    }
    dir.assign(d.data(), d.data() + nrtfn);
  }
  Check(CEodeRootInit(mem_, nrtfn, RootFn));
  cb_->roots = std::move(g);
  cb_->nroots = nrtfn;
  if (!dir.empty()) Check(CEodeSetRootDirection(mem_, dir.data()));
}

py::array_t<int> Integrator::RootInfo() {
  mem();
  py::array_t<int> info(cb_->nroots);
  if (cb_->nroots > 0) Check(CEodeGetRootInfo(mem_, info.mutable_data()));
  return info;
}

}  // namespace ceode_py
