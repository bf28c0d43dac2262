// Root finding (events): the user's functions g_i(t, x, v) are checked for a sign change over
// every step on the dense output, and a root is located by the Illinois variant of regula falsi
// on the interpolant (docs/theory.md, "Event location"), as CVODE's cvRootfind does on its own.
// The record (CERootMem) is written only here; the core holds a pointer, null when off.
#include <algorithm>
#include <cmath>
#include <new>
#include <vector>

#include "ceode_adapt.hpp"
#include "ceode_impl.hpp"

namespace ceode {

struct CERootMem {
  CEodeRootFn g = nullptr;
  int nrtfn = 0;
  std::vector<int> dir;   // +1 / -1: only increasing / decreasing roots; 0: both
  std::vector<int> info;  // CEodeGetRootInfo: +1 / -1 at the last root return, else 0
  std::vector<sunrealtype> glo, ghi, gmid;
  sunrealtype tlo = 0;     // checked up to here; glo = g(tlo) (g_i = 0: inactive)
  sunrealtype troot = 0;   // the last root returned
  bool need_start = true;  // g(tlo) is evaluated at the next check (init, restart)
  bool warn_inactive = true;
  bool check_null = false;  // the first check after a start warns of a g_i that stays zero
  long int nge = 0;
  N_Vector x = nullptr;  // the state handed to g
  N_Vector v = nullptr;
};

void RootMemFree::operator()(CERootMem* rm) const {
  if (rm == nullptr) return;
  if (rm->x != nullptr) N_VDestroy(rm->x);
  if (rm->v != nullptr) N_VDestroy(rm->v);
  delete rm;
}

namespace {

// The interval the dense output covers: the next step [tcur, tcur + h] (fixed steps) or the
// last accepted step [tcur - hlast, tcur] (error control; empty before the first step).
void DenseInterval(const CEodeMemRec* ce, sunrealtype* a, sunrealtype* b) {
  if (AdaptOn(ce)) {
    *a = ce->tcur - ce->adapt->hlast;
    *b = ce->tcur;
  } else {
    *a = ce->tcur;
    *b = ce->tcur + ce->h;
  }
}

// x and v at t from the dense output; at a step point the method's own values (at the fixed
// step's right end the position x(tcur + h), which meets the constraints of a DAE).
void StateAt(CEodeMemRec* ce, CERootMem* rm, sunrealtype t) {
  const sunrealtype s = t - ce->tcur;
  Interpolate(ce, s, 0, rm->x);
  Interpolate(ce, s, 1, rm->v);
  if (!AdaptOn(ce) && s == ce->h) N_VScale(1, ce->xnext, rm->x);
}

int EvalG(CEodeMemRec* ce, CERootMem* rm, sunrealtype t, sunrealtype* g, const char* func) {
  StateAt(ce, rm, t);
  const int rv = rm->g(t, rm->x, rm->v, g, ce->user_data);
  ++rm->nge;
  if (rv != 0) {
    return ProcessError(ce, CE_RTFUNC_FAIL, func,
                        "The root function g failed at t = %.17g (it returned %d).",
                        static_cast<double>(t), rv);
  }
  for (int i = 0; i < rm->nrtfn; ++i) {
    if (!std::isfinite(g[i])) {
      return ProcessError(ce, CE_RTFUNC_FAIL, func,
                          "The root function returned g[%d] = %g at t = %.17g: every component "
                          "must be finite.",
                          i, static_cast<double>(g[i]), static_cast<double>(t));
    }
  }
  return CE_SUCCESS;
}

// g at the first check after an init, a restart or a change of the dense interval; a component
// zero there is inactive until it moves away from zero.
int StartRoots(CEodeMemRec* ce, CERootMem* rm, sunrealtype t, const char* func) {
  if (rm->x == nullptr || N_VGetLength(rm->x) != ce->n) {
    if (rm->x != nullptr) N_VDestroy(rm->x);
    if (rm->v != nullptr) N_VDestroy(rm->v);
    rm->x = CloneVector(ce->xcur);
    rm->v = CloneVector(ce->xcur);
    if (rm->x == nullptr || rm->v == nullptr) {
      return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory (root finding vectors).");
    }
  }
  const int flag = EvalG(ce, rm, t, rm->glo.data(), func);
  if (flag != CE_SUCCESS) return flag;
  rm->tlo = t;
  rm->need_start = false;
  rm->check_null = rm->warn_inactive;
  return CE_SUCCESS;
}

// A component zero at the start and still zero at the end of the first interval is most likely
// identically zero (as CVODE warns): it stays inactive until it moves away from zero.
void WarnNull(CEodeMemRec* ce, CERootMem* rm, sunrealtype t, const char* func) {
  rm->check_null = false;
  for (int i = 0; i < rm->nrtfn; ++i) {
    if (rm->glo[i] == 0 && rm->ghi[i] == 0) {
      ProcessError(ce, CE_WARNING, func,
                   "g[%d] = 0 from t = %.17g to %.17g: it is inactive until it moves away from "
                   "zero (CEodeSetNoInactiveRootWarn silences this).",
                   i, static_cast<double>(rm->tlo), static_cast<double>(t));
    }
  }
}

// Whether component i has a root of the wanted direction in (t_a, t_b] from g_a, g_b: a sign
// change, or g_b = 0. g_a = 0 is an inactive component.
bool Brackets(const CERootMem& rm, int i, const sunrealtype* ga, const sunrealtype* gb) {
  if (ga[i] == 0 || (rm.dir[i] != 0 && rm.dir[i] * ga[i] > 0)) return false;
  return gb[i] == 0 || (ga[i] < 0) != (gb[i] < 0);
}

// The component the secant follows: of those with a strict sign change, the one whose linear
// crossing comes first (largest |g_b| / |g_b - g_a|); -1 when none changes sign strictly.
int Leading(const CERootMem& rm, const sunrealtype* ga, const sunrealtype* gb, bool* any) {
  int imax = -1;
  sunrealtype best = -1;
  *any = false;
  for (int i = 0; i < rm.nrtfn; ++i) {
    if (!Brackets(rm, i, ga, gb)) continue;
    *any = true;
    if (gb[i] == 0) continue;
    const sunrealtype frac = std::fabs(gb[i]) / std::fabs(gb[i] - ga[i]);
    if (frac > best) {
      best = frac;
      imax = i;
    }
  }
  return imax;
}

// The secant point of the bracket, kept at least ttol / 2 inside it (and away from an end the
// secant hugs) so that the bracket shrinks every iteration.
sunrealtype SecantPoint(sunrealtype tlo, sunrealtype thi, sunrealtype glo, sunrealtype ghi,
                        sunrealtype alpha, sunrealtype ttol) {
  const sunrealtype w = thi - tlo;
  sunrealtype tmid = thi - w * ghi / (ghi - alpha * glo);
  const sunrealtype margin = std::max(sunrealtype(0.5) * ttol, sunrealtype(0.1) * w);
  if (!(tmid - tlo >= 0.5 * ttol)) tmid = tlo + std::min(margin, sunrealtype(0.5) * w);
  if (!(thi - tmid >= 0.5 * ttol)) tmid = thi - std::min(margin, sunrealtype(0.5) * w);
  return tmid;
}

constexpr int kMaxSecant = 50;

// Illinois regula falsi on [tlo, thi] (roots bracketed there): narrows the bracket of the
// earliest root to ttol; the root is its right end, where g has its new sign (or is zero).
int Illinois(CEodeMemRec* ce, CERootMem* rm, sunrealtype thi, const char* func) {
  const sunrealtype ttol = 100 * SUN_UNIT_ROUNDOFF * (std::fabs(ce->tcur) + std::fabs(ce->h));
  std::vector<sunrealtype>& glo = rm->glo;
  std::vector<sunrealtype>& ghi = rm->ghi;
  sunrealtype tlo = rm->tlo;
  sunrealtype alpha = 1;
  int side = 0;  // 1: the last iteration kept tlo; 2: it kept thi
  bool any = false;
  int imax = Leading(*rm, glo.data(), ghi.data(), &any);
  for (int it = 0; imax >= 0 && thi - tlo > ttol; ++it) {
    // A g far from linear in t (a jump) can hold the secant near one end; past kMaxSecant
    // iterations the bracket is halved, which ends in at most 60 more.
    const sunrealtype tmid = it < kMaxSecant
                                 ? SecantPoint(tlo, thi, glo[imax], ghi[imax], alpha, ttol)
                                 : tlo + sunrealtype(0.5) * (thi - tlo);
    const int flag = EvalG(ce, rm, tmid, rm->gmid.data(), func);
    if (flag != CE_SUCCESS) return flag;
    bool left = false;
    for (int i = 0; i < rm->nrtfn && !left; ++i)
      left = Brackets(*rm, i, glo.data(), rm->gmid.data());
    // The end kept twice in a row has its g halved (alpha weighs glo against ghi).
    if (left) {
      alpha = side == 1 ? alpha * sunrealtype(0.5) : 1;
      side = 1;
      thi = tmid;
      ghi.swap(rm->gmid);
    } else {
      alpha = side == 2 ? alpha * 2 : 1;
      side = 2;
      tlo = tmid;
      glo.swap(rm->gmid);
    }
    imax = Leading(*rm, glo.data(), ghi.data(), &any);
  }
  for (int i = 0; i < rm->nrtfn; ++i) {
    rm->info[i] = Brackets(*rm, i, glo.data(), ghi.data()) ? (glo[i] < 0 ? 1 : -1) : 0;
  }
  rm->troot = thi;
  return CE_ROOT_RETURN;
}

}  // namespace

void RootRestart(CEodeMemRec* ce, bool counters) {
  CERootMem* rm = ce->root.get();
  if (rm == nullptr) return;
  rm->need_start = true;
  std::fill(rm->info.begin(), rm->info.end(), 0);
  if (counters) rm->nge = 0;
}

void RootFreeVectors(CEodeMemRec* ce) {
  CERootMem* rm = ce->root.get();
  if (rm == nullptr) return;
  if (rm->x != nullptr) N_VDestroy(rm->x);
  if (rm->v != nullptr) N_VDestroy(rm->v);
  rm->x = rm->v = nullptr;
  rm->need_start = true;
}

sunrealtype RootTime(const CEodeMemRec* ce) { return ce->root->troot; }

long int RootNumGEvals(const CEodeMemRec* ce) { return ce->root == nullptr ? 0 : ce->root->nge; }

int RootCheck(CEodeMemRec* ce, sunrealtype tend, const char* func) {
  CERootMem* rm = ce->root.get();
  sunrealtype a = 0;
  sunrealtype b = 0;
  DenseInterval(ce, &a, &b);
  const sunrealtype tol = 1e-8 * (b - a);
  // A restart or a new step size can leave tlo outside the interval: the check starts afresh.
  if (rm->need_start || rm->tlo < a - tol || rm->tlo > b + tol) {
    const int flag = StartRoots(ce, rm, std::min(std::max(ce->tretlast, a), b), func);
    if (flag != CE_SUCCESS) return flag;
  }
  if (!(tend > rm->tlo)) return CE_SUCCESS;
  int flag = EvalG(ce, rm, tend, rm->ghi.data(), func);
  if (flag != CE_SUCCESS) return flag;
  if (rm->check_null) WarnNull(ce, rm, tend, func);
  bool any = false;
  Leading(*rm, rm->glo.data(), rm->ghi.data(), &any);
  if (any) {
    std::fill(rm->info.begin(), rm->info.end(), 0);
    flag = Illinois(ce, rm, tend, func);
    if (flag != CE_ROOT_RETURN) return flag;
  }
  // The check goes on from the root (or tend): g there is the new glo; a component that has
  // moved away from zero is active again, its crossing in this interval not looked for.
  for (int i = 0; i < rm->nrtfn; ++i) rm->glo[i] = rm->ghi[i];
  rm->tlo = any ? rm->troot : tend;
  return any ? CE_ROOT_RETURN : CE_SUCCESS;
}

}  // namespace ceode

