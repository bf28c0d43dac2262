// Optional inputs and outputs, statistics and flag names.
#include <cmath>
#include <cstdlib>
#include <cstring>

#include "ceode_impl.hpp"

using ceode::Access;
using ceode::BuildPlans;
using ceode::ProcessError;
using ceode::Restart;

namespace {

template <typename T>
int GetCounter(void* mem, const char* func, T* out, T CEodeMemRec::*field) {
  CEodeMemRec* ce = nullptr;
  const int flag = Access(mem, func, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (out == nullptr) return ProcessError(ce, CE_ILL_INPUT, func, "The output pointer is NULL.");
  *out = ce->*field;
  return CE_SUCCESS;
}

}  // namespace

extern "C" {

int CEodeSetMethod(void* mem, int degree, const sunrealtype* params) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  char why[512];
  if (ceode::ValidateMethodParams(degree, params, why, sizeof(why)) != CE_SUCCESS)
    return ProcessError(ce, CE_ILL_INPUT, __func__, "%s.", why);
  ce->degree = degree;
  for (int i = 0; i < ceode::kMaxDegree; ++i) ce->params[i] = i < degree - 1 ? params[i] : 0;
  ce->pc_k_default = ceode::DefaultPCCorrections(degree, params);
  try {
    ce->method_name = "custom G" + std::to_string(degree);
  } catch (...) {
    return ProcessError(ce, CE_MEM_FAIL, __func__, "Out of memory.");
  }
  ce->omega_limit = 0;
  Restart(ce);
  return CE_SUCCESS;
}

int CEodeSetMethodByName(void* mem, const char* name) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  const ceode::MethodSet* m = ceode::FindMethodSet(name);
  if (m == nullptr) {
    char known[512] = "";
    for (int i = 0; i < ceode::NumMethodSets(); ++i) {
      std::strncat(known, i ? ", " : "", sizeof(known) - std::strlen(known) - 1);
      std::strncat(known, ceode::MethodSetAt(i).name, sizeof(known) - std::strlen(known) - 1);
    }
    return ProcessError(ce, CE_ILL_INPUT, __func__, "Unknown method name \"%s\"; known names: %s.",
                        name ? name : "(null)", known);
  }
  flag = CEodeSetMethod(mem, m->degree, m->params.data());
  if (flag == CE_SUCCESS) ce->method_name = m->name;  // short names: no allocation (SSO)
  return flag;
}

int CEodeGetMethodParams(const char* name, int* degree, sunrealtype* params, int max_params) {
  const ceode::MethodSet* m = ceode::FindMethodSet(name);
  if (m == nullptr || degree == nullptr) return CE_ILL_INPUT;
  *degree = m->degree;
  if (params != nullptr) {
    if (max_params < m->degree - 1) return CE_ILL_INPUT;
    for (int i = 0; i < m->degree - 1; ++i) params[i] = m->params[i];
  }
  return CE_SUCCESS;
}

int CEodeGetNumMethods(void) { return ceode::NumMethodSets(); }

const char* CEodeGetMethodName(int index) {
  if (index < 0 || index >= ceode::NumMethodSets()) return nullptr;
  return ceode::MethodSetAt(index).name;
}

int CEodeSetZeroStart(void* mem, sunbooleantype zero_start) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  ce->zero_start = zero_start != SUNFALSE;
  Restart(ce);
  return CE_SUCCESS;
}

int CEodeSetCompensatedSummation(void* mem, sunbooleantype on) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  ce->compensated = on != SUNFALSE;
  Restart(ce);  // the compensation vectors start from zero with the history
  return CE_SUCCESS;
}

int CEodeSetFusedKernel(void* mem, sunbooleantype on) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  ce->fused = on != SUNFALSE;
  if (ce->started) BuildPlans(ce);  // in-place plans run on the fused kernel only
  return CE_SUCCESS;
}

int CEodeSetInPlaceUpdate(void* mem, sunbooleantype on) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  ce->in_place = on != SUNFALSE;
  if (ce->started) BuildPlans(ce);  // from the current vectors: the run goes on unchanged
  return CE_SUCCESS;
}

int CEodeSetFixedStep(void* mem, sunrealtype h) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (!(h > 0) || !std::isfinite(h)) {
    return ProcessError(ce, CE_ILL_INPUT, __func__,
                        "h = %g: the fixed step must be positive and finite.",
                        static_cast<double>(h));
  }
  if (h != ce->h) Restart(ce);
  ce->h = h;
  return CE_SUCCESS;
}

