// Index-3 constraints: the saddle-point Newton solve of method.md section 3.
#include "ceode_impl.hpp"

namespace ceode {

bool HasConstraints(const CEodeMemRec* ce) { return ce->phifn != nullptr; }

int ConstrInitialize(CEodeMemRec* ce, const char* func) {
  if (!HasConstraints(ce)) return CE_SUCCESS;
  return ProcessError(ce, CE_ILL_INPUT, func, "Constraints are not implemented yet.");
}

int ConstrStart(CEodeMemRec* ce, const char* func) {
  return ProcessError(ce, CE_ILL_INPUT, func, "Constraints are not implemented yet.");
}

int ConstrSolveStep(CEodeMemRec* ce, sunrealtype, N_Vector, N_Vector, const char* func) {
  return ProcessError(ce, CE_ILL_INPUT, func, "Constraints are not implemented yet.");
}

void ConstrFree(CEodeMemRec* /*ce*/) {}

}  // namespace ceode

extern "C" {

int CEodeSetConstraints(void* mem, N_Vector phi_template, CEodeConstrFn phi, CEodeConstrJacFn G) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  (void)phi_template;
  (void)phi;
  (void)G;
  return ceode::ProcessError(ce, CE_ILL_INPUT, __func__, "Constraints are not implemented yet.");
}

int CEodeGetMultipliers(void* mem, N_Vector lambda) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  (void)lambda;
  return ceode::ProcessError(ce, CE_ILL_INPUT, __func__, "Constraints are not implemented yet.");
}

}  // extern "C"
