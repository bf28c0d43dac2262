// -----------------------------------------------------------------------------
// fe_scene.h: the runners shared by the FE plate scenes (bench/wp_fe_plate.cpp,
// wp_fe_nonlinear.cpp, wp_fe_damped_mass.cpp, wp_fe_damped_stiff.cpp): one problem
// description, CEODE on the second-order form (explicit, or implicit with
// prediction-correction, fixed point or Newton with a matrix-free SPGMR), SUNDIALS on
// the first-order form y = (x, v) (ARKODE ERK adaptive, CVODE Adams, CVODE BDF + SPGMR
// or + KLU with the scene's sparse Jacobian, ARKStep IMEX + SPGMR, ARKStep DIRK +
// SPGMR), and the equal-error figures the scenes print.
//
// Every solver integrates to the nout output instants tend k / nout in its normal
// mode (no per-step output); the error is the maximum over those instants of
// ||x - x_ref||_2 / ||x0||_2, x_ref a table the scene fills (modal closed form or a
// converged run). Rows go through wp::Table (bench/wp_common.h), timings through
// wp::TimeMedian.
// -----------------------------------------------------------------------------
#ifndef CEODE_BENCH_FE_SCENE_H_
#define CEODE_BENCH_FE_SCENE_H_

#include <sunlinsol/sunlinsol_spgmr.h>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "wp_common.h"

