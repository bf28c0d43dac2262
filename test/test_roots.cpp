// Root finding (events): CEodeRootInit and its options, on fixed and adaptive steps, explicit
// and constrained, against event times known in closed form.
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <cstring>

#include "test_util.hpp"

using namespace ceode_test;

namespace {

constexpr sunrealtype kPi = SUN_RCONST(3.141592653589793238462643383279503);

// x'' = -x, x(0) = 1, x'(0) = 1/2: x = R cos(t - phi), R = sqrt(5)/2, phi = atan(1/2).
int Oscillator(sunrealtype, N_Vector x, N_Vector, N_Vector f, void*) {
  N_VScale(-1, x, f);
  return 0;
}
const sunrealtype kPhase = std::atan(SUN_RCONST(0.5));
// The k-th zero of x (k = 0, 1, ...): x decreases through the even ones.
sunrealtype OscillatorZero(int k) { return kPhase + kPi / 2 + k * kPi; }

int GX(sunrealtype, N_Vector x, N_Vector, sunrealtype* g, void*) {
  g[0] = NV_Ith_S(x, 0);
  return 0;
}

struct Event {
  sunrealtype t;
  std::vector<int> info;
};

struct OscSetup {
  std::string method = "G5_O4";
  sunrealtype h = SUN_RCONST(0.01);  // fixed step; 0: error control with tol
  sunrealtype tol = 0;
  int itask = CE_NORMAL;
  sunrealtype x0 = 1, v0 = SUN_RCONST(0.5);
};

// A memory for the oscillator as set up.
Mem MakeOscillator(SUNContext ctx, const OscSetup& s, N_Vector x, N_Vector v) {
  Mem mem(CEodeCreate(ctx));
  NV_Ith_S(x, 0) = s.x0;
  NV_Ith_S(v, 0) = s.v0;
  EXPECT_EQ(CEodeInit(mem.get(), Oscillator, 0, x, v), CE_SUCCESS);
  EXPECT_EQ(CEodeSetMethodByName(mem.get(), s.method.c_str()), CE_SUCCESS);
  EXPECT_EQ(CEodeSetStabilityGuard(mem.get(), CE_GUARD_OFF, 0), CE_SUCCESS);
  if (s.h > 0) {
    EXPECT_EQ(CEodeSetFixedStep(mem.get(), s.h), CE_SUCCESS);
  } else {
    EXPECT_EQ(CEodeSStolerances(mem.get(), s.tol, s.tol), CE_SUCCESS);
  }
  return mem;
}

// The oscillator as set up, owning its context, vectors and memory; g (nrtfn root functions)
// is attached when given.
struct OscRun {
  explicit OscRun(const OscSetup& s, int nrtfn = 0, CEodeRootFn g = nullptr)
      : x(SerialVector(1, ctx)),
        v(SerialVector(1, ctx)),
        mem(MakeOscillator(ctx, s, x.get(), v.get())) {
    if (g != nullptr) EXPECT_EQ(CEodeRootInit(mem.get(), nrtfn, g), CE_SUCCESS);
  }
  Context ctx;
  Vector x, v;
  Mem mem;
};

// Every event of g up to tend, evolving to tend (CE_NORMAL) or step by step (CE_ONE_STEP).
std::vector<Event> Events(void* mem, int nrtfn, N_Vector x, N_Vector v, sunrealtype tend,
                          int itask) {
  std::vector<Event> out;
  sunrealtype t = 0;
  for (;;) {
    const int flag = CEodeEvolve(mem, tend, x, v, &t, itask);
    EXPECT_GE(flag, 0) << FlagName(flag);
    // CE_NORMAL returns tout (within 1e-8 h) with CE_SUCCESS; CE_ONE_STEP passes it.
    if (flag < 0 || (flag == CE_SUCCESS && (itask == CE_NORMAL || t >= tend))) break;
    if (flag == CE_ROOT_RETURN) {
      Event e{t, std::vector<int>(nrtfn)};
      EXPECT_EQ(CEodeGetRootInfo(mem, e.info.data()), CE_SUCCESS);
      out.push_back(e);
    }
  }
  return out;
}

std::vector<Event> OscillatorEvents(const OscSetup& s, sunrealtype tend, const int* dir = nullptr) {
  OscRun run(s, 1, GX);
  void* mem = run.mem.get();
  N_Vector x = run.x.get(), v = run.v.get();
  if (dir != nullptr) EXPECT_EQ(CEodeSetRootDirection(mem, const_cast<int*>(dir)), 0);
  return Events(mem, 1, x, v, tend, s.itask);
}

// Max |t_event - exact| over the oscillator's zeros up to 10 (all three must be found).
sunrealtype OscillatorEventError(const OscSetup& s) {
  const std::vector<Event> ev = OscillatorEvents(s, 10);
  EXPECT_EQ(ev.size(), 3u);
  sunrealtype err = 0;
  for (size_t k = 0; k < ev.size(); ++k) {
    err = std::max(err, std::fabs(ev[k].t - OscillatorZero(static_cast<int>(k))));
    EXPECT_EQ(ev[k].info[0], k % 2 == 0 ? -1 : 1);
  }
  return err;
}

}  // namespace