using ceode::CERootMem;
using ceode::ProcessError;

namespace {

// The access guard of the functions that need root functions attached.
int AccessRoots(void* mem, const char* func, CEodeMemRec** ce) {
  const int flag = ceode::Access(mem, func, ce);
  if (flag != CE_SUCCESS || (*ce)->root != nullptr) return flag;
  return ProcessError(*ce, CE_ILL_INPUT, func,
                      "No root functions: call CEodeRootInit with nrtfn > 0 first.");
}

}  // namespace

extern "C" {

int CEodeRootInit(void* mem, int nrtfn, CEodeRootFn g) {
  CEodeMemRec* ce = nullptr;
  const int flag = ceode::Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (nrtfn < 0) {
    return ProcessError(ce, CE_ILL_INPUT, __func__,
                        "nrtfn = %d: pass the number of root functions (0 turns them off).", nrtfn);
  }
  const bool warn = ce->root == nullptr || ce->root->warn_inactive;
  if (nrtfn == 0) {
    ce->root.reset();
    ceode::StepOptionsChanged(ce);
    return CE_SUCCESS;
  }
  if (g == nullptr) {
    return ProcessError(ce, CE_ILL_INPUT, __func__,
                        "g = NULL with nrtfn = %d: pass the root function g(t, x, v, gout, data).",
                        nrtfn);
  }
  std::unique_ptr<CERootMem, ceode::RootMemFree> rm(new (std::nothrow) CERootMem);
  if (rm == nullptr) return ProcessError(ce, CE_MEM_FAIL, __func__, "Out of memory.");
  try {
    rm->dir.assign(nrtfn, 0);
    rm->info.assign(nrtfn, 0);
    rm->glo.assign(nrtfn, 0);
    rm->ghi.assign(nrtfn, 0);
    rm->gmid.assign(nrtfn, 0);
  } catch (...) {
    return ProcessError(ce, CE_MEM_FAIL, __func__, "Out of memory (%d root functions).", nrtfn);
  }
  rm->g = g;
  rm->nrtfn = nrtfn;
  rm->warn_inactive = warn;
  ce->root = std::move(rm);
  ceode::StepOptionsChanged(ce);
  return CE_SUCCESS;
}

int CEodeSetRootDirection(void* mem, int* rootdir) {
  CEodeMemRec* ce = nullptr;
  const int flag = AccessRoots(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (rootdir == nullptr) return ProcessError(ce, CE_ILL_INPUT, __func__, "rootdir = NULL.");
  for (int i = 0; i < ce->root->nrtfn; ++i) {
    ce->root->dir[i] = rootdir[i] > 0 ? 1 : (rootdir[i] < 0 ? -1 : 0);
  }
  return CE_SUCCESS;
}

int CEodeSetNoInactiveRootWarn(void* mem) {
  CEodeMemRec* ce = nullptr;
  const int flag = AccessRoots(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  ce->root->warn_inactive = false;
  return CE_SUCCESS;
}

int CEodeGetRootInfo(void* mem, int* rootsfound) {
  CEodeMemRec* ce = nullptr;
  const int flag = AccessRoots(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (rootsfound == nullptr) return ProcessError(ce, CE_ILL_INPUT, __func__, "rootsfound = NULL.");
  std::copy(ce->root->info.begin(), ce->root->info.end(), rootsfound);
  return CE_SUCCESS;
}

int CEodeGetNumGEvals(void* mem, long int* ngevals) {
  CEodeMemRec* ce = nullptr;
  const int flag = ceode::Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (ngevals == nullptr) return ProcessError(ce, CE_ILL_INPUT, __func__, "ngevals = NULL.");
  *ngevals = ceode::RootNumGEvals(ce);
  return CE_SUCCESS;
}

}  // extern "C"
