// ceode.Integrator: one CEODE memory, its SUNContext and its vectors, owned by the object and
// freed by close() or when the object is collected.
#ifndef CEODE_PYTHON_INTEGRATOR_HPP_
#define CEODE_PYTHON_INTEGRATOR_HPP_

#include <string>
#include <vector>

#include "ceode_py.hpp"

namespace ceode_py {

class Integrator {
 public:
  Integrator(py::object f, double t0, py::handle x0, py::handle v0, py::handle method);
  ~Integrator() { FreeAll(); }
  Integrator(const Integrator&) = delete;
  Integrator& operator=(const Integrator&) = delete;
  void Close();

  // integrator.cpp: options
  void SetMethod(py::handle method);
  void SetFixedStep(double h);
  void SetTolerances(double rtol, py::handle atol);
  void SetVelocityDependence(bool depends);
  void SetStabilityGuard(const std::string& mode, py::handle omega_max, long every);
  double GetStableStep(double safety);
  double GetFrequencyBound();
  void SetMass(py::handle M, py::handle constant);
  void SetConstraints(py::object phi, py::object G, long nc);
  void SetLinearSolver(const std::string& kind);
  void SetImplicitMode(const std::string& mode);
  void SetVelJacDiagonal(py::handle c);
  void SetZeroStart(bool on);
  void SetStopTime(double tstop);
  void SetMaxNumSteps(long mxsteps);
  py::dict Stats();
  // roots.cpp: events
  void SetRoots(py::object g, int nrtfn, py::handle direction);
  py::array_t<int> RootInfo();
  int last_flag() const { return last_flag_; }
  sunindextype size() const { return cb_->n; }
  double time() const { return t_; }

  // integrator_run.cpp: solving
  py::tuple Evolve(double tout, bool one_step);
  py::tuple EvolveMany(py::handle times);
  void Reinit(double t0, py::handle x0, py::handle v0);
  py::array_t<sunrealtype> Accel();
  py::array_t<sunrealtype> Multipliers();
  // Raises CEodeError for flag < 0 and a callback's exception (chained to it) first.
  void Check(int flag);
  // CEodeError(CE_MEM_NULL) once closed; RuntimeError from inside the integrator's own
  // callbacks (CEODE's calls are not re-entrant).
  void* mem();

  // The GC's view of the Python objects held (tp_traverse, tp_clear).
  int Traverse(visitproc visit, void* arg);
  void ClearReferences();

 private:
  friend void ErrHandler(int, const char*, const char*, char*, void*);
  friend class BusyScope;
  void Create(py::object f, double t0, py::handle x0, py::handle v0);
  void AttachStructure();
  void FreeAll() noexcept;
  void Prepare();
  std::string Message();
  [[noreturn]] void RaisePending(int flag);
  int EvolveOnce(double tout, int itask);
  bool PythonFree() const;

  SUNContext ctx_ = nullptr;
  void* mem_ = nullptr;
  N_Vector x_ = nullptr, v_ = nullptr;
  std::unique_ptr<CallbackData> cb_;  // user_data: its address stays fixed
  SolverSet solvers_;
  bool solvers_dirty_ = false;
  double t_ = 0.0;
  int last_flag_ = 0;
  bool busy_ = false;  // inside a C call that runs callbacks
  std::vector<std::string> warnings_;
  std::string last_error_;
};

// Marks the integrator busy while CEODE runs its callbacks.
class BusyScope {
 public:
  explicit BusyScope(Integrator* self) : self_(self) { self_->busy_ = true; }
  ~BusyScope() { self_->busy_ = false; }
  BusyScope(const BusyScope&) = delete;
  BusyScope& operator=(const BusyScope&) = delete;

 private:
  Integrator* self_;
};

void ErrHandler(int code, const char* module, const char* function, char* msg, void* data);

}  // namespace ceode_py

#endif  // CEODE_PYTHON_INTEGRATOR_HPP_