// The event time inherits the error of the interpolant, which is the set's order p in x
// (docs/theory.md, "Event location"): the fitted slope over five step sizes is at least p - 0.3
// (the margin test_high_degree gives the node errors). The steps halve, except G8_O8's, which
// shrink by sqrt(2) from 0.16: its errors fall by 2^8 a halving and would reach the root's time
// tolerance ttol = 100 ulp (|t| + |h|) = 2e-13 within five halvings; above 0.16 they are not yet
// asymptotic (0.4 -> 0.2: a factor 71, not 256).
TEST(RootFinding, LocatesEventTimesAtTheSetsOrder) {
  struct Case {
    const char* method;
    int order;
    double hmax;  // inside the stability interval (w = 1)
    double ratio;
  };
  for (const Case& c : {Case{"G3_CD", 2, 0.08, 2}, Case{"G4_A34", 3, 0.08, 2},
                        Case{"G5_O4", 4, 0.08, 2}, Case{"G8_O8", 8, 0.16, std::sqrt(2.0)}}) {
    std::vector<double> hs, errs;
    for (int k = 0; k < 5; ++k) {
      OscSetup s;
      s.method = c.method;
      s.h = c.hmax / std::pow(c.ratio, k);
      hs.push_back(s.h);
      errs.push_back(OscillatorEventError(s));
    }
    const double slope = FitOrder(hs, errs);
    std::printf("%s event-time errors %.2e .. %.2e, slope %.2f\n", c.method, errs.front(),
                errs.back(), slope);
    EXPECT_GE(slope, c.order - 0.3) << c.method;
  }
}

// With error control the event time is as accurate as the position near it: |dt| = |dx| / |x'|
// with |x'| = R > 1 at the zeros. The measured errors are 0.16 to 1.6 tol (tol = 1e-6, 1e-9);
// the bound 4 tol leaves room for the controller's rounding, not for a lost order.
TEST(RootFinding, EventTimesFollowTheToleranceWithErrorControl) {
  for (const char* method : {"G4_A34", "G5_O4", "G8_O8"}) {
    for (sunrealtype tol : {SUN_RCONST(1e-6), SUN_RCONST(1e-9)}) {
      OscSetup s;
      s.method = method;
      s.h = 0;
      s.tol = tol;
      const sunrealtype err = OscillatorEventError(s);
      std::printf("%s tol %.0e: event-time error %.2e\n", method, tol, err);
      EXPECT_LT(err, 4 * tol) << method;
    }
  }
}

// dir = +1 keeps the zeros where x increases (the odd ones), dir = -1 the even ones.
TEST(RootFinding, ReportsOnlyTheChosenDirection) {
  for (int d : {1, -1}) {
    for (sunrealtype h : {SUN_RCONST(0.01), SUN_RCONST(0.0)}) {
      OscSetup s;
      s.h = h;
      s.tol = 1e-9;
      const std::vector<Event> ev = OscillatorEvents(s, 10, &d);
      ASSERT_EQ(ev.size(), d > 0 ? 1u : 2u);  // zeros 0 and 2 decreasing, 1 increasing
      for (size_t k = 0; k < ev.size(); ++k) {
        const int zero = static_cast<int>(2 * k) + (d > 0 ? 1 : 0);
        EXPECT_NEAR(ev[k].t, OscillatorZero(zero), 1e-6);
        EXPECT_EQ(ev[k].info[0], d);
      }
    }
  }
}

namespace {

// Three functions of t alone: zeros at 0.3 (g0 and, twice as steep, g2) and 0.35 (g1).
int GLinear(sunrealtype t, N_Vector, N_Vector, sunrealtype* g, void*) {
  g[0] = t - SUN_RCONST(0.3);
  g[1] = SUN_RCONST(0.35) - t;
  g[2] = 2 * (t - SUN_RCONST(0.3));
  return 0;
}

int GAtNode(sunrealtype t, N_Vector, N_Vector, sunrealtype* g, void*) {
  g[0] = t - SUN_RCONST(0.5);
  return 0;
}

}  // namespace

// One step [0.25, 0.5] holds three roots: the earliest (0.3, of g0 and g2 together, reported
// with their directions) first, then g1's at 0.35; the time tolerance is 100 ulp of |t| + |h|.
TEST(RootFinding, ReportsSeveralRootsOfOneStepInOrder) {
  for (int itask : {CE_NORMAL, CE_ONE_STEP}) {
    OscSetup s;
    s.h = SUN_RCONST(0.25);
    OscRun run(s, 3, GLinear);
    void* mem = run.mem.get();
    N_Vector x = run.x.get(), v = run.v.get();
    const std::vector<Event> ev = Events(mem, 3, x, v, 1, itask);
    ASSERT_EQ(ev.size(), 2u);
    const double ttol = 100 * SUN_UNIT_ROUNDOFF * (1 + 0.25);
    EXPECT_NEAR(ev[0].t, 0.3, ttol);
    EXPECT_EQ(ev[0].info, (std::vector<int>{1, 0, 1}));
    EXPECT_NEAR(ev[1].t, 0.35, ttol);
    EXPECT_EQ(ev[1].info, (std::vector<int>{0, -1, 0}));
  }
}