namespace fes {

using Vec = std::vector<double>;

struct Problem {
  int n = 0;  // DOFs of x
  void* user = nullptr;
  CEodeRhsFn f2 = nullptr;              // a = f(t, x, v), accelerations
  ARKRhsFn f1 = nullptr;                // (v, a) on y = (x, v)
  ARKRhsFn fe = nullptr, fi = nullptr;  // IMEX split of f1 (fi the stiff, implicit part)
  bool fi_linear = false;               // fi linear in y (ARKStepSetLinear)
  bool f1_linear = false;               // f1 linear in y (ARKStepSetLinear for the DIRK)
  CVLsJacFn jac1 = nullptr;             // sparse CSR Jacobian of f1 (CVODE BDF + KLU)
  long jac_nnz = 0;                     // its nonzeros
  Vec x0, v0, mass;                     // mass: lumped, for the guard's inner product
  double tend = 0;
  int nout = 20;
  std::vector<Vec> ref;  // x_ref at tend k / nout, k = 1..nout
  double x0norm = 1;
};

inline double OutputTime(const Problem& p, int k) { return p.tend * k / p.nout; }

inline double RelError(const Problem& p, int k, const double* x) {
  const Vec& r = p.ref[k - 1];
  double e2 = 0;
  for (int i = 0; i < p.n; ++i) e2 += (x[i] - r[i]) * (x[i] - r[i]);
  return std::sqrt(e2) / p.x0norm;
}

inline double Norm2(const Vec& x) {
  double s = 0;
  for (double q : x) s += q * q;
  return std::sqrt(s);
}

// Fixed steps: h = (tend / nout) / m with the smallest m that keeps h <= h_req, so
// every output instant is a step point.
inline long StepsPerOutput(const Problem& p, double h_req) {
  return static_cast<long>(std::ceil(p.tend / p.nout / h_req - 1e-9));
}
inline double FixedStep(const Problem& p, double h_req) {
  return p.tend / p.nout / static_cast<double>(StepsPerOutput(p, h_req));
}

// ------------------------------------------------------------------- CEODE
// How CEODE is told about f's velocity dependence and how it solves the step.
struct CeodeCfg {
  const char* method = "G3_CD";
  bool vel = false;  // declared (implicit step); false: CEodeSetVelocityDependence(FALSE)
  int mode = CE_IMPLICIT_NEWTON;  // CEodeSetImplicitMode
  bool spgmr = false;             // Newton with a matrix-free SPGMR (else fixed point)
  int maxl = 20;
  double nls_rtol = 0;  // CEodeSetNonlinTolerances(rtol, 1e-2 rtol): |a| ~ 1e-2; 0: CEODE's default
};

struct CeodeStats {
  long nni = 0, nfe_dq = 0, npc = 0, nnls = 0;
  double coupling = 0;
};

// x(t) at the output instants into xs (when not null).
inline int CeodeRun(SUNContext ctx, Problem* p, const CeodeCfg& c, double h_req, wp::Outcome* out,
                    CeodeStats* st = nullptr, std::vector<Vec>* xs = nullptr) {
  wp::CeodeObjects o(ctx, p->n);
  if (o.mem == nullptr || o.x == nullptr) return 1;
  std::copy(p->x0.begin(), p->x0.end(), N_VGetArrayPointer(o.x));
  std::copy(p->v0.begin(), p->v0.end(), N_VGetArrayPointer(o.v));
  const double h = FixedStep(*p, h_req);
  void* mem = o.mem;
  bool bad = wp::Failed(CEodeInit(mem, p->f2, 0, o.x, o.v), "CEodeInit") ||
             wp::Failed(CEodeSetUserData(mem, p->user), "CEodeSetUserData") ||
             wp::Failed(CEodeSetMethodByName(mem, c.method), "CEodeSetMethodByName") ||
             wp::Failed(CEodeSetFixedStep(mem, h), "CEodeSetFixedStep") ||
             wp::Failed(CEodeSetStabilityGuard(mem, CE_GUARD_OFF, 0), "CEodeSetStabilityGuard") ||
             wp::Failed(CEodeSetMaxNumSteps(mem, 100000000L), "CEodeSetMaxNumSteps") ||
             wp::Failed(CEodeSetStopTime(mem, p->tend), "CEodeSetStopTime") ||
             wp::Failed(CEodeSetVelocityDependence(mem, c.vel ? SUNTRUE : SUNFALSE),
                        "CEodeSetVelocityDependence");
  if (!bad && c.vel) {
    bad =
        wp::Failed(CEodeSetImplicitMode(mem, c.mode), "CEodeSetImplicitMode") ||
        (c.nls_rtol > 0 && wp::Failed(CEodeSetNonlinTolerances(mem, c.nls_rtol, 1e-2 * c.nls_rtol),
                                      "CEodeSetNonlinTolerances"));
    if (!bad && c.spgmr) {
      o.LS = SUNLinSol_SPGMR(o.x, SUN_PREC_NONE, c.maxl, ctx);
      // Restarts: without them an unpreconditioned SPGMR stalls on M + kappa b K and the
      // Newton iteration at CEODE's 1e-12 tolerance fails (measured at 0.9 h_s, 3 360 DOF).
      bad = o.LS == nullptr || SUNLinSol_SPGMRSetMaxRestarts(o.LS, 5) != 0 ||
            wp::Failed(CEodeSetLinearSolver(mem, o.LS, nullptr), "CEodeSetLinearSolver");
    }
  }
  double emax = 0, t = 0;
  for (int k = 1; k <= p->nout && !bad; ++k) {
    bad = wp::Failed(CEodeEvolve(mem, OutputTime(*p, k), o.x, o.v, &t, CE_NORMAL), "CEodeEvolve");
    if (bad) break;
    const double* xd = N_VGetArrayPointer(o.x);
    if (xs != nullptr) xs->emplace_back(xd, xd + p->n);
    const double e = p->ref.empty() ? 0 : RelError(*p, k, xd);
    if (!(e <= emax)) emax = e;
  }
  long nfe = 0, nfe_dq = 0;
  bad = bad || wp::Failed(CEodeGetNumSteps(mem, &out->steps), "CEodeGetNumSteps") ||
        wp::Failed(CEodeGetNumRhsEvals(mem, &nfe), "CEodeGetNumRhsEvals") ||
        wp::Failed(CEodeGetNumRhsEvalsJacDQ(mem, &nfe_dq), "CEodeGetNumRhsEvalsJacDQ");
  if (!bad && st != nullptr) {
    long nfc = 0;
    st->nfe_dq = nfe_dq;
    bad = wp::Failed(CEodeGetNumNonlinSolvIters(mem, &st->nni), "CEodeGetNumNonlinSolvIters") ||
          wp::Failed(CEodeGetImplicitStats(mem, &st->npc, &st->nnls, &nfc, &st->coupling),
                     "CEodeGetImplicitStats");
  }
  out->rhs_evals = nfe + nfe_dq;
  out->error = emax;
  return bad || !std::isfinite(emax) ? 1 : 0;
}

// The stable step of a set from the guard (CEodeGetStableStep, safety 1) at x0.
inline double GuardStep(SUNContext ctx, Problem* p, const char* method) {
  wp::CeodeObjects o(ctx, p->n);
  std::copy(p->x0.begin(), p->x0.end(), N_VGetArrayPointer(o.x));
  std::copy(p->v0.begin(), p->v0.end(), N_VGetArrayPointer(o.v));
  N_Vector m = N_VNew_Serial(p->n, ctx);
  if (m == nullptr) return 0;
  std::copy(p->mass.begin(), p->mass.end(), N_VGetArrayPointer(m));
  sunrealtype h = 0;
  if (wp::Failed(CEodeInit(o.mem, p->f2, 0, o.x, o.v), "CEodeInit") ||
      wp::Failed(CEodeSetUserData(o.mem, p->user), "CEodeSetUserData") ||
      wp::Failed(CEodeSetMethodByName(o.mem, method), "CEodeSetMethodByName") ||
      wp::Failed(CEodeSetVelocityDependence(o.mem, SUNFALSE), "CEodeSetVelocityDependence") ||
      wp::Failed(CEodeSetGuardMass(o.mem, m), "CEodeSetGuardMass") ||
      wp::Failed(CEodeGetStableStep(o.mem, 1, &h), "CEodeGetStableStep")) {
    h = 0;
  }
  N_VDestroy(m);
  return h;
}

// --------------------------------------------------------------- hand loop
// Leapfrog, the loop explicit FE codes write (the practical limit, solver "CEODE-hand"):
// v_{n+1/2} = v_{n-1/2} + h a_n, x_{n+1} = x_n + h v_{n+1/2}, one accel(x, a) call and one
// fused update pass per step; the same method as CEODE G3_CD.
template <class Accel>
int LeapfrogRun(const Problem& pr, double h_req, const Accel& accel, wp::Outcome* out) {
  const int n = pr.n;
  const long m = StepsPerOutput(pr, h_req);
  const double h = FixedStep(pr, h_req);
  Vec x(pr.x0), v(n), a(n);
  accel(x.data(), a.data());
  for (int k = 0; k < n; ++k) {
    v[k] = pr.v0[k] + 0.5 * h * a[k];
    x[k] += h * v[k];
  }
  double emax = 0;
  long steps = 1;
  for (int o = 1; o <= pr.nout; ++o) {
    for (long j = (o == 1 ? 1 : 0); j < m; ++j, ++steps) {
      accel(x.data(), a.data());
      for (int k = 0; k < n; ++k) {
        v[k] += h * a[k];
        x[k] += h * v[k];
      }
    }
    const double e = pr.ref.empty() ? 0 : RelError(pr, o, x.data());
    if (!(e <= emax)) emax = e;
  }
  out->steps = steps;
  out->rhs_evals = steps;
  out->error = emax;
  return std::isfinite(emax) ? 0 : 1;
}

// ---------------------------------------------------------------- SUNDIALS
enum class Kind { kErk, kAdams, kBdfSpgmr, kBdfKlu, kImexSpgmr, kDirkSpgmr };

struct SunConfig {
  Kind kind;
  int order;  // ERK only
  const char* solver;
  const char* config;
};

// The objects of one SUNDIALS run, freed together.
struct SunObjects {
  N_Vector y = nullptr;
  SUNMatrix J = nullptr;
  SUNLinearSolver LS = nullptr;
  SUNNonlinearSolver NLS = nullptr;
  void* mem = nullptr;
  Kind kind = Kind::kErk;
  SunObjects() = default;
  SunObjects(const SunObjects&) = delete;
  SunObjects& operator=(const SunObjects&) = delete;
  ~SunObjects() {
    if (kind == Kind::kErk) ERKStepFree(&mem);
    if (kind == Kind::kImexSpgmr || kind == Kind::kDirkSpgmr) ARKStepFree(&mem);
    if (kind == Kind::kAdams || kind == Kind::kBdfSpgmr || kind == Kind::kBdfKlu) CVodeFree(&mem);
    if (NLS != nullptr) SUNNonlinSolFree(NLS);
    if (LS != nullptr) SUNLinSolFree(LS);
    if (J != nullptr) SUNMatDestroy(J);
    if (y != nullptr) N_VDestroy(y);
  }
};

// Krylov dimension of SPGMR: the default 5 stalls on I - gamma J at large gamma omega_max.
constexpr int kMaxl = 20;

inline bool ArkSetup(Problem* p, const SunConfig& c, double tol, SUNContext ctx, SunObjects* o) {
  const bool imex = c.kind == Kind::kImexSpgmr;
  o->mem = imex ? ARKStepCreate(p->fe, p->fi, 0, o->y, ctx)
                : ARKStepCreate(nullptr, p->f1, 0, o->y, ctx);
  o->LS = SUNLinSol_SPGMR(o->y, SUN_PREC_NONE, kMaxl, ctx);
  return o->mem != nullptr && o->LS != nullptr &&
         !wp::Failed(ARKStepSetUserData(o->mem, p->user), "ARKStepSetUserData") &&
         !wp::Failed(ARKStepSetMaxNumSteps(o->mem, 100000000L), "ARKStepSetMaxNumSteps") &&
         !wp::Failed(ARKStepSStolerances(o->mem, tol, tol), "ARKStepSStolerances") &&
         !wp::Failed(ARKStepSetLinearSolver(o->mem, o->LS, nullptr), "ARKStepSetLinearSolver") &&
         (!(imex ? p->fi_linear : p->f1_linear) ||
          !wp::Failed(ARKStepSetLinear(o->mem, 0), "ARKStepSetLinear"));
}

// atol = tol: |x| <= O(1) and the error is relative to ||x0||.
inline bool SunSetup(SUNContext ctx, Problem* p, const SunConfig& c, double tol, SunObjects* o) {
  if (c.kind == Kind::kErk) {
    o->mem = ERKStepCreate(p->f1, 0, o->y, ctx);
    return o->mem != nullptr &&
           !wp::Failed(ERKStepSetUserData(o->mem, p->user), "ERKStepSetUserData") &&
           !wp::Failed(ERKStepSetOrder(o->mem, c.order), "ERKStepSetOrder") &&
           !wp::Failed(ERKStepSetMaxNumSteps(o->mem, 100000000L), "ERKStepSetMaxNumSteps") &&
           !wp::Failed(ERKStepSStolerances(o->mem, tol, tol), "ERKStepSStolerances");
  }
  if (c.kind == Kind::kImexSpgmr || c.kind == Kind::kDirkSpgmr) return ArkSetup(p, c, tol, ctx, o);
  o->mem = CVodeCreate(c.kind == Kind::kAdams ? CV_ADAMS : CV_BDF, ctx);
  const bool ok = o->mem != nullptr &&
                  !wp::Failed(CVodeInit(o->mem, p->f1, 0, o->y), "CVodeInit") &&
                  !wp::Failed(CVodeSetUserData(o->mem, p->user), "CVodeSetUserData") &&
                  !wp::Failed(CVodeSetMaxNumSteps(o->mem, 100000000L), "CVodeSetMaxNumSteps") &&
                  !wp::Failed(CVodeSStolerances(o->mem, tol, tol), "CVodeSStolerances");
  if (!ok) return false;
  if (c.kind == Kind::kAdams) {
    o->NLS = SUNNonlinSol_FixedPoint(o->y, 0, ctx);
    return o->NLS != nullptr &&
           !wp::Failed(CVodeSetNonlinearSolver(o->mem, o->NLS), "CVodeSetNonlinearSolver");
  }
  if (c.kind == Kind::kBdfSpgmr) {
    o->LS = SUNLinSol_SPGMR(o->y, SUN_PREC_NONE, kMaxl, ctx);
    return o->LS != nullptr &&
           !wp::Failed(CVodeSetLinearSolver(o->mem, o->LS, nullptr), "CVodeSetLinearSolver");
  }
  o->J = SUNSparseMatrix(2 * p->n, 2 * p->n, p->jac_nnz, CSR_MAT, ctx);
  o->LS = o->J != nullptr ? SUNLinSol_KLU(o->y, o->J, ctx) : nullptr;
  return o->LS != nullptr && p->jac1 != nullptr &&
         !wp::Failed(CVodeSetLinearSolver(o->mem, o->LS, o->J), "CVodeSetLinearSolver") &&
         !wp::Failed(CVodeSetJacFn(o->mem, p->jac1), "CVodeSetJacFn");
}

inline int SunEvolve(const SunObjects& o, double tout, double* t) {
  if (o.kind == Kind::kErk) return ERKStepEvolve(o.mem, tout, o.y, t, ARK_NORMAL);
  if (o.kind == Kind::kImexSpgmr || o.kind == Kind::kDirkSpgmr) {
    return ARKStepEvolve(o.mem, tout, o.y, t, ARK_NORMAL);
  }
  return CVode(o.mem, tout, o.y, t, CV_NORMAL);
}

// f evaluations of every kind (explicit, implicit, the Krylov products' difference quotients).
inline bool SunCounters(const SunObjects& o, wp::Outcome* out) {
  long nfe = 0, nfi = 0, nfls = 0;
  bool ok = true;
  if (o.kind == Kind::kErk) {
    ok = ERKStepGetNumSteps(o.mem, &out->steps) == 0 && ERKStepGetNumRhsEvals(o.mem, &nfe) == 0;
  } else if (o.kind == Kind::kImexSpgmr || o.kind == Kind::kDirkSpgmr) {
    ok = ARKStepGetNumSteps(o.mem, &out->steps) == 0 &&
         ARKStepGetNumRhsEvals(o.mem, &nfe, &nfi) == 0 &&
         ARKStepGetNumLinRhsEvals(o.mem, &nfls) == 0;
  } else {
    ok = CVodeGetNumSteps(o.mem, &out->steps) == 0 && CVodeGetNumRhsEvals(o.mem, &nfe) == 0 &&
         (o.kind == Kind::kAdams || CVodeGetNumLinRhsEvals(o.mem, &nfls) == 0);
  }
  out->rhs_evals = nfe + nfi + nfls;
  return ok;
}

inline int SunRun(SUNContext ctx, Problem* p, const SunConfig& c, double tol, wp::Outcome* out) {
  const int n = p->n;
  SunObjects o;
  o.kind = c.kind;
  o.y = N_VNew_Serial(2 * n, ctx);
  if (o.y == nullptr) return 1;
  double* Y = N_VGetArrayPointer(o.y);
  std::copy(p->x0.begin(), p->x0.end(), Y);
  std::copy(p->v0.begin(), p->v0.end(), Y + n);
  bool bad = !SunSetup(ctx, p, c, tol, &o);
  double emax = 0, t = 0;
  for (int k = 1; k <= p->nout && !bad; ++k) {
    bad = wp::Failed(SunEvolve(o, OutputTime(*p, k), &t), "Evolve");
    const double e = bad ? 0 : RelError(*p, k, Y);
    if (!(e <= emax)) emax = e;
  }
  bad = bad || !SunCounters(o, out);
  out->error = emax;
  return bad || !std::isfinite(emax) ? 1 : 0;
}

// A SUNDIALS curve stops after the first tolerance whose run takes longer than this (CPU s; the
// run that crosses it is kept). A timed point used to run six times (wp::TimeMedian): with 5 s and
// tolerances down to 1e-7, wp_fe_damped_mass alone took 757 s.
constexpr double kSundialsCutoff = 1.5;

// One curve per configuration over the tolerances; a curve stops once one run costs
// max_seconds (it is past every CEODE point by then) or fails.
inline void SundialsCurves(SUNContext ctx, Problem* p, const std::vector<SunConfig>& configs,
                           const std::vector<double>& tols, double max_seconds,
                           wp::Rounds* rounds) {
  for (const SunConfig& c : configs) {
    for (double tol : tols) {
      const double first =
          rounds->Measure(c.solver, c.config, tol,
                          [ctx, p, c, tol](wp::Outcome* o) { return SunRun(ctx, p, c, tol, o); });
      if (first < 0 || first > max_seconds) break;
    }
  }
}

// The SUNDIALS configurations every plate variant is compared with, over one tolerance list.
inline void PeerCurves(SUNContext ctx, Problem* p, bool quick, wp::Rounds* rounds) {
  const std::vector<SunConfig> configs = {
      {Kind::kErk, 3, "ARKODE-ERK", "order3"},      {Kind::kErk, 4, "ARKODE-ERK", "order4"},
      {Kind::kErk, 5, "ARKODE-ERK", "order5"},      {Kind::kAdams, 0, "CVODE-Adams", "fixedpoint"},
      {Kind::kBdfSpgmr, 0, "CVODE-BDF", "SPGMR"},   {Kind::kImexSpgmr, 0, "ARKODE-IMEX", "SPGMR"},
      {Kind::kDirkSpgmr, 0, "ARKODE-DIRK", "SPGMR"}};
  const std::vector<double> tols =
      quick ? std::vector<double>{1e-4} : std::vector<double>{1e-3, 1e-4, 1e-5, 1e-6};
  SundialsCurves(ctx, p, configs, tols, quick ? 0.3 : kSundialsCutoff, rounds);
}

// ------------------------------------------------------------ equal error
// At each level, the best CEODE curve against the best SUNDIALS curve and the best hand loop
// (time at equal error, wp::TimeAtError); < 1 means CEODE is faster.
inline void PrintJudged(const wp::Table& table, const std::vector<double>& levels) {
  std::vector<std::pair<std::string, std::string>> curves;
  for (const wp::Row& r : table.rows()) {
    const auto key = std::make_pair(r.solver, r.config);
    if (std::find(curves.begin(), curves.end(), key) == curves.end()) curves.push_back(key);
  }
  std::printf(
      "\ntime at equal relative position error\n%7s %-24s %10s %-24s %10s %-18s %10s %8s %8s\n",
      "error", "best CEODE", "s", "best SUNDIALS", "s", "best hand", "s", "CE/SUN", "CE/hand");
  for (double e : levels) {
    double best[3] = {-1, -1, -1};  // CEODE, SUNDIALS, hand
    std::string name[3] = {"not reached", "not reached", "not reached"};
    for (const auto& k : curves) {
      const double t = wp::TimeAtError(table.rows(), k.first, k.second, e);
      const int side = k.first == "CEODE" ? 0 : (k.first == "CEODE-hand" ? 2 : 1);
      if (t > 0 && (best[side] < 0 || t < best[side])) {
        best[side] = t;
        name[side] = k.first + " " + k.second;
      }
    }
    std::printf("%7.0e %-24s %10.3e %-24s %10.3e %-18s %10.3e %8.3f %8.3f\n", e, name[0].c_str(),
                best[0], name[1].c_str(), best[1], name[2].c_str(), best[2],
                best[0] > 0 && best[1] > 0 ? best[0] / best[1] : 0.0,
                best[0] > 0 && best[2] > 0 ? best[0] / best[2] : 0.0);
  }
}

// Observed order of one curve from its last three rows (h_or_tol is the step).
inline double CurveOrder(const wp::Table& table, const std::string& solver,
                         const std::string& config) {
  std::vector<const wp::Row*> c;
  for (const wp::Row& r : table.rows()) {
    if (r.solver == solver && r.config == config) c.push_back(&r);
  }
  if (c.size() < 2) return 0;
  const wp::Row* a = c.size() >= 3 ? c[c.size() - 3] : c[0];
  const wp::Row* b = c.back();
  return std::log(a->error / b->error) / std::log(a->h_or_tol / b->h_or_tol);
}

// The rows of two curves at the same steps agree (same method written twice).
inline int CheckSameMethod(const wp::Table& table, const std::string& s1, const std::string& c1,
                           const std::string& s2, const std::string& c2, double rel) {
  std::vector<const wp::Row*> a, b;
  for (const wp::Row& r : table.rows()) {
    if (r.solver == s1 && r.config == c1) a.push_back(&r);
    if (r.solver == s2 && r.config == c2) b.push_back(&r);
  }
  int bad = 0;
  for (size_t i = 0; i < a.size() && i < b.size(); ++i) {
    const double d = std::fabs(a[i]->error - b[i]->error);
    const bool ok = d <= rel * a[i]->error + 1e-14;
    if (!ok) {
      std::printf("%s %s vs %s %s at h = %.4e: error %.6e vs %.6e -- MISMATCH\n", s1.c_str(),
                  c1.c_str(), s2.c_str(), c2.c_str(), a[i]->h_or_tol, a[i]->error, b[i]->error);
    }
    bad += !ok;
  }
  return bad;
}

}  // namespace fes

#endif  // CEODE_BENCH_FE_SCENE_H_