int CEodeSetVelocityDependence(void* mem, sunbooleantype depends) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  // CE_VELOCITY_DETECT: the start decides (ceode_pc.cpp); any other nonzero value declares it.
  ce->vel_request = depends;
  ce->vel_dependent = depends != SUNFALSE && depends != CE_VELOCITY_DETECT;
  ce->vel_checked_f = nullptr;
  Restart(ce);
  return CE_SUCCESS;
}

int CEodeSetUserData(void* mem, void* user_data) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  ce->user_data = user_data;
  return CE_SUCCESS;
}

int CEodeSetStopTime(void* mem, sunrealtype tstop) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (!std::isfinite(tstop))
    return ProcessError(ce, CE_ILL_INPUT, __func__, "tstop is not finite.");
  ce->tstop = tstop;
  ce->tstop_set = true;
  return CE_SUCCESS;
}

int CEodeClearStopTime(void* mem) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  ce->tstop_set = false;
  return CE_SUCCESS;
}

int CEodeSetMaxNumSteps(void* mem, long int mxsteps) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  // CEODE's own rule: a non-positive value restores the default (CVODE restores it for 0 and
  // disables the test for a negative value).
  ce->mxstep = mxsteps > 0 ? mxsteps : ceode::kDefaultMaxSteps;
  return CE_SUCCESS;
}

int CEodeSetMaxNonlinIters(void* mem, int maxcor) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (maxcor < 1) {
    return ProcessError(ce, CE_ILL_INPUT, __func__, "maxcor = %d: need at least 1 iteration.",
                        maxcor);
  }
  ce->maxcor = maxcor;
  ce->maxcor_set = true;
  if (ce->NLS != nullptr) SUNNonlinSolSetMaxIters(ce->NLS, maxcor);
  return CE_SUCCESS;
}

int CEodeSetNonlinTolerances(void* mem, sunrealtype reltol, sunrealtype abstol) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if ((flag = ceode::ValidateNonlinTolerances(ce, __func__, reltol, abstol)) != CE_SUCCESS)
    return flag;
  ce->nls_reltol = reltol;
  ce->nls_abstol = abstol;
  ce->nls_tol_set = true;
  return CE_SUCCESS;
}

int CEodeSetJacEvalFrequency(void* mem, long int msbj) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  ce->msbj = msbj > 0 ? msbj : ceode::kDefaultJacEvalFrequency;
  ce->msbj_set = msbj > 0;
  return CE_SUCCESS;
}

int CEodeSetErrHandlerFn(void* mem, CEodeErrHandlerFn ehfun, void* eh_data) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  ce->ehfun = ehfun;
  ce->eh_data = eh_data;
  return CE_SUCCESS;
}

int CEodeSetErrFile(void* mem, FILE* errfp) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  ce->errfp = errfp;
  ce->to_context = false;  // SUNDIALS 7: this memory's messages leave the context's path
  return CE_SUCCESS;
}

int CEodeSetStabilityGuard(void* mem, int mode, long int every) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (mode != CE_GUARD_OFF && mode != CE_GUARD_WARN && mode != CE_GUARD_REFUSE) {
    return ProcessError(ce, CE_ILL_INPUT, __func__,
                        "mode = %d: use CE_GUARD_OFF, CE_GUARD_WARN or CE_GUARD_REFUSE.", mode);
  }
  if (every < 0) {
    return ProcessError(ce, CE_ILL_INPUT, __func__,
                        "every = %ld: use 0 (check at start only) or a positive step count.",
                        every);
  }
  ce->guard_mode = mode;
  ce->guard_every = every;
  ce->guard_warned = false;
  ce->guard_pending = true;
  return CE_SUCCESS;
}

int CEodeSetMaxFrequency(void* mem, sunrealtype omega_max) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (!(omega_max >= 0) || !std::isfinite(omega_max)) {
    return ProcessError(ce, CE_ILL_INPUT, __func__,
                        "omega_max = %g: pass a non-negative frequency (0: estimate it).",
                        static_cast<double>(omega_max));
  }
  ce->omega_user = omega_max;
  ce->guard_warned = false;
  ce->guard_pending = true;  // a new estimate is checked at the next CEodeEvolve
  return CE_SUCCESS;
}