namespace {
int GJump(sunrealtype t, N_Vector, N_Vector, sunrealtype* g, void*) {
  g[0] = t < SUN_RCONST(0.37) ? -1 : SUN_RCONST(1e-3);
  return 0;
}
}  // namespace

// A g that jumps (no root, a sign change) is bracketed to the time tolerance all the same, with
// a bounded number of evaluations (Illinois' weights, then halving: at most 110 per event).
TEST(RootFinding, BracketsAJumpOfG) {
  OscSetup s;
  s.h = SUN_RCONST(0.25);
  OscRun run(s, 1, GJump);
  void* mem = run.mem.get();
  N_Vector x = run.x.get(), v = run.v.get();
  const std::vector<Event> ev = Events(mem, 1, x, v, 1, CE_NORMAL);
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_NEAR(ev[0].t, 0.37, 100 * SUN_UNIT_ROUNDOFF * (1 + 0.25));
  EXPECT_GE(ev[0].t, 0.37);  // the root is the end where g has its new sign
  long nge = 0;
  CEodeGetNumGEvals(mem, &nge);
  std::printf("jump located with %ld g evaluations\n", nge);
  EXPECT_LT(nge, 4 + 2 + 110);  // one per step (four steps, the start, the end) and the search
}

// A zero exactly at a step point (0.5 = 4 h) is returned at that time, once.
TEST(RootFinding, ReturnsARootAtAStepPointOnce) {
  OscSetup s;
  s.h = SUN_RCONST(0.125);
  OscRun run(s, 1, GAtNode);
  void* mem = run.mem.get();
  N_Vector x = run.x.get(), v = run.v.get();
  const std::vector<Event> ev = Events(mem, 1, x, v, 2, CE_NORMAL);
  ASSERT_EQ(ev.size(), 1u);
  EXPECT_EQ(ev[0].t, 0.5);
  EXPECT_EQ(ev[0].info[0], 1);
}

namespace {
struct Warnings {
  int count = 0;
};
int GXAndZero(sunrealtype, N_Vector x, N_Vector, sunrealtype* g, void*) {
  g[0] = NV_Ith_S(x, 0);
  g[1] = 0;
  return 0;
}
void CountWarnings(int code, const char*, const char*, char*, void* data) {
  if (code == CE_WARNING) ++static_cast<Warnings*>(data)->count;
}
}  // namespace

// x(0) = 0: the zero at the start is not an event, the first is x's next zero at pi, for fixed
// and adaptive steps. A second function, identically zero, is never an event, and one warning
// names it (unless silenced).
TEST(RootFinding, KeepsAZeroAtTheStartInactive) {
  for (bool silence : {false, true}) {
    for (sunrealtype h : {SUN_RCONST(0.01), SUN_RCONST(0.0)}) {
      OscSetup s;
      s.h = h;
      s.tol = 1e-9;
      s.x0 = 0;
      s.v0 = 1;
      OscRun run(s);
      void* mem = run.mem.get();
      N_Vector x = run.x.get(), v = run.v.get();
      Warnings w;
      ASSERT_EQ(CEodeSetErrHandlerFn(mem, CountWarnings, &w), CE_SUCCESS);
      ASSERT_EQ(CEodeRootInit(mem, 2, GXAndZero), CE_SUCCESS);
      if (silence) ASSERT_EQ(CEodeSetNoInactiveRootWarn(mem), CE_SUCCESS);
      const std::vector<Event> ev = Events(mem, 2, x, v, 7, CE_NORMAL);
      ASSERT_EQ(ev.size(), 2u);
      EXPECT_NEAR(ev[0].t, kPi, 1e-6);
      EXPECT_EQ(ev[0].info, (std::vector<int>{-1, 0}));
      EXPECT_NEAR(ev[1].t, 2 * kPi, 1e-6);
      EXPECT_EQ(w.count, silence ? 0 : 1);
    }
  }
}

// CE_ONE_STEP returns each event as CE_NORMAL does (the same interpolant, the same times), with
// the state at the root: x(t_root) = 0 to the event-time error.
TEST(RootFinding, OneStepReturnsTheSameEventsAsNormal) {
  for (sunrealtype h : {SUN_RCONST(0.01), SUN_RCONST(0.0)}) {
    OscSetup s;
    s.h = h;
    s.tol = 1e-9;
    const std::vector<Event> normal = OscillatorEvents(s, 10);
    s.itask = CE_ONE_STEP;
    const std::vector<Event> one = OscillatorEvents(s, 10);
    ASSERT_EQ(normal.size(), one.size());
    for (size_t k = 0; k < one.size(); ++k) {
      EXPECT_EQ(one[k].t, normal[k].t);
      EXPECT_EQ(one[k].info, normal[k].info);
    }
  }
}

