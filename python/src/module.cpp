// The extension ceode._ceode: the Integrator's Python interface and the module's contents.
// The package ceode (python/ceode/__init__.py) re-exports them.
#include "integrator.hpp"

namespace ceode_py {

namespace {

// The Integrator takes part in garbage collection: a right-hand side that refers back to its
// integrator (a bound method, a closure) forms a cycle the collector can free.
void GcSupport(PyHeapTypeObject* heap_type) {
  PyTypeObject* type = &heap_type->ht_type;
  type->tp_flags |= Py_TPFLAGS_HAVE_GC;
  type->tp_traverse = [](PyObject* self, visitproc visit, void* arg) -> int {
#if PY_VERSION_HEX >= 0x03090000
    Py_VISIT(Py_TYPE(self));
#endif
    auto vh = reinterpret_cast<py::detail::instance*>(self)->get_value_and_holder();
    if (!vh.holder_constructed()) return 0;
    return vh.value_ptr<Integrator>()->Traverse(visit, arg);
  };
  type->tp_clear = [](PyObject* self) -> int {
    auto vh = reinterpret_cast<py::detail::instance*>(self)->get_value_and_holder();
    if (vh.holder_constructed()) vh.value_ptr<Integrator>()->ClearReferences();
    return 0;
  };
}

void DefineOptions(py::class_<Integrator>& c) {
  c.def("set_method", &Integrator::SetMethod, py::arg("method"))
      .def("set_fixed_step", &Integrator::SetFixedStep, py::arg("h"))
      .def("set_tolerances", &Integrator::SetTolerances, py::arg("rtol"), py::arg("atol"))
      .def("set_velocity_dependence", &Integrator::SetVelocityDependence, py::arg("flag"))
      .def("set_stability_guard", &Integrator::SetStabilityGuard, py::arg("mode") = "warn",
           py::arg("omega_max") = py::none(), py::arg("every") = 0)
      .def("get_stable_step", &Integrator::GetStableStep, py::arg("safety") = 0.0)
      .def("get_frequency_bound", &Integrator::GetFrequencyBound)
      .def("set_mass", &Integrator::SetMass, py::arg("M"), py::arg("constant") = py::none())
      .def("set_constraints", &Integrator::SetConstraints, py::arg("phi"), py::arg("G"),
           py::arg("nc"))
      .def("set_linear_solver", &Integrator::SetLinearSolver, py::arg("kind") = "dense")
      .def("set_implicit_mode", &Integrator::SetImplicitMode, py::arg("mode"))
      .def("set_vel_jac_diagonal", &Integrator::SetVelJacDiagonal, py::arg("c"))
      .def("set_zero_start", &Integrator::SetZeroStart, py::arg("flag"))
      .def("set_stop_time", &Integrator::SetStopTime, py::arg("tstop"))
      .def("set_max_num_steps", &Integrator::SetMaxNumSteps, py::arg("mxsteps"))
      .def("set_roots", &Integrator::SetRoots, py::arg("g"), py::arg("nrtfn"),
           py::arg("direction") = py::none());
}

void DefineSolving(py::class_<Integrator>& c) {
  c.def("evolve", &Integrator::Evolve, py::arg("tout"), py::arg("one_step") = false)
      .def("evolve_many", &Integrator::EvolveMany, py::arg("times"))
      .def("reinit", &Integrator::Reinit, py::arg("t0"), py::arg("x0"), py::arg("v0"))
      .def("stats", &Integrator::Stats)
      .def("get_accel", &Integrator::Accel)
      .def("get_multipliers", &Integrator::Multipliers)
      .def("close", &Integrator::Close)
      .def("__enter__", [](py::object self) { return self; })
      .def("__exit__", [](Integrator& self, py::args) { self.Close(); })
      .def_property_readonly("n", &Integrator::size)
      .def("root_info", &Integrator::RootInfo)
      .def_property_readonly("last_flag", &Integrator::last_flag)
      .def_property_readonly("t", &Integrator::time);
}

}  // namespace

void RegisterIntegrator(py::module_& m) {
  py::class_<Integrator> c(m, "Integrator", py::custom_type_setup(GcSupport),
                           "CEODE's integrator for M x'' = f(t, x, x') (docs/python.md).");
  c.def(py::init<py::object, double, py::handle, py::handle, py::handle>(), py::arg("f"),
        py::arg("t0"), py::arg("x0"), py::arg("v0"), py::arg("method") = "G4_A34");
  DefineOptions(c);
  DefineSolving(c);
}

}  // namespace ceode_py

PYBIND11_MODULE(_ceode, m) {
  m.doc() = "CEODE's compiled core; import the package ceode instead.";
  ceode_py::RegisterErrors(m);
  ceode_py::RegisterMethods(m);
  ceode_py::RegisterStructure(m);
  ceode_py::RegisterIntegrator(m);
}
