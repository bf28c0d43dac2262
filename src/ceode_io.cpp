// Optional inputs and outputs, statistics and flag names.
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "ceode_adapt.hpp"
#include "ceode_impl.hpp"
#include "ceode_testing.h"

using ceode::Access;
using ceode::ProcessError;
using ceode::Restart;

namespace {

// A value of the memory or of one of its modules' records (get reads it from the memory).
template <typename T, typename Get>
int GetValue(void* mem, const char* func, T* out, Get get) {
  CEodeMemRec* ce = nullptr;
  const int flag = Access(mem, func, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (out == nullptr) return ProcessError(ce, CE_ILL_INPUT, func, "The output pointer is NULL.");
  *out = get(*ce);
  return CE_SUCCESS;
}

// The solver statistics: the velocity-dependent step's solvers and the constrained step's
// saddle-point solver count apart, the user sees their sums.
long int Nni(const CEodeMemRec& ce) { return ce.nls.nni + ce.con.nni; }
long int Nnf(const CEodeMemRec& ce) { return ce.nls.nnf + ce.con.nnf; }
long int Nsetups(const CEodeMemRec& ce) { return ce.ls.nsetups + ce.con.nsetups; }
long int Nsolves(const CEodeMemRec& ce) { return ce.ls.nsolves + ce.con.nsolves; }
long int Nje(const CEodeMemRec& ce) { return ce.ls.nje + ce.con.nje; }

template <typename T>
int GetCounter(void* mem, const char* func, T* out, T CEodeMemRec::*field) {
  return GetValue(mem, func, out, [field](const CEodeMemRec& ce) { return ce.*field; });
}

// PrintAllStats' entries: the named choices first, then the figures.
struct NamedStat {
  const char* name;
  const char* value;
};
struct Stat {
  const char* name;
  double value;
  bool integer;
};

// One "name = value" line each (SUN_OUTPUTFORMAT_TABLE) or one line of name,value pairs (CSV).
template <std::size_t N, std::size_t M>
void WriteStats(FILE* out, bool csv, const NamedStat (&names)[N], const Stat (&stats)[M]) {
  for (std::size_t i = 0; i < N; ++i) {
    if (csv) {
      std::fprintf(out, "%s%s,%s", i == 0 ? "" : ",", names[i].name, names[i].value);
    } else {
      std::fprintf(out, "%-28s = %s\n", names[i].name, names[i].value);
    }
  }
  for (const Stat& r : stats) {
    if (r.integer) {
      std::fprintf(out, csv ? ",%s,%ld" : "%-28s = %ld\n", r.name, static_cast<long>(r.value));
    } else {
      std::fprintf(out, csv ? ",%s,%.16g" : "%-28s = %.16g\n", r.name, r.value);
    }
  }
  if (csv) std::fprintf(out, "\n");
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
  ceode::PcMethodChanged(ce);
  try {
    ce->method_name = "custom G" + std::to_string(degree);
  } catch (...) {
    return ProcessError(ce, CE_MEM_FAIL, __func__, "Out of memory.");
  }
  ceode::GuardMethodChanged(ce);
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
  return ceode::SetFusedKernel(ce, on != SUNFALSE, __func__);
}

int CEodeSetInPlaceUpdate(void* mem, sunbooleantype on) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  return ceode::SetInPlaceUpdate(ce, on != SUNFALSE, __func__);
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
  if (h != ce->h || ceode::AdaptOn(ce)) Restart(ce);
  ceode::AdaptDisable(ce);  // a fixed step ends error control (the last of the two calls decides)
  ce->h = h;
  return CE_SUCCESS;
}

int CEodeSetVelocityMode(void* mem, CEodeVelocityMode mode) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  const int m = static_cast<int>(mode);
  if (m != CE_VELOCITY_INDEPENDENT && m != CE_VELOCITY_DEPENDENT && m != CE_VELOCITY_DETECT) {
    return ProcessError(ce, CE_ILL_INPUT, __func__,
                        "mode = %d: use CE_VELOCITY_INDEPENDENT, CE_VELOCITY_DEPENDENT or "
                        "CE_VELOCITY_DETECT.",
                        m);
  }
  // CE_VELOCITY_DETECT: the start decides (ceode_pc.cpp).
  ceode::PcSetVelocityRequest(ce, m);
  ce->vel_dependent = m == CE_VELOCITY_DEPENDENT;
  Restart(ce);
  return CE_SUCCESS;
}

int CEodeSetVelocityDependence(void* mem, sunbooleantype depends) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (depends != SUNTRUE && depends != SUNFALSE) {
    return ProcessError(ce, CE_ILL_INPUT, __func__,
                        "depends = %d: this setter takes SUNTRUE or SUNFALSE; detection of the "
                        "dependence is CEodeSetVelocityMode(mem, CE_VELOCITY_DETECT).",
                        static_cast<int>(depends));
  }
  return CEodeSetVelocityMode(mem,
                              depends == SUNTRUE ? CE_VELOCITY_DEPENDENT : CE_VELOCITY_INDEPENDENT);
}

int CEodeSetUserData(void* mem, void* user_data) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  ce->user_data = user_data;
  ceode::SelectRhs(ce);  // the steps call f with the new data
  return CE_SUCCESS;
}

int CEodeSetStopTime(void* mem, sunrealtype tstop) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if ((flag = ceode::ValidateTime(ce, __func__, "tstop", tstop)) != CE_SUCCESS) return flag;
  ce->tstop = tstop;
  ce->tstop_set = true;
  ceode::StepOptionsChanged(ce);
  return CE_SUCCESS;
}