// The state returned with CE_ROOT_RETURN is the interpolant at the root, and the integration
// goes on from there: a later CE_NORMAL output equals the run without roots.
TEST(RootFinding, ReturnsTheStateAtTheRootAndContinues) {
  for (sunrealtype h : {SUN_RCONST(0.01), SUN_RCONST(0.0)}) {
    OscSetup s;
    s.h = h;
    s.tol = 1e-10;
    OscRun run(s, 1, GX);
    void* mem = run.mem.get();
    N_Vector x = run.x.get(), v = run.v.get();
    sunrealtype t = 0;
    ASSERT_EQ(CEodeEvolve(mem, 5, x, v, &t, CE_NORMAL), CE_ROOT_RETURN);
    EXPECT_NEAR(t, OscillatorZero(0), 1e-8);
    EXPECT_LT(std::fabs(NV_Ith_S(x, 0)), 1e-12);  // g = x is zero there to ttol
    EXPECT_NEAR(NV_Ith_S(v, 0), -std::sqrt(SUN_RCONST(1.25)), 1e-8);
    ASSERT_EQ(CEodeEvolve(mem, 7, x, v, &t, CE_NORMAL), CE_ROOT_RETURN);
    EXPECT_NEAR(t, OscillatorZero(1), 1e-8);
    ASSERT_EQ(CEodeEvolve(mem, 7, x, v, &t, CE_NORMAL), CE_SUCCESS);
    EXPECT_EQ(t, 7);
    EXPECT_NEAR(NV_Ith_S(x, 0), std::cos(7) + 0.5 * std::sin(7), 1e-7);
  }
}

namespace {

// x'' = -x - 2 zeta x' (zeta = 0.1), x(0) = 1, x'(0) = 1/2: x = e^{-zeta t} R cos(wd t - phi) with
// wd = sqrt(1 - zeta^2), tan phi = (x'(0) + zeta x(0)) / wd, zeros at (phi + pi/2 + k pi) / wd.
constexpr sunrealtype kZeta = SUN_RCONST(0.1);
int Damped(sunrealtype, N_Vector x, N_Vector v, N_Vector f, void*) {
  N_VLinearSum(-1, x, -2 * kZeta, v, f);
  return 0;
}
sunrealtype DampedZero(int k) {
  const sunrealtype wd = std::sqrt(1 - kZeta * kZeta);
  return (std::atan((SUN_RCONST(0.5) + kZeta) / wd) + kPi / 2 + k * kPi) / wd;
}

// Max |t_event - exact| over the damped oscillator's three zeros up to 10, the velocity dependence
// declared (the implicit path: Newton with a dense solver, or prediction-correction).
sunrealtype DampedEventError(const char* method, sunrealtype h, sunrealtype tol, int mode) {
  Context ctx;
  Vector x = SerialVector(1, ctx, 1), v = SerialVector(1, ctx, SUN_RCONST(0.5));
  Matrix A(SUNDenseMatrix(1, 1, ctx));
  LinearSolver LS(SUNLinSol_Dense(x.get(), A.get(), ctx));
  Mem mem(CEodeCreate(ctx));
  EXPECT_EQ(CEodeInit(mem.get(), Damped, 0, x.get(), v.get()), CE_SUCCESS);
  EXPECT_EQ(CEodeSetMethodByName(mem.get(), method), CE_SUCCESS);
  EXPECT_EQ(CEodeSetStabilityGuard(mem.get(), CE_GUARD_OFF, 0), CE_SUCCESS);
  EXPECT_EQ(h > 0 ? CEodeSetFixedStep(mem.get(), h) : CEodeSStolerances(mem.get(), tol, tol), 0);
  EXPECT_EQ(CEodeSetVelocityDependence(mem.get(), SUNTRUE), CE_SUCCESS);
  EXPECT_EQ(CEodeSetImplicitMode(mem.get(), mode), CE_SUCCESS);
  EXPECT_EQ(CEodeSetLinearSolver(mem.get(), LS.get(), A.get()), CE_SUCCESS);
  EXPECT_EQ(CEodeRootInit(mem.get(), 1, GX), CE_SUCCESS);
  const std::vector<Event> ev = Events(mem.get(), 1, x.get(), v.get(), 10, CE_NORMAL);
  EXPECT_EQ(ev.size(), 3u);
  sunrealtype err = 0;
  for (size_t k = 0; k < ev.size(); ++k) {
    err = std::max(err, std::fabs(ev[k].t - DampedZero(static_cast<int>(k))));
  }
  return err;
}

}  // namespace

