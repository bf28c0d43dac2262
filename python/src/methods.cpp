// Method sets and the stability analysis: methods(), method_order(), stability_limit(),
// spectral_radius(), version(). Memory-free C functions return bare flags; the messages
// here name the cause.
#include <ceode/ceode.h>
#include <ceode/ceode_stability.h>
#include <pybind11/stl.h>

#include <string>

#include "ceode_py.hpp"

namespace ceode_py {

namespace {

constexpr int kMaxParams = 16;

std::string KnownNames() {
  std::string known;
  for (int i = 0; i < CEodeGetNumMethods(); ++i) {
    if (i > 0) known += ", ";
    known += CEodeGetMethodName(i);
  }
  return known;
}

MethodSpec ParseName(const std::string& name) {
  MethodSpec spec;
  spec.params.resize(kMaxParams);
  if (CEodeGetMethodParams(name.c_str(), &spec.degree, spec.params.data(), kMaxParams) < 0) {
    RaiseCEodeError(CE_ILL_INPUT,
                    "Unknown method name \"" + name + "\"; known names: " + KnownNames() + ".");
  }
  spec.params.resize(spec.degree - 1);
  spec.name = name;
  return spec;
}

py::list Methods() {
  py::list out;
  for (int i = 0; i < CEodeGetNumMethods(); ++i) out.append(CEodeGetMethodName(i));
  return out;
}

int MethodOrder(py::handle method) {
  const MethodSpec s = ParseMethod(method);
  int px = 0, pv = 0;
  const int flag = CEodeMethodOrder(s.degree, s.params.data(), &px, &pv);
  if (flag < 0) RaiseCEodeError(flag, "CEodeMethodOrder refused these parameters.");
  return px;
}

double StabilityLimit(py::handle method, double xi) {
  const MethodSpec s = ParseMethod(method);
  sunrealtype omega = 0.0;
  const int flag = CEodeStabilityLimit(s.degree, s.params.data(), xi, &omega);
  if (flag < 0) {
    RaiseCEodeError(flag, "CEodeStabilityLimit refused the input (xi must be finite and >= 0).");
  }
  return omega;
}

// Omega a float: a float; Omega an array: an array of the same shape (one setup for all).
py::object SpectralRadius(py::handle method, py::handle Omega, double xi) {
  const MethodSpec s = ParseMethod(method);
  const bool scalar = PyFloat_Check(Omega.ptr()) || PyLong_Check(Omega.ptr());
  RealArray om = RealArray::ensure(Omega);
  if (!om) throw py::type_error("Omega must be a float or an array of floats.");
  py::array_t<sunrealtype> rho(std::vector<py::ssize_t>(om.shape(), om.shape() + om.ndim()));
  const int flag = CEodeSpectralRadii(s.degree, s.params.data(), xi, static_cast<int>(om.size()),
                                      om.data(), rho.mutable_data());
  if (flag < 0) {
    RaiseCEodeError(flag, "CEodeSpectralRadii refused the input (Omega and xi must be finite).");
  }
  if (scalar) return py::float_(rho.data()[0]);
  return std::move(rho);
}

py::tuple MethodParams(py::handle method) {
  const MethodSpec s = ParseMethod(method);
  return py::make_tuple(s.degree, py::cast(s.params));
}

std::string Version() {
  char buf[64];
  CEodeGetVersion(buf, sizeof(buf));
  return buf;
}

}  // namespace

MethodSpec ParseMethod(py::handle method) {
  if (py::isinstance<py::str>(method)) return ParseName(method.cast<std::string>());
  if (!py::isinstance<py::sequence>(method) && !py::isinstance<py::array>(method)) {
    throw py::type_error("method must be a set name (ceode.methods()) or a sequence of floats.");
  }
  RealArray p = RealArray::ensure(method);
  if (!p || p.ndim() != 1 || p.size() < 2 || p.size() > kMaxParams) {
    throw py::value_error("method parameters: a 1-D sequence of 2 to 16 floats (degree - 1).");
  }
  MethodSpec spec;
  spec.params.assign(p.data(), p.data() + p.size());
  spec.degree = static_cast<int>(p.size()) + 1;
  return spec;
}

void RegisterMethods(py::module_& m) {
  m.def("methods", &Methods, "The names of CEODE's parameter sets.");
  m.def("method_order", &MethodOrder, py::arg("method"),
        "The order in x of a set (a name or a parameter sequence).");
  m.def("stability_limit", &StabilityLimit, py::arg("method"), py::arg("xi") = 0.0,
        "Omega_max: the largest omega*h with spectral radius <= 1 (0: unstable for every step).");
  m.def("spectral_radius", &SpectralRadius, py::arg("method"), py::arg("Omega"),
        py::arg("xi") = 0.0, "Spectral radius of the amplification matrix at Omega = omega*h.");
  m.def("method_params", &MethodParams, py::arg("method"),
        "(degree, [alpha, beta, ...]): a set's degree and its degree - 1 parameters.");
  m.def("version", &Version, "The library's version string (CEodeGetVersion).");
}

}  // namespace ceode_py