int CEodeGetAccel(void* mem, N_Vector a) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce, true);
  if (flag != CE_SUCCESS) return flag;
  if (a == nullptr || N_VGetLength(a) != ce->n) {
    return ProcessError(ce, CE_ILL_INPUT, __func__, "a must be a vector cloned from x0.");
  }
  if (!ce->started) {
    return ProcessError(ce, CE_ILL_INPUT, __func__, "No acceleration yet: call CEodeEvolve first.");
  }
  // The acceleration at the last output time, from the same interpolant as x and v.
  ceode::Interpolate(ce, ce->tretlast - ce->tcur, 2, a);
  return CE_SUCCESS;
}

int CEodeGetCurrentTime(void* mem, sunrealtype* tcur) {
  return GetCounter<sunrealtype>(mem, __func__, tcur, &CEodeMemRec::tcur);
}
int CEodeGetCurrentStep(void* mem, sunrealtype* hcur) {
  return GetCounter<sunrealtype>(mem, __func__, hcur, &CEodeMemRec::h);
}
int CEodeGetNumSteps(void* mem, long int* n) {
  return GetCounter<long int>(mem, __func__, n, &CEodeMemRec::nst);
}
int CEodeGetNumRhsEvals(void* mem, long int* n) {
  return GetCounter<long int>(mem, __func__, n, &CEodeMemRec::nfe);
}
int CEodeGetNumStartRhsEvals(void* mem, long int* n) {
  return GetCounter<long int>(mem, __func__, n, &CEodeMemRec::nfe_start);
}
int CEodeGetNumGuardRhsEvals(void* mem, long int* n) {
  return GetCounter<long int>(mem, __func__, n, &CEodeMemRec::nfe_guard);
}
int CEodeGetNumNonlinSolvIters(void* mem, long int* n) {
  return GetCounter<long int>(mem, __func__, n, &CEodeMemRec::nni);
}
int CEodeGetNumNonlinSolvConvFails(void* mem, long int* n) {
  return GetCounter<long int>(mem, __func__, n, &CEodeMemRec::nnf);
}
int CEodeGetNumLinSolvSetups(void* mem, long int* n) {
  return GetCounter<long int>(mem, __func__, n, &CEodeMemRec::nsetups);
}
int CEodeGetNumLinSolves(void* mem, long int* n) {
  return GetCounter<long int>(mem, __func__, n, &CEodeMemRec::nls_solves);
}
int CEodeGetNumJacEvals(void* mem, long int* n) {
  return GetCounter<long int>(mem, __func__, n, &CEodeMemRec::nje);
}
int CEodeGetNumRhsEvalsJacDQ(void* mem, long int* n) {
  return GetCounter<long int>(mem, __func__, n, &CEodeMemRec::nfeDQ);
}
int CEodeGetNumMassEvals(void* mem, long int* n) {
  return GetCounter<long int>(mem, __func__, n, &CEodeMemRec::nme);
}
int CEodeGetNumConstrEvals(void* mem, long int* n) {
  return GetCounter<long int>(mem, __func__, n, &CEodeMemRec::nce);
}
int CEodeGetNumConstrJacEvals(void* mem, long int* n) {
  return GetCounter<long int>(mem, __func__, n, &CEodeMemRec::nge);
}
int CEodeGetMaxFrequencyEstimate(void* mem, sunrealtype* omega_max) {
  return GetCounter<sunrealtype>(mem, __func__, omega_max, &CEodeMemRec::omega_est);
}

int CEodeGetLastErrorMessage(void* mem, const char** msg) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (msg == nullptr) return ProcessError(ce, CE_ILL_INPUT, __func__, "msg = NULL.");
  *msg = ce->last_msg.c_str();
  return CE_SUCCESS;
}

