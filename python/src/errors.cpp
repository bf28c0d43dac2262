// Errors: every negative CEODE flag becomes ceode.CEodeError(flag, flag_name, message).
#include <ceode/ceode.h>

#include <cstdlib>

#include "ceode_py.hpp"

namespace ceode_py {

namespace {

// CEodeGetReturnFlagName's string is the caller's to free, as CVODE's is.
std::string FlagName(long flag) {
  char* name = CEodeGetReturnFlagName(flag);
  std::string out = name != nullptr ? name : "CE_UNKNOWN";
  std::free(name);
  return out;
}

}  // namespace

py::object MakeCEodeError(int flag, const std::string& message) {
  py::object cls = py::module_::import("ceode._errors").attr("CEodeError");
  return cls(flag, FlagName(flag), message);
}

void RaiseCEodeError(int flag, const std::string& message) {
  py::object err = MakeCEodeError(flag, message);
  PyErr_SetObject(err.get_type().ptr(), err.ptr());
  throw py::error_already_set();
}

void EmitWarnings(std::vector<std::string>* warnings) {
  if (warnings->empty()) return;
  std::vector<std::string> list;
  list.swap(*warnings);
  py::object cls = py::module_::import("ceode._errors").attr("CEodeWarning");
  for (const std::string& w : list) {
    if (PyErr_WarnEx(cls.ptr(), w.c_str(), 2) != 0) throw py::error_already_set();
  }
}

void RegisterErrors(py::module_& m) {
  m.def(
      "flag_name", [](long flag) { return FlagName(flag); }, py::arg("flag"),
      "The name of a CEODE return flag (CEodeGetReturnFlagName).");
}

}  // namespace ceode_py