// The implicit path (f reads x'): with Newton the event times converge at G5_O4's order 4 (slope
// >= 3.7 over four halvings, as on the explicit path), and with error control (Newton and
// prediction-correction) they stay within 4 tol, the explicit path's bound.
TEST(RootFinding, LocatesEventsOnTheImplicitPath) {
  std::vector<double> hs, errs;
  for (int k = 0; k < 4; ++k) {
    hs.push_back(0.08 / (1 << k));
    errs.push_back(DampedEventError("G5_O4", hs.back(), 0, CE_IMPLICIT_NEWTON));
  }
  const double slope = FitOrder(hs, errs);
  std::printf("implicit G5_O4 event-time errors %.2e .. %.2e, slope %.2f\n", errs.front(),
              errs.back(), slope);
  EXPECT_GE(slope, 3.7);
  for (int mode : {CE_IMPLICIT_NEWTON, CE_IMPLICIT_PC}) {
    const sunrealtype err = DampedEventError("G5_O4", 0, 1e-9, mode);
    std::printf("implicit G5_O4 mode %d tol 1e-9: event-time error %.2e\n", mode, err);
    EXPECT_LT(err, 4e-9);
  }
}

namespace {

// The pendulum of examples/pendulum_dae.c: q = (x, y, theta), M = diag(1, 1, 0), Phi = (x - sin
// theta, y + cos theta), released at rest from the horizontal (x = 1).
constexpr sunrealtype kGrav = SUN_RCONST(9.81);
int PendForce(sunrealtype, N_Vector, N_Vector, N_Vector f, void*) {
  NV_Ith_S(f, 0) = 0;
  NV_Ith_S(f, 1) = -kGrav;
  NV_Ith_S(f, 2) = 0;
  return 0;
}
int PendMass(sunrealtype, N_Vector, SUNMatrix M, void*, N_Vector, N_Vector, N_Vector) {
  SUNMatZero(M);
  SM_ELEMENT_D(M, 0, 0) = 1;
  SM_ELEMENT_D(M, 1, 1) = 1;
  return 0;
}
int PendPhi(sunrealtype, N_Vector q, N_Vector p, void*) {
  NV_Ith_S(p, 0) = NV_Ith_S(q, 0) - std::sin(NV_Ith_S(q, 2));
  NV_Ith_S(p, 1) = NV_Ith_S(q, 1) + std::cos(NV_Ith_S(q, 2));
  return 0;
}
int PendJac(sunrealtype, N_Vector q, SUNMatrix G, void*) {
  SUNMatZero(G);
  SM_ELEMENT_D(G, 0, 0) = 1;
  SM_ELEMENT_D(G, 0, 2) = -std::cos(NV_Ith_S(q, 2));
  SM_ELEMENT_D(G, 1, 1) = 1;
  SM_ELEMENT_D(G, 1, 2) = -std::sin(NV_Ith_S(q, 2));
  return 0;
}
// g = x, and the largest constraint residual g saw at a step point.
struct PendData {
  sunrealtype h = 0;
  sunrealtype node_residual = 0;
};
int PendG(sunrealtype t, N_Vector q, N_Vector, sunrealtype* g, void* data) {
  auto* d = static_cast<PendData*>(data);
  const sunrealtype k = d->h > 0 ? t / d->h : SUN_RCONST(0.5);
  if (std::fabs(k - std::round(k)) < 1e-9) {
    const sunrealtype r = std::hypot(NV_Ith_S(q, 0), NV_Ith_S(q, 1)) - 1;
    d->node_residual = std::max(d->node_residual, std::fabs(r));
  }
  g[0] = NV_Ith_S(q, 0);
  return 0;
}

// The times the constrained pendulum passes the bottom (x = 0) up to t = 5: fixed step h, or
// h = 0 and error control at tol.
std::vector<sunrealtype> PendulumDaeEvents(sunrealtype h, PendData* data, sunrealtype tol = 0) {
  Context ctx;
  Vector x = SerialVector(3, ctx), v = SerialVector(3, ctx, 0), p = SerialVector(2, ctx);
  Vector b = SerialVector(5, ctx);
  Matrix M(SUNDenseMatrix(3, 3, ctx)), A(SUNDenseMatrix(5, 5, ctx));
  LinearSolver LS(SUNLinSol_Dense(b.get(), A.get(), ctx));
  NV_Ith_S(x.get(), 0) = 1;
  NV_Ith_S(x.get(), 1) = 0;
  NV_Ith_S(x.get(), 2) = kPi / 2;
  Mem mem(CEodeCreate(ctx));
  data->h = h;
  EXPECT_EQ(CEodeInit(mem.get(), PendForce, 0, x.get(), v.get()), CE_SUCCESS);
  EXPECT_EQ(CEodeSetUserData(mem.get(), data), CE_SUCCESS);
  EXPECT_EQ(CEodeSetMethodByName(mem.get(), "G5_ONES"), CE_SUCCESS);
  if (h > 0) {
    EXPECT_EQ(CEodeSetZeroStart(mem.get(), SUNTRUE), CE_SUCCESS);
    EXPECT_EQ(CEodeSetFixedStep(mem.get(), h), CE_SUCCESS);
  } else {
    EXPECT_EQ(CEodeSStolerances(mem.get(), tol, tol), CE_SUCCESS);
    EXPECT_EQ(CEodeSetInitStep(mem.get(), 1e-3), CE_SUCCESS);  // from rest (wp_common.h's note)
  }
  EXPECT_EQ(CEodeSetMassFn(mem.get(), PendMass, M.get(), SUNTRUE), CE_SUCCESS);
  EXPECT_EQ(CEodeSetLinearSolver(mem.get(), LS.get(), A.get()), CE_SUCCESS);
  EXPECT_EQ(CEodeSetConstraints(mem.get(), p.get(), PendPhi, PendJac), CE_SUCCESS);
  EXPECT_EQ(CEodeRootInit(mem.get(), 1, PendG), CE_SUCCESS);
  std::vector<sunrealtype> out;
  for (const Event& e : Events(mem.get(), 1, x.get(), v.get(), 5, CE_NORMAL)) out.push_back(e.t);
  return out;
}

}  // namespace