int CEodePrintAllStats(void* mem, FILE* outfile, SUNOutputFormat fmt) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (outfile == nullptr) return ProcessError(ce, CE_ILL_INPUT, __func__, "outfile = NULL.");
  struct Row {
    const char* name;
    double value;
    bool integer;
  };
  const Row rows[] = {
      {"Current time", static_cast<double>(ce->tcur), false},
      {"Steps", static_cast<double>(ce->nst), true},
      {"Step size", static_cast<double>(ce->h), false},
      {"RHS fn evals", static_cast<double>(ce->nfe), true},
      {"RHS fn evals in start", static_cast<double>(ce->nfe_start), true},
      {"RHS fn evals in stability guard", static_cast<double>(ce->nfe_guard), true},
      {"NLS iters", static_cast<double>(ce->nni), true},
      {"NLS fails", static_cast<double>(ce->nnf), true},
      {"LS setups", static_cast<double>(ce->nsetups), true},
      {"LS solves", static_cast<double>(ce->nls_solves), true},
      {"Jac fn evals", static_cast<double>(ce->nje), true},
      {"RHS fn evals for Jac DQ", static_cast<double>(ce->nfeDQ), true},
      {"Mass fn evals", static_cast<double>(ce->nme), true},
      {"Constraint fn evals", static_cast<double>(ce->nce), true},
      {"Constraint Jac evals", static_cast<double>(ce->nge), true},
      {"Max frequency estimate", static_cast<double>(ce->omega_est), false},
  };
  if (fmt == SUN_OUTPUTFORMAT_TABLE) {
    std::fprintf(outfile, "%-28s = %s\n", "Method", ce->method_name.c_str());
    for (const Row& r : rows) {
      if (r.integer) {
        std::fprintf(outfile, "%-28s = %ld\n", r.name, static_cast<long>(r.value));
      } else {
        std::fprintf(outfile, "%-28s = %.16g\n", r.name, r.value);
      }
    }
  } else if (fmt == SUN_OUTPUTFORMAT_CSV) {
    std::fprintf(outfile, "Method,%s", ce->method_name.c_str());
    for (const Row& r : rows) {
      if (r.integer) {
        std::fprintf(outfile, ",%s,%ld", r.name, static_cast<long>(r.value));
      } else {
        std::fprintf(outfile, ",%s,%.16g", r.name, r.value);
      }
    }
    std::fprintf(outfile, "\n");
  } else {
    return ProcessError(
        ce, CE_ILL_INPUT, __func__,
        "Unknown output format: use SUN_OUTPUTFORMAT_TABLE or SUN_OUTPUTFORMAT_CSV.");
  }
  return CE_SUCCESS;
}

}  // extern "C"

const char* ceode::FlagName(long int flag) {
  static const struct {
    long int flag;
    const char* name;
  } kNames[] = {
      {CE_SUCCESS, "CE_SUCCESS"},
      {CE_TSTOP_RETURN, "CE_TSTOP_RETURN"},
      {CE_WARNING, "CE_WARNING"},
      {CE_MEM_NULL, "CE_MEM_NULL"},
      {CE_ILL_INPUT, "CE_ILL_INPUT"},
      {CE_NO_MALLOC, "CE_NO_MALLOC"},
      {CE_MEM_FAIL, "CE_MEM_FAIL"},
      {CE_RHSFUNC_FAIL, "CE_RHSFUNC_FAIL"},
      {CE_FIRST_RHSFUNC_ERR, "CE_FIRST_RHSFUNC_ERR"},
      {CE_CONV_FAILURE, "CE_CONV_FAILURE"},
      {CE_LSETUP_FAIL, "CE_LSETUP_FAIL"},
      {CE_LSOLVE_FAIL, "CE_LSOLVE_FAIL"},
      {CE_LINIT_FAIL, "CE_LINIT_FAIL"},
      {CE_NLS_INIT_FAIL, "CE_NLS_INIT_FAIL"},
      {CE_NLS_FAIL, "CE_NLS_FAIL"},
      {CE_CONSTR_FAIL, "CE_CONSTR_FAIL"},
      {CE_MASSFUNC_FAIL, "CE_MASSFUNC_FAIL"},
      {CE_JACFUNC_FAIL, "CE_JACFUNC_FAIL"},
      {CE_UNSTABLE, "CE_UNSTABLE"},
      {CE_TOO_MUCH_WORK, "CE_TOO_MUCH_WORK"},
      {CE_BAD_T, "CE_BAD_T"},
      {CE_VECTOROP_ERR, "CE_VECTOROP_ERR"},
  };
  for (const auto& entry : kNames) {
    if (entry.flag == flag) return entry.name;
  }
  return "NONE";
}

extern "C" {

char* CEodeGetReturnFlagName(long int flag) {
  // The caller owns the returned string, as with CVodeGetReturnFlagName.
  const char* name = ceode::FlagName(flag);
  const size_t len = std::strlen(name) + 1;
  char* out = static_cast<char*>(std::malloc(len));
  if (out != nullptr) std::memcpy(out, name, len);
  return out;
}

}  // extern "C"
