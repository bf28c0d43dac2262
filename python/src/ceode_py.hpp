// The Python module's shared declarations: each record is written by the file named beside it.
#ifndef CEODE_PYTHON_CEODE_PY_HPP_
#define CEODE_PYTHON_CEODE_PY_HPP_

#include <ceode/ceode.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_matrix.h>

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace ceode_py {

namespace py = pybind11;
using RealArray = py::array_t<sunrealtype, py::array::c_style | py::array::forcecast>;

// ---- errors.cpp ------------------------------------------------------------------------
void RegisterErrors(py::module_& m);
// Raises ceode.CEodeError(flag, flag name, message).
[[noreturn]] void RaiseCEodeError(int flag, const std::string& message);
// The CEodeError instance itself (for chaining it to a callback's exception).
py::object MakeCEodeError(int flag, const std::string& message);
// Emits collected CEODE warnings as ceode.CEodeWarning.
void EmitWarnings(std::vector<std::string>* warnings);

// ---- methods.cpp -----------------------------------------------------------------------
struct MethodSpec {
  int degree = 0;
  std::vector<sunrealtype> params;  // degree - 1 values
  std::string name;                 // empty for a parameter sequence
};
// A set name or a sequence of parameters; TypeError for anything else, CEodeError for an
// unknown name.
MethodSpec ParseMethod(py::handle method);
void RegisterMethods(py::module_& m);

// ---- views.cpp: numpy arrays over CEODE's own data, without copies ---------------------
// Views are cached by data pointer: CEODE passes the same few vectors again and again.
class ViewCache {
 public:
  explicit ViewCache(bool writable) : writable_(writable) {}
  py::array Vector(sunrealtype* data, sunindextype n);
  // A column-major (rows x cols) matrix, as SUNDenseMatrix stores it.
  py::array Matrix(sunrealtype* data, sunindextype rows, sunindextype cols);
  void Clear() { entries_.clear(); }

 private:
  struct Entry {
    const sunrealtype* data;
    sunindextype rows, cols;
    py::array view;
  };
  const py::array* Find(const sunrealtype* data, sunindextype rows, sunindextype cols) const;
  py::array Add(py::array view, sunrealtype* data, sunindextype rows, sunindextype cols);
  bool writable_;
  std::vector<Entry> entries_;
};
// A copy of an N_Vector's data as a new numpy array.
py::array_t<sunrealtype> CopyVector(N_Vector v);
// x0/v0/atol checks: a 1-D float array of length n (n < 0: any length >= 1).
RealArray AsVector(py::handle obj, const char* what, sunindextype n);

// ---- structure.cpp: M a = force(t) - K x - C v in C++ ----------------------------------
struct Csr {
  sunindextype rows = 0, cols = 0;
  std::vector<sunindextype> ptr, idx;
  std::vector<sunrealtype> val;
};
Csr ToCsr(py::handle matrix, const char* what);
// The arrays the right-hand side loops over: 32-bit indices move less memory per entry.
struct Csr32 {
  std::vector<int32_t> ptr, idx;
  std::vector<sunrealtype> val;
};
bool IsSparse(py::handle obj);
class LinearStructure {
 public:
  LinearStructure(py::object M, py::object K, py::object C, py::object force);
  sunindextype size() const { return n_; }
  bool lumped() const { return sparse_mass_.rows == 0; }
  bool damped() const { return C_.rows > 0; }
  bool has_force() const { return !force_.is_none(); }
  const std::vector<sunrealtype>& lumped_mass() const { return mass_; }
  const Csr& sparse_mass() const { return sparse_mass_; }
  const Csr& damping() const { return C_; }
  // out = M^{-1} (force - K x - C v) for a lumped M, force - K x - C v otherwise.
  void Evaluate(const sunrealtype* x, const sunrealtype* v, sunrealtype* out) const;
  const py::object& force() const { return force_; }

 private:
  sunindextype n_ = 0;
  std::vector<sunrealtype> mass_, inv_mass_;
  Csr sparse_mass_, K_, C_;
  Csr32 k32_, c32_;
  py::object force_;
};
void RegisterStructure(py::module_& m);

// ---- callbacks.cpp: the C trampolines and the exception they stash ---------------------
struct MassSpec {
  enum Kind { kNone, kDense, kSparse } kind = kNone;
  py::object callable = py::none();  // M(t, x) -> matrix, or None for a constant one
  std::vector<sunrealtype> dense;    // constant dense M, column-major
  Csr sparse;                        // constant sparse M (or the first value of a callable)
  bool constant = true;
};
struct ConstraintSpec {
  sunindextype nc = 0;
  py::object phi = py::none(), jac = py::none();  // phi(t, x, out), G(t, x, out): (nc, n)
};
struct CallbackData {
  sunindextype n = 0;
  py::object rhs = py::none();                 // f(t, x, v, out), or None
  std::shared_ptr<LinearStructure> structure;  // or the right-hand side in C++
  MassSpec mass;
  ConstraintSpec constr;
  py::object roots = py::none();  // g(t, x, v, gout), or None
  int nroots = 0;
  ViewCache in{false}, out{true};
  long python_calls = 0;
  // The first exception a callback raised; CEODE is stopped by the failing return.
  std::unique_ptr<py::error_already_set> pending;
  // Runs body, stashing an exception; 0 on success, -1 after a failure.
  template <class Body>
  int Guard(Body&& body);
};
int RhsFn(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, void* user_data);
int StructureVelJac(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, SUNMatrix J, void* user_data,
                    N_Vector t1, N_Vector t2, N_Vector t3);

// ---- mass.cpp --------------------------------------------------------------------------
MassSpec ParseMass(py::handle M, py::handle constant, sunindextype n, sunrealtype t0,
                   py::handle x0);
int MassFn(sunrealtype t, N_Vector x, SUNMatrix M, void* user_data, N_Vector t1, N_Vector t2,
           N_Vector t3);
// Copies a sparse matrix into a CSR SUNSparseMatrix (growing it when needed).
int CopyCsr(const Csr& A, SUNMatrix M);
// The matrices and solver a configuration needs; owned by the Integrator.
struct SolverSet {
  SUNMatrix M = nullptr, A = nullptr;
  SUNLinearSolver LS = nullptr;
  void Free();
};
// Attaches the mass matrix and a linear solver (dense, or KLU for a sparse M).
int AttachSolvers(void* mem, SUNContext ctx, const CallbackData& cb, SolverSet* set);

// ---- constraints.cpp -------------------------------------------------------------------
int PhiFn(sunrealtype t, N_Vector x, N_Vector phi, void* user_data);
int PhiJacFn(sunrealtype t, N_Vector x, SUNMatrix G, void* user_data);

// ---- roots.cpp -------------------------------------------------------------------------
int RootFn(sunrealtype t, N_Vector x, N_Vector v, sunrealtype* gout, void* user_data);

// ---- integrator.cpp, integrator_run.cpp ------------------------------------------------
void RegisterIntegrator(py::module_& m);

template <class Body>
int CallbackData::Guard(Body&& body) {
  if (pending) return -1;  // an earlier callback failed: stop without calling Python again
  try {
    body();
    return 0;
  } catch (py::error_already_set& e) {
    pending = std::make_unique<py::error_already_set>(std::move(e));
  } catch (const py::builtin_exception& e) {
    e.set_error();
    pending = std::make_unique<py::error_already_set>();
  } catch (const std::exception& e) {
    PyErr_SetString(PyExc_RuntimeError, e.what());
    pending = std::make_unique<py::error_already_set>();
  }
  return -1;
}

}  // namespace ceode_py

#endif  // CEODE_PYTHON_CEODE_PY_HPP_