// The DAE path: g sees positions on the constraint manifold at step points (residual at
// round-off), and the bottom passages converge: the change from h = 2e-3 to 1e-3 is below 1e-6
// and four times (two halvings of an order-4 set leave >= 16x) the change from 1e-3 to 5e-4.
TEST(RootFinding, LocatesEventsOfAConstrainedSystem) {
  PendData d1, d2, d3;
  const std::vector<sunrealtype> e1 = PendulumDaeEvents(2e-3, &d1);
  const std::vector<sunrealtype> e2 = PendulumDaeEvents(1e-3, &d2);
  const std::vector<sunrealtype> e3 = PendulumDaeEvents(5e-4, &d3);
  ASSERT_EQ(e1.size(), e3.size());
  ASSERT_EQ(e2.size(), e3.size());
  ASSERT_GE(e3.size(), 4u);  // the period of this pendulum is 2.37 s: >= 4 bottom passages
  double c12 = 0, c23 = 0;
  for (size_t k = 0; k < e3.size(); ++k) {
    c12 = std::max(c12, std::fabs(e1[k] - e2[k]));
    c23 = std::max(c23, std::fabs(e2[k] - e3[k]));
  }
  std::printf("DAE bottom passages: changes %.2e, %.2e (first at %.6f)\n", c12, c23, e3[0]);
  EXPECT_LT(c12, 1e-6);
  EXPECT_LT(4 * c23, c12);
  EXPECT_LT(d2.node_residual, 1e-13);
  // With error control at tol = 1e-8 the passages stay within 10 tol of the fixed-step ones
  // (whose own error, c23 above, is two orders smaller).
  PendData da;
  const std::vector<sunrealtype> ea = PendulumDaeEvents(0, &da, 1e-8);
  ASSERT_EQ(ea.size(), e3.size());
  double ca = 0;
  for (size_t k = 0; k < e3.size(); ++k) ca = std::max(ca, std::fabs(ea[k] - e3[k]));
  std::printf("DAE with error control (tol 1e-8): passages within %.2e of h = 5e-4\n", ca);
  EXPECT_LT(ca, 1e-7);
}

namespace {
int GFails(sunrealtype t, N_Vector, N_Vector, sunrealtype* g, void*) {
  g[0] = 1;
  return t > 0.5 ? 7 : 0;
}
int GNaN(sunrealtype t, N_Vector, N_Vector, sunrealtype* g, void*) {
  g[0] = 1;
  g[1] = t > 0.5 ? std::nan("") : 1;
  return 0;
}
void Silent(int, const char*, const char*, char*, void*) {}
std::string LastMessage(void* mem) {
  const char* msg = nullptr;
  CEodeGetLastErrorMessage(mem, &msg);
  return msg != nullptr ? msg : "";
}
}  // namespace

TEST(RootFinding, RefusesBadInputWithAFlagAndAMessage) {
  OscRun run(OscSetup{});
  void* mem = run.mem.get();
  N_Vector x = run.x.get(), v = run.v.get();
  ASSERT_EQ(CEodeSetErrHandlerFn(mem, Silent, nullptr), CE_SUCCESS);
  EXPECT_EQ(CEodeRootInit(mem, -1, GX), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(LastMessage(mem), "nrtfn = -1"));
  EXPECT_EQ(CEodeRootInit(mem, 2, nullptr), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(LastMessage(mem), "g = NULL"));
  EXPECT_EQ(CEodeSetRootDirection(mem, nullptr), CE_ILL_INPUT);  // no roots yet
  int info[2];
  EXPECT_EQ(CEodeGetRootInfo(mem, info), CE_ILL_INPUT);
  ASSERT_EQ(CEodeRootInit(mem, 1, GX), CE_SUCCESS);
  EXPECT_EQ(CEodeSetRootDirection(mem, nullptr), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(LastMessage(mem), "rootdir = NULL"));
  EXPECT_EQ(CEodeGetRootInfo(mem, nullptr), CE_ILL_INPUT);
  EXPECT_TRUE(Contains(LastMessage(mem), "rootsfound = NULL"));
  EXPECT_EQ(CEodeGetNumGEvals(mem, nullptr), CE_ILL_INPUT);
  EXPECT_EQ(CEodeRootInit(nullptr, 1, GX), CE_MEM_NULL);
  EXPECT_EQ(FlagName(CE_ROOT_RETURN), "CE_ROOT_RETURN");
  EXPECT_EQ(FlagName(CE_RTFUNC_FAIL), "CE_RTFUNC_FAIL");
}