int CEodeClearStopTime(void* mem) {
  CEodeMemRec* ce = nullptr;
  int flag = Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  ce->tstop_set = false;
  ceode::StepOptionsChanged(ce);
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
int CEodeGetNumNonlinSolvIters(void* mem, long int* n) {
  return GetValue<long int>(mem, __func__, n, [](const CEodeMemRec& ce) { return Nni(ce); });
}
int CEodeGetNumNonlinSolvConvFails(void* mem, long int* n) {
  return GetValue<long int>(mem, __func__, n, [](const CEodeMemRec& ce) { return Nnf(ce); });
}
int CEodeGetNumLinSolvSetups(void* mem, long int* n) {
  return GetValue<long int>(mem, __func__, n, [](const CEodeMemRec& ce) { return Nsetups(ce); });
}
int CEodeGetNumLinSolves(void* mem, long int* n) {
  return GetValue<long int>(mem, __func__, n, [](const CEodeMemRec& ce) { return Nsolves(ce); });
}
int CEodeGetNumJacEvals(void* mem, long int* n) {
  return GetValue<long int>(mem, __func__, n, [](const CEodeMemRec& ce) { return Nje(ce); });
}
int CEodeGetNumRhsEvalsJacDQ(void* mem, long int* n) {
  return GetValue<long int>(mem, __func__, n, [](const CEodeMemRec& ce) { return ce.ls.nfeDQ; });
}
int CEodeGetNumMassEvals(void* mem, long int* n) {
  return GetValue<long int>(mem, __func__, n, [](const CEodeMemRec& ce) { return ce.ls.nme; });
}
int CEodeGetNumConstrEvals(void* mem, long int* n) {
  return GetValue<long int>(mem, __func__, n, [](const CEodeMemRec& ce) { return ce.con.nce; });
}
int CEodeGetNumConstrJacEvals(void* mem, long int* n) {
  return GetValue<long int>(mem, __func__, n, [](const CEodeMemRec& ce) { return ce.con.nge; });
}
int CEodeGetNumPCSteps(void* mem, long int* npcsteps) {
  return GetValue<long int>(mem, __func__, npcsteps,
                            [](const CEodeMemRec& ce) { return ce.pc.nsteps; });
}
int CEodeGetNumPCCorrections(void* mem, long int* npccorr) {
  return GetValue<long int>(mem, __func__, npccorr,
                            [](const CEodeMemRec& ce) { return ce.pc.ncorr; });
}
int CEodeGetMaxFrequencyEstimate(void* mem, sunrealtype* omega_max) {
  return GetValue<sunrealtype>(mem, __func__, omega_max,
                               [](const CEodeMemRec& ce) { return ce.guard.omega_est; });
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
  if (fmt != SUN_OUTPUTFORMAT_TABLE && fmt != SUN_OUTPUTFORMAT_CSV) {
    return ProcessError(
        ce, CE_ILL_INPUT, __func__,
        "Unknown output format: use SUN_OUTPUTFORMAT_TABLE or SUN_OUTPUTFORMAT_CSV.");
  }
  const NamedStat names[] = {
      {"Method", ce->method_name.c_str()},
      {"Velocity dependence", ceode::VelocityDependenceName(ce)},
      {"Acceleration solve", ceode::AccelSolveName(ce)},
  };
  const Stat rows[] = {
      {"Current time", static_cast<double>(ce->tcur), false},
      {"Steps", static_cast<double>(ce->nst), true},
      {"Step size", static_cast<double>(ce->h), false},
      {"RHS fn evals", static_cast<double>(ce->nfe), true},
      {"RHS fn evals in start", static_cast<double>(ce->nfe_start), true},
      {"RHS fn evals in stability guard", static_cast<double>(ce->guard.nfe), true},
      {"NLS iters", static_cast<double>(Nni(*ce)), true},
      {"PC steps", static_cast<double>(ce->pc.nsteps), true},
      {"PC corrections", static_cast<double>(ce->pc.ncorr), true},
      {"NLS fails", static_cast<double>(Nnf(*ce)), true},
      {"LS setups", static_cast<double>(Nsetups(*ce)), true},
      {"LS solves", static_cast<double>(Nsolves(*ce)), true},
      {"Jac fn evals", static_cast<double>(Nje(*ce)), true},
      {"RHS fn evals for Jac DQ", static_cast<double>(ce->ls.nfeDQ), true},
      {"Mass fn evals", static_cast<double>(ce->ls.nme), true},
      {"Constraint fn evals", static_cast<double>(ce->con.nce), true},
      {"Constraint Jac evals", static_cast<double>(ce->con.nge), true},
      {"Max frequency estimate", static_cast<double>(ce->guard.omega_est), false},
      {"Error test fails", static_cast<double>(ce->adapt ? ce->adapt->netf : 0), true},
      {"Steps limited by stability", static_cast<double>(ce->adapt ? ce->adapt->ncapped : 0), true},
      {"Root fn evals", static_cast<double>(ceode::RootNumGEvals(ce)), true},
  };
  WriteStats(outfile, fmt == SUN_OUTPUTFORMAT_CSV, names, rows);
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
      {CE_ROOT_RETURN, "CE_ROOT_RETURN"},
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
      {CE_ERR_FAILURE, "CE_ERR_FAILURE"},
      {CE_INCONSISTENT_IC, "CE_INCONSISTENT_IC"},
      {CE_RTFUNC_FAIL, "CE_RTFUNC_FAIL"},
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
