// Where CEODE's messages go on SUNDIALS 7 (docs/user_guide.md, "SUNDIALS 6.4 and 7.x"):
// errors through the handlers pushed on the SUNContext, warnings to its logger,
// unless the CEODE memory has its own handler (CEodeSetErrHandlerFn) or file
// (CEodeSetErrFile). On 6.4 the context has neither, and these tests skip.
#include <ceode/ceode.h>
#include <gtest/gtest.h>
#include <nvector/nvector_serial.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "ceode_sundials_compat.h"  // SUN_COMM_NULL on SUNDIALS 6.4
#include "test_util.hpp"

#if SUNDIALS_VERSION_MAJOR >= 7
#include <sundials/sundials_errors.h>
#include <sundials/sundials_logger.h>
#endif

namespace {

using ceode_test::Context;
using ceode_test::Mem;

struct Seen {
  int calls = 0;
  int code = 0;
  std::string func;
  std::string msg;
};

#if SUNDIALS_VERSION_MAJOR >= 7
void ContextHandler(int /*line*/, const char* func, const char* /*file*/, const char* msg,
                    SUNErrCode code, void* data, SUNContext /*ctx*/) {
  auto* s = static_cast<Seen*>(data);
  ++s->calls;
  s->code = code;
  s->func = func != nullptr ? func : "";
  s->msg = msg != nullptr ? msg : "";
}
#endif

void CeodeHandler(int code, const char* /*module*/, const char* func, char* msg, void* data) {
  auto* s = static_cast<Seen*>(data);
  ++s->calls;
  s->code = code;
  s->func = func;
  s->msg = msg;
}

int Oscillator(sunrealtype /*t*/, N_Vector x, N_Vector /*v*/, N_Vector f, void* /*data*/) {
  N_VScale(-1, x, f);
  return 0;
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

TEST(SundialsSeven, ErrorsReachTheHandlerPushedOnTheContextWithFlagAndFunction) {
#if SUNDIALS_VERSION_MAJOR >= 7
  Context ctx;
  Seen seen;
  ASSERT_EQ(SUNContext_ClearErrHandlers(ctx), SUN_SUCCESS);  // no default logging handler
  ASSERT_EQ(SUNContext_PushErrHandler(ctx, ContextHandler, &seen), SUN_SUCCESS);
  Mem mem(CEodeCreate(ctx));
  EXPECT_EQ(CEodeSetFixedStep(mem.get(), -1), CE_ILL_INPUT);
  EXPECT_EQ(seen.calls, 1);
  EXPECT_EQ(seen.code, CE_ILL_INPUT);
  EXPECT_EQ(seen.func, "CEodeSetFixedStep");
  EXPECT_NE(seen.msg.find("positive and finite"), std::string::npos) << seen.msg;
  EXPECT_NE(seen.msg.find("CE_ILL_INPUT"), std::string::npos) << seen.msg;
  // Reported errors are cleared, as ARKODE and CVODE leave the context.
  EXPECT_EQ(SUNContext_PeekLastError(ctx), SUN_SUCCESS);
#else
  GTEST_SKIP() << "SUNDIALS " << SUNDIALS_VERSION << ": no error handlers on the SUNContext";
#endif
}

TEST(SundialsSeven, CeodesOwnHandlerAndFileTakeTheMessagesOffTheContext) {
#if SUNDIALS_VERSION_MAJOR >= 7
  Context ctx;
  Seen on_context;
  Seen on_ceode;
  ASSERT_EQ(SUNContext_PushErrHandler(ctx, ContextHandler, &on_context), SUN_SUCCESS);
  Mem mem(CEodeCreate(ctx));
  ASSERT_EQ(CEodeSetErrHandlerFn(mem.get(), CeodeHandler, &on_ceode), CE_SUCCESS);
  EXPECT_EQ(CEodeSetFixedStep(mem.get(), -1), CE_ILL_INPUT);
  EXPECT_EQ(on_ceode.calls, 1);
  EXPECT_EQ(on_ceode.code, CE_ILL_INPUT);
  EXPECT_EQ(on_context.calls, 0);
  // Removing CEODE's handler restores the context's path ...
  ASSERT_EQ(CEodeSetErrHandlerFn(mem.get(), nullptr, nullptr), CE_SUCCESS);
  EXPECT_EQ(CEodeSetFixedStep(mem.get(), -1), CE_ILL_INPUT);
  EXPECT_EQ(on_context.calls, 1);
  // ... and CEodeSetErrFile(NULL) silences this memory only.
  ASSERT_EQ(CEodeSetErrFile(mem.get(), nullptr), CE_SUCCESS);
  EXPECT_EQ(CEodeSetFixedStep(mem.get(), -1), CE_ILL_INPUT);
  EXPECT_EQ(on_context.calls, 1);
  const char* msg = nullptr;
  ASSERT_EQ(CEodeGetLastErrorMessage(mem.get(), &msg), CE_SUCCESS);
  EXPECT_NE(std::string(msg).find("positive and finite"), std::string::npos) << msg;
#else
  GTEST_SKIP() << "SUNDIALS " << SUNDIALS_VERSION << ": no error handlers on the SUNContext";
#endif
}

TEST(SundialsSeven, WarningsGoToTheLoggersWarningStreamAndNotToTheErrorHandlers) {
#if SUNDIALS_VERSION_MAJOR >= 7
  Context ctx;
  Seen seen;
  ASSERT_EQ(SUNContext_PushErrHandler(ctx, ContextHandler, &seen), SUN_SUCCESS);
  SUNLogger logger = nullptr;
  ASSERT_EQ(SUNContext_GetLogger(ctx, &logger), SUN_SUCCESS);
  const std::string path = std::string(CEODE_BINARY_DIR) + "/test_sundials_compat_warn.txt";
  std::remove(path.c_str());
  ASSERT_EQ(SUNLogger_SetWarningFilename(logger, path.c_str()), SUN_SUCCESS);
  auto x = ceode_test::SerialVector(1, ctx, 1);
  auto v = ceode_test::SerialVector(1, ctx, 0);
  Mem mem(CEodeCreate(ctx));
  ASSERT_EQ(CEodeInit(mem.get(), Oscillator, 0, x.get(), v.get()), CE_SUCCESS);
  ASSERT_EQ(CEodeSetMethodByName(mem.get(), "G3_CD"), CE_SUCCESS);
  ASSERT_EQ(CEodeSetFixedStep(mem.get(), 0.5), CE_SUCCESS);
  ASSERT_EQ(CEodeSetMaxFrequency(mem.get(), 5.0), CE_SUCCESS);  // h omega = 2.5 > 2
  ASSERT_EQ(CEodeSetStabilityGuard(mem.get(), CE_GUARD_WARN, 0), CE_SUCCESS);
  sunrealtype t = 0;
  EXPECT_EQ(CEodeEvolve(mem.get(), 1, x.get(), v.get(), &t, CE_NORMAL), CE_SUCCESS);
  ASSERT_EQ(SUNLogger_Flush(logger, SUN_LOGLEVEL_ALL), SUN_SUCCESS);
  EXPECT_EQ(seen.calls, 0);
  const std::string log = ReadFile(path);
  EXPECT_NE(log.find("WARNING"), std::string::npos) << log;
  EXPECT_NE(log.find("CEodeSetMaxFrequency"), std::string::npos) << log;
  EXPECT_NE(log.find("CE_WARNING"), std::string::npos) << log;
#else
  GTEST_SKIP() << "SUNDIALS " << SUNDIALS_VERSION << ": no SUNLogger warning stream";
#endif
}

TEST(SundialsSixAndSeven, ContextsWithoutACommunicatorRunTheSolverOnBoth) {
  // SUN_COMM_NULL (an MPI_Comm on an MPI-enabled 7.x, where NULL aborts) or NULL on 6.4.
  SUNContext ctx = nullptr;
  ASSERT_EQ(SUNContext_Create(SUN_COMM_NULL, &ctx), 0);
  N_Vector x = N_VNew_Serial(1, ctx);
  N_Vector v = N_VNew_Serial(1, ctx);
  NV_Ith_S(x, 0) = 1;
  NV_Ith_S(v, 0) = 0;
  void* mem = CEodeCreate(ctx);
  int flag = CEodeInit(mem, Oscillator, 0, x, v);
  if (flag == CE_SUCCESS) flag = CEodeSetMethodByName(mem, "G4_A34");
  if (flag == CE_SUCCESS) flag = CEodeSetFixedStep(mem, 1e-2);
  sunrealtype t = 0;
  if (flag == CE_SUCCESS) flag = CEodeEvolve(mem, 1, x, v, &t, CE_NORMAL);
  EXPECT_EQ(flag, CE_SUCCESS);
  EXPECT_NEAR(NV_Ith_S(x, 0), std::cos(1.0), 1e-6);
  CEodeFree(&mem);
  N_VDestroy(x);
  N_VDestroy(v);
  SUNContext_Free(&ctx);
}

}  // namespace