// g failing or returning NaN stops CEodeEvolve with CE_RTFUNC_FAIL, a message naming the cause,
// and a finite state; with root finding turned off the same memory integrates on.
TEST(RootFinding, ReportsAFailingRootFunctionAndStaysUsable) {
  for (int which : {0, 1}) {
    OscRun run(OscSetup{});
    void* mem = run.mem.get();
    N_Vector x = run.x.get(), v = run.v.get();
    ASSERT_EQ(CEodeSetErrHandlerFn(mem, Silent, nullptr), CE_SUCCESS);
    ASSERT_EQ(CEodeRootInit(mem, which == 0 ? 1 : 2, which == 0 ? GFails : GNaN), 0);
    sunrealtype t = 0;
    EXPECT_EQ(CEodeEvolve(mem, 2, x, v, &t, CE_NORMAL), CE_RTFUNC_FAIL);
    EXPECT_TRUE(Contains(LastMessage(mem), which == 0 ? "returned 7" : "g[1] = nan"));
    EXPECT_TRUE(std::isfinite(NV_Ith_S(x, 0)) && std::isfinite(NV_Ith_S(v, 0)));
    EXPECT_LE(t, 0.5 + 0.01);
    ASSERT_EQ(CEodeRootInit(mem, 0, nullptr), CE_SUCCESS);
    EXPECT_EQ(CEodeEvolve(mem, 2, x, v, &t, CE_NORMAL), CE_SUCCESS);
    EXPECT_EQ(t, 2);
    EXPECT_NEAR(NV_Ith_S(x, 0), std::cos(2) + 0.5 * std::sin(2), 1e-7);
  }
}

namespace {

struct Trace {
  std::vector<sunrealtype> values;  // t, x, v of every output
  long int nfe = 0;
  long int nst = 0;
};

// The oscillator to 10 with outputs every 0.37; roots: 0 none, 1 RootInit(0), 2 RootInit(1) then
// RootInit(0), 3 g = x on (events skipped over: the outputs are those of tout).
Trace OutputTrace(sunrealtype h, int roots) {
  OscSetup s;
  s.h = h;
  s.tol = 1e-8;
  OscRun run(s);
  void* mem = run.mem.get();
  N_Vector x = run.x.get(), v = run.v.get();
  if (roots == 1) EXPECT_EQ(CEodeRootInit(mem, 0, nullptr), CE_SUCCESS);
  if (roots >= 2) EXPECT_EQ(CEodeRootInit(mem, 1, GX), CE_SUCCESS);
  if (roots == 2) EXPECT_EQ(CEodeRootInit(mem, 0, nullptr), CE_SUCCESS);
  Trace tr;
  sunrealtype t = 0;
  for (int k = 1; k * SUN_RCONST(0.37) <= 10; ++k) {
    int flag = CE_ROOT_RETURN;
    while (flag == CE_ROOT_RETURN) flag = CEodeEvolve(mem, k * 0.37, x, v, &t, CE_NORMAL);
    EXPECT_EQ(flag, CE_SUCCESS);
    tr.values.insert(tr.values.end(), {t, NV_Ith_S(x, 0), NV_Ith_S(v, 0)});
  }
  CEodeGetNumRhsEvals(mem, &tr.nfe);
  CEodeGetNumSteps(mem, &tr.nst);
  return tr;
}

}  // namespace

// nrtfn = 0 is the run without root finding bit for bit, fixed and adaptive.
TEST(RootFinding, TurnedOffLeavesTheRunBitwiseUnchanged) {
  for (sunrealtype h : {SUN_RCONST(0.01), SUN_RCONST(0.0)}) {
    const Trace ref = OutputTrace(h, 0);
    for (int roots : {1, 2}) {
      const Trace tr = OutputTrace(h, roots);
      ASSERT_EQ(tr.values.size(), ref.values.size());
      EXPECT_EQ(
          std::memcmp(tr.values.data(), ref.values.data(), ref.values.size() * sizeof(sunrealtype)),
          0);
      EXPECT_EQ(tr.nfe, ref.nfe);
      EXPECT_EQ(tr.nst, ref.nst);
    }
  }
}

