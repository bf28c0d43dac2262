// The differences between SUNDIALS 6.4 and 7.x that the library meets, in one
// place (docs/user_guide.md, "SUNDIALS 6.4 and 7.x"). Not installed.
#ifndef CEODE_SRC_CEODE_SUNDIALS_HPP_
#define CEODE_SRC_CEODE_SUNDIALS_HPP_

#include <ceode/ceode.h>
#include <sundials/sundials_config.h>
#include <sundials/sundials_context.h>
#include <sundials/sundials_nvector.h>

#include <cstdio>

#if SUNDIALS_VERSION_MAJOR >= 7
#include <sundials/sundials_errors.h>
#include <sundials/sundials_logger.h>
// SUNHandleErrWithMsg is the call ARKODE and CVODE make to run the context's
// handler stack; SUNDIALS 7 installs it only under priv/. Without it CEODE's
// errors still reach the context's logger, but not handlers the user pushed.
#if __has_include(<sundials/priv/sundials_errors_impl.h>)
#include <sundials/priv/sundials_errors_impl.h>
#define CEODE_HAVE_SUN_HANDLE_ERR 1
#endif
// SUNDIALS 7 replaced the per-class success codes by SUN_SUCCESS; the library
// keeps the 6.4 names so that one source reads the same on both.
#ifndef SUN_NLS_SUCCESS
#define SUN_NLS_SUCCESS SUN_SUCCESS
#endif
#ifndef SUNLS_SUCCESS
#define SUNLS_SUCCESS SUN_SUCCESS
#endif
#ifndef SUNMAT_SUCCESS
#define SUNMAT_SUCCESS SUN_SUCCESS
#endif
#endif

namespace ceode::sun {

// True when SUNDIALS 7 conventions apply: errors go through the SUNContext.
constexpr bool kContextErrors = SUNDIALS_VERSION_MAJOR >= 7;

// A context without a communicator: SUN_COMM_NULL on 7.x (an MPI_Comm on an MPI
// build, where a null pointer compiles and aborts at run time), NULL on 6.4.
inline int ContextCreate(SUNContext* ctx) {
#if SUNDIALS_VERSION_MAJOR >= 7
  return SUNContext_Create(SUN_COMM_NULL, ctx);
#else
  return SUNContext_Create(nullptr, ctx);
#endif
}

// The vector lives in one process (no communicator).
inline bool IsLocal(N_Vector v) {
#if SUNDIALS_VERSION_MAJOR >= 7
  return N_VGetCommunicator(v) == SUN_COMM_NULL;
#else
  return N_VGetCommunicator(v) == nullptr;
#endif
}

// A distributed vector whose local part is one contiguous array (NVECTOR_PARALLEL): the
// one-pass update can run on that part, its norm finished by one allreduce. Through the ops
// table, so that libceode does not link the parallel vector (N_VGetLocalLength is deprecated
// on 6.4).
inline bool LocalArrayWithReduce(N_Vector v) {
  return N_VGetVectorID(v) == SUNDIALS_NVEC_PARALLEL && v->ops->nvgetlocallength != nullptr &&
         v->ops->nvdotprodmultiallreduce != nullptr && N_VGetArrayPointer(v) != nullptr;
}

// Hands a CEODE message to the SUNContext as SUNDIALS 7 packages do: warnings
// to the logger's warning stream, errors to the context's handler stack (whose
// default handler writes them to the logger's error stream). The context's
// handlers see only an int code, so the flag's name ends the text. No-op on 6.4.
inline void ReportToContext(SUNContext ctx, int flag, const char* flag_name, const char* func,
                            const char* msg) {
#if SUNDIALS_VERSION_MAJOR >= 7
  SUNLogger logger = nullptr;
  if (ctx == nullptr || SUNContext_GetLogger(ctx, &logger) != SUN_SUCCESS) return;
  char text[1100];
  std::snprintf(text, sizeof(text), "%s (%s)", msg, flag_name);
  if (flag == CE_WARNING) {
    SUNLogger_QueueMsg(logger, SUN_LOGLEVEL_WARNING, "CEODE", func, "%s", text);
    return;
  }
#ifdef CEODE_HAVE_SUN_HANDLE_ERR
  SUNHandleErrWithMsg(__LINE__, func, __FILE__, text, flag, ctx);
  (void)SUNContext_GetLastError(ctx);  // reported, so cleared (as ARKODE does)
#else
  SUNLogger_QueueMsg(logger, SUN_LOGLEVEL_ERROR, "CEODE", func, "%s", text);
#endif
#else
  (void)ctx, (void)flag, (void)flag_name, (void)func, (void)msg;
#endif
}

}  // namespace ceode::sun

#endif  // CEODE_SRC_CEODE_SUNDIALS_HPP_