// Root finding evaluates g on the dense output only: the run with events takes the same steps
// with the same f evaluations as without, and its outputs at tout are the same.
TEST(RootFinding, CostsNoRhsEvaluations) {
  for (sunrealtype h : {SUN_RCONST(0.01), SUN_RCONST(0.0)}) {
    const Trace ref = OutputTrace(h, 0);
    const Trace tr = OutputTrace(h, 3);
    EXPECT_EQ(tr.nfe, ref.nfe);
    EXPECT_EQ(tr.nst, ref.nst);
    ASSERT_EQ(tr.values.size(), ref.values.size());
    for (size_t i = 0; i < ref.values.size(); ++i) EXPECT_EQ(tr.values[i], ref.values[i]) << i;
  }
}

// CEodeReset restarts at a changed state and keeps the counters and the step: after reversing
// the velocity at the first zero, x follows the reflected oscillation.
TEST(RootFinding, ResetRestartsFromTheEventState) {
  for (sunrealtype h : {SUN_RCONST(0.01), SUN_RCONST(0.0)}) {
    OscSetup s;
    s.h = h;
    s.tol = 1e-10;
    OscRun run(s, 1, GX);
    void* mem = run.mem.get();
    N_Vector x = run.x.get(), v = run.v.get();
    sunrealtype t = 0;
    ASSERT_EQ(CEodeEvolve(mem, 8, x, v, &t, CE_NORMAL), CE_ROOT_RETURN);
    long int nst0 = 0, nst1 = 0, nge = 0;
    CEodeGetNumSteps(mem, &nst0);
    const sunrealtype t0 = t, v0 = -NV_Ith_S(v, 0);
    sunrealtype hnext = 0, h0 = 0;
    CEodeGetCurrentStep(mem, &hnext);
    N_VScale(-1, v, v);
    NV_Ith_S(x, 0) = 0;  // the event's state exactly: g = 0 there, inactive at the restart
    ASSERT_EQ(CEodeReset(mem, t0, x, v), CE_SUCCESS);
    // The reflected motion x = v0 sin(t - t0) has its next zero at t0 + pi.
    ASSERT_EQ(CEodeEvolve(mem, 8, x, v, &t, CE_NORMAL), CE_ROOT_RETURN);
    EXPECT_NEAR(t, t0 + kPi, 1e-7);
    CEodeGetActualInitStep(mem, &h0);
    EXPECT_EQ(h0, hnext);  // the controller's step (or the fixed step) goes on
    ASSERT_EQ(CEodeEvolve(mem, 8, x, v, &t, CE_NORMAL), CE_SUCCESS);
    EXPECT_NEAR(NV_Ith_S(x, 0), v0 * std::sin(8 - t0), 1e-7);
    CEodeGetNumSteps(mem, &nst1);
    CEodeGetNumGEvals(mem, &nge);
    EXPECT_GT(nst1, nst0);
    EXPECT_GT(nge, nst1);  // one g a step at least, counted across the reset
  }
}

// A reset refused for its arguments (a NaN time, a state of the wrong length) leaves the memory
// as it was: a later CEodeReInit starts exactly as one without the refused calls.
TEST(RootFinding, ARefusedResetChangesNothing) {
  for (sunrealtype h : {SUN_RCONST(0.01), SUN_RCONST(0.0)}) {
    std::vector<sunrealtype> end[2];
    for (int refuse : {0, 1}) {
      OscSetup s;
      s.h = h;
      s.tol = 1e-8;
      OscRun run(s, 1, GX);
      void* mem = run.mem.get();
      N_Vector x = run.x.get(), v = run.v.get();
      ASSERT_EQ(CEodeSetErrHandlerFn(mem, Silent, nullptr), CE_SUCCESS);
      sunrealtype t = 0;
      ASSERT_EQ(CEodeEvolve(mem, 1, x, v, &t, CE_NORMAL), CE_SUCCESS);
      if (refuse == 1) {
        Vector wrong = SerialVector(2, run.ctx);
        EXPECT_EQ(CEodeReset(mem, NAN, x, v), CE_ILL_INPUT);
        EXPECT_EQ(CEodeReset(mem, t, wrong.get(), wrong.get()), CE_ILL_INPUT);
      }
      NV_Ith_S(x, 0) = 1;
      NV_Ith_S(v, 0) = SUN_RCONST(0.5);
      ASSERT_EQ(CEodeReInit(mem, 0, x, v), CE_SUCCESS);
      ASSERT_EQ(CEodeEvolve(mem, 3, x, v, &t, CE_NORMAL), CE_ROOT_RETURN);
      long nst = 0;
      sunrealtype h0 = 0;
      CEodeGetNumSteps(mem, &nst);
      CEodeGetActualInitStep(mem, &h0);
      end[refuse] = {t, NV_Ith_S(x, 0), NV_Ith_S(v, 0), static_cast<sunrealtype>(nst), h0};
    }
    EXPECT_EQ(end[1], end[0]);
  }
}
