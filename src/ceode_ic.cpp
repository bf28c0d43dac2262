// Consistent initial conditions of the constrained problem (docs/theory.md section 8.5): the
// first start's check that x0 lies on Phi(x, t0) = 0 and v0 on G(x0) v = -Phi_t(x0, t0), and
// CEodeCalcIC, which projects them there (IDACalcIC's counterpart).
//
// Both are measured per constraint in the units of x and v: row i of G is the normal of the level
// set of Phi_i, so |Phi_i| / |G_i| is the distance of x0 from that surface (to first order) and
// |G_i v + Phi_t,i| / |G_i| the velocity across it. A start is consistent when every distance is
// below sqrt(uround) |x0|_max and every normal velocity below sqrt(uround) times the velocity
// scale: data computed in double precision from lengths and angles sits eight orders of magnitude
// below that, a wrong length, angle or velocity far above it.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "ceode_saddle.hpp"

namespace ceode {

namespace {

constexpr int kMaxProjectionIters = 10;
// The position projection has converged when no constraint is farther away than this many ulps
// of |x|; it has stagnated at round-off when it no longer halves below kStallUlps ulps.
constexpr sunrealtype kProjectionUlps = 4;
constexpr sunrealtype kStallUlps = 100;

// The workspace of one check or projection, freed when it ends.
struct IcWork {
  CEodeMemRec* ce = nullptr;
  Saddle sad;
  bool sad_init = false;
  SUNMatrix G = nullptr;
  N_Vector phi = nullptr, phit = nullptr, ptmp = nullptr, lam = nullptr;  // length nc
  N_Vector dx = nullptr, xsave = nullptr, vsave = nullptr;                // length n
  std::vector<sunrealtype> gnorm;                                         // |G_i|, row norms
  explicit IcWork(CEodeMemRec* c) : ce(c) {}
  IcWork(const IcWork&) = delete;
  IcWork& operator=(const IcWork&) = delete;
  ~IcWork() {
    if (sad_init) SaddleFree(&sad);
    if (G != nullptr) SUNMatDestroy(G);
    for (N_Vector v : {phi, phit, ptmp, lam, dx, xsave, vsave}) {
      if (v != nullptr) N_VDestroy(v);
    }
  }
};

// G in the kind the constraint module hands the user (its saddle matrix's: sparse with a sparse
// attached solver, dense otherwise), so that the same CEodeConstrJacFn fills it.
SUNMatrix MakeG(const CEodeMemRec* ce) {
  const sunindextype nc = ce->con.nc, n = ce->n;
  const SUNMatrix A = ce->ls.LS != nullptr ? ce->ls.A : nullptr;
  if (A == nullptr || SUNMatGetID(A) != SUNMATRIX_SPARSE) return SUNDenseMatrix(nc, n, ce->sunctx);
  const sunindextype nnz = std::min<sunindextype>(nc * n, 4 * (nc + n) + 16);
  return SUNSparseMatrix(nc, n, nnz, SUNSparseMatrix_SparseType(A), ce->sunctx);
}

int Alloc(IcWork* w, const char* func) {
  CEodeMemRec* ce = w->ce;
  w->G = MakeG(ce);
  N_Vector* cvecs[] = {&w->phi, &w->phit, &w->ptmp, &w->lam};
  for (N_Vector* v : cvecs) *v = CloneVector(ce->con.phi);
  N_Vector* svecs[] = {&w->dx, &w->xsave, &w->vsave};
  for (N_Vector* v : svecs) *v = CloneVector(ce->xcur);
  bool ok = w->G != nullptr;
  for (N_Vector* v : cvecs) ok = ok && *v != nullptr;
  for (N_Vector* v : svecs) ok = ok && *v != nullptr;
  if (ok) {
    try {
      w->gnorm.assign(static_cast<size_t>(ce->con.nc), 0);
    } catch (...) {
      ok = false;
    }
  }
  return ok ? CE_SUCCESS : ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
}

int EvalPhi(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector phi, const char* func) {
  const int rv = ce->con.phi_fn(t, x, phi, ce->user_data);
  ++ce->con.nce;
  if (rv != 0 || !IsFinite(phi)) {
    return ProcessError(ce, CE_CONSTR_FAIL, func,
                        "The constraint function %s at t = %.17g while CEODE checked or projected "
                        "the initial conditions.",
                        rv != 0 ? "failed" : "returned NaN or Inf", static_cast<double>(t));
  }
  return CE_SUCCESS;
}

// G(x, t) and its row norms.
int EvalG(IcWork* w, sunrealtype t, N_Vector x, const char* func) {
  CEodeMemRec* ce = w->ce;
  SUNMatZero(w->G);
  const int rv = ce->con.G_fn(t, x, w->G, ce->user_data);
  ++ce->con.nge;
  std::fill(w->gnorm.begin(), w->gnorm.end(), SUN_RCONST(0.0));
  bool finite = true;
  if (rv == 0) {  // a failed call may leave a sparse G's index arrays half written
    ForEachEntry(w->G, [&](sunindextype r, sunindextype, sunrealtype v) {
      finite &= std::isfinite(v);
      w->gnorm[r] += v * v;
    });
  }
  if (rv != 0 || !finite) {
    return ProcessError(ce, CE_CONSTR_FAIL, func,
                        "The constraint Jacobian function %s at t = %.17g while CEODE checked or "
                        "projected the initial conditions.",
                        rv != 0 ? "failed" : "returned NaN or Inf", static_cast<double>(t));
  }
  for (sunrealtype& g : w->gnorm) g = std::sqrt(g);
  return CE_SUCCESS;
}

// Phi_t(x, t) by fourth-order central differences in t. The increment is eps^(1/5) times the
// step's time scale (100 h; 1 before a step is set): a driving motion resolved by h leaves a
// truncation error of order (omega s)^4 and a rounding error of order eps / s, both near
// 1e-13 relative. A constraint without explicit time dependence gives exactly zero.
int EvalPhiT(IcWork* w, sunrealtype t, N_Vector x, const char* func) {
  static const sunrealtype kW[2] = {SUN_RCONST(8.0) / 12, SUN_RCONST(-1.0) / 12};
  const sunrealtype scale = w->ce->h > 0 ? 100 * w->ce->h : SUN_RCONST(1.0);
  const sunrealtype s = std::pow(SUN_UNIT_ROUNDOFF, SUN_RCONST(0.2)) * scale;
  N_VConst(0, w->phit);
  int flag = CE_SUCCESS;
  for (int j = 1; j <= 2 && flag == CE_SUCCESS; ++j) {
    flag = EvalPhi(w->ce, t + j * s, x, w->ptmp, func);
    if (flag == CE_SUCCESS) N_VLinearSum(1, w->phit, kW[j - 1] / s, w->ptmp, w->phit);
    if (flag == CE_SUCCESS) flag = EvalPhi(w->ce, t - j * s, x, w->ptmp, func);
    if (flag == CE_SUCCESS) N_VLinearSum(1, w->phit, -kW[j - 1] / s, w->ptmp, w->phit);
  }
  return flag;
}

// out = G v + Phi_t, the residual of the velocity constraint (G and Phi_t evaluated).
void VelocityResidual(IcWork* w, N_Vector v, N_Vector out) {
  N_VScale(1, w->phit, out);
  sunrealtype* od = N_VGetArrayPointer(out);
  const sunrealtype* vd = N_VGetArrayPointer(v);
  ForEachEntry(w->G, [&](sunindextype r, sunindextype c, sunrealtype g) { od[r] += g * vd[c]; });
}

// The largest |r_i| / |G_i| (a zero row of G: |r_i| itself), its component and r_i.
struct Offset {
  sunrealtype dist = 0;
  sunindextype at = 0;
  sunrealtype value = 0;
};

Offset LargestOffset(const IcWork& w, N_Vector r) {
  const sunrealtype* rd = N_VGetArrayPointer(r);
  Offset o;
  for (size_t i = 0; i < w.gnorm.size(); ++i) {
    const sunrealtype d = std::fabs(rd[i]) / (w.gnorm[i] > 0 ? w.gnorm[i] : SUN_RCONST(1.0));
    if (d > o.dist || std::isnan(d)) {
      o.dist = d;
      o.at = static_cast<sunindextype>(i);
      o.value = rd[i];
    }
  }
  return o;
}

// The constrained step's requirement (ConstrInitialize): local data on one process.
bool LocalData(N_Vector v) { return N_VGetArrayPointer(v) != nullptr && sun::IsLocal(v); }

// The velocity scale of the consistency test: |v|_max, or the driving speed |Phi_t,i| / |G_i|.
sunrealtype VelocityScale(const IcWork& w, N_Vector v) {
  return std::max(N_VMaxNorm(v), LargestOffset(w, w.phit).dist);
}

// The minimum-norm correction in the kinetic-energy metric: [[M, G^T], [G, 0]] [d; s] = [0; -r]
// minimises d^T M d subject to G d = -r (M = I without a mass matrix), into w->dx.
int MinimumNormCorrection(IcWork* w, sunrealtype t, N_Vector x, N_Vector r, const char* func) {
  CEodeMemRec* ce = w->ce;
  bool refreshed = false;
  int flag = MassUpdate(ce, t, x, func);
  if (flag == CE_SUCCESS) {
    flag = SaddleSetup(ce, &w->sad, 0, nullptr, w->G, w->G, t, func, false, &refreshed);
  }
  if (flag == CE_SUCCESS) flag = SaddleSolve(ce, &w->sad, 0, x, -1, r, t, func);
  if (flag == CE_SUCCESS) SaddleSplit(w->sad, w->dx, w->lam);
  return flag;
}

// Gauss-Newton on Phi(x, t0) = 0 from x0 with minimum-norm corrections.
int ProjectPosition(IcWork* w, const char* func) {
  CEodeMemRec* ce = w->ce;
  const sunrealtype t0 = ce->tcur;
  sunrealtype dprev = SUN_BIG_REAL;
  Offset o;
  for (int m = 0; m < kMaxProjectionIters; ++m) {
    int flag = EvalPhi(ce, t0, ce->xcur, w->phi, func);
    if (flag == CE_SUCCESS) flag = EvalG(w, t0, ce->xcur, func);
    if (flag != CE_SUCCESS) return flag;
    o = LargestOffset(*w, w->phi);
    const sunrealtype ulp = SUN_UNIT_ROUNDOFF * N_VMaxNorm(ce->xcur);
    if (o.dist <= kProjectionUlps * ulp) return CE_SUCCESS;
    if (o.dist <= kStallUlps * ulp && o.dist > dprev / 2) return CE_SUCCESS;  // round-off floor
    dprev = o.dist;
    if ((flag = MinimumNormCorrection(w, t0, ce->xcur, w->phi, func)) != CE_SUCCESS) return flag;
    N_VLinearSum(1, ce->xcur, 1, w->dx, ce->xcur);
  }
  return ProcessError(ce, CE_CONV_FAILURE, func,
                      "The projection of x0 onto Phi(x, t0) = 0 did not converge in %d "
                      "Gauss-Newton iterations (constraint %ld still %g away): the constraints "
                      "may have no solution near x0, or CEodeConstrJacFn is not the derivative "
                      "of the constraint function. x0 and v0 are left as they were.",
                      kMaxProjectionIters, static_cast<long>(o.at), static_cast<double>(o.dist));
}

// The velocity constraint is linear in v: one minimum-norm correction, and a second one only when
// the first left more than round-off (an ill-conditioned G).
int ProjectVelocity(IcWork* w, const char* func) {
  CEodeMemRec* ce = w->ce;
  const sunrealtype t0 = ce->tcur;
  int flag = EvalG(w, t0, ce->xcur, func);
  if (flag == CE_SUCCESS) flag = EvalPhiT(w, t0, ce->xcur, func);
  for (int pass = 0; pass < 2 && flag == CE_SUCCESS; ++pass) {
    VelocityResidual(w, ce->D[1], w->ptmp);
    const sunrealtype ulp = SUN_UNIT_ROUNDOFF * VelocityScale(*w, ce->D[1]);
    if (pass > 0 && LargestOffset(*w, w->ptmp).dist <= kStallUlps * ulp) break;
    flag = MinimumNormCorrection(w, t0, ce->xcur, w->ptmp, func);
    if (flag == CE_SUCCESS) N_VLinearSum(1, ce->D[1], 1, w->dx, ce->D[1]);
  }
  return flag;
}

// The sentence of an inconsistent start: which constraint, how far, the threshold, the remedy.
int ReportInconsistent(CEodeMemRec* ce, const char* func, const Offset* pos, sunrealtype tolx,
                       const Offset* vel, sunrealtype tolv) {
  char ptxt[320] = "", vtxt[320] = "";
  if (pos != nullptr) {
    std::snprintf(ptxt, sizeof(ptxt),
                  "x0 is off the position constraints: Phi_%ld(x0, t0) = %.3g puts it %.3g from "
                  "the constraint surface (consistent: below sqrt(uround) |x0|_max = %.3g). ",
                  static_cast<long>(pos->at), static_cast<double>(pos->value),
                  static_cast<double>(pos->dist), static_cast<double>(tolx));
  }
  if (vel != nullptr) {
    std::snprintf(vtxt, sizeof(vtxt),
                  "v0 violates the velocity constraint G v = -Phi_t: component %ld of G v0 + "
                  "Phi_t is %.3g, a velocity of %.3g across the constraint (consistent: below "
                  "%.3g). ",
                  static_cast<long>(vel->at), static_cast<double>(vel->value),
                  static_cast<double>(vel->dist), static_cast<double>(tolv));
  }
  return ProcessError(ce, CE_INCONSISTENT_IC, func,
                      "Inconsistent initial conditions at t0 = %.17g. %s%sCall CEodeCalcIC(mem, "
                      "%s) before CEodeEvolve to project them onto the constraints, or correct "
                      "them (components count from 0).",
                      static_cast<double>(ce->tcur), ptxt, vtxt,
                      pos != nullptr ? "CE_IC_POSITION | CE_IC_VELOCITY" : "CE_IC_VELOCITY");
}

// CEodeCalcIC's checks of its input; the attached objects pass the start's validation points.
int CheckCalcICInput(CEodeMemRec* ce, const char* func, int what) {
  if (what <= 0 || (what & ~(CE_IC_POSITION | CE_IC_VELOCITY)) != 0) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "what = %d: use CE_IC_POSITION, CE_IC_VELOCITY or both (bitwise or).",
                        what);
  }
  if (!HasConstraints(ce)) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "No constraints are set (CEodeSetConstraints): there is nothing to "
                        "project the initial conditions onto.");
  }
  if (!LocalData(ce->xcur) || !LocalData(ce->con.phi)) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "The projection needs state and constraint vectors with local data "
                        "on one process (serial, OpenMP, Pthreads), as the constrained step does.");
  }
  int flag = ValidateMassMatrix(ce, func, ce->ls.M);
  if (flag == CE_SUCCESS) flag = ValidateLinearSolver(ce, func, ce->ls.LS, ce->ls.A, true);
  if (flag == CE_SUCCESS) flag = ValidateMassAgainstSolver(ce, func);
  return flag == CE_SUCCESS ? ValidateConstraintTemplate(ce, func) : flag;
}

int CalcIC(CEodeMemRec* ce, const char* func, int what) {
  // The state at tcur changes and the solvers are used: the next CEodeEvolve starts from it.
  Restart(ce);
  IcWork w(ce);
  int flag = Alloc(&w, func);
  if (flag == CE_SUCCESS) flag = SaddleInit(ce, &w.sad, func);
  w.sad_init = true;
  if (flag != CE_SUCCESS) return flag;
  N_VScale(1, ce->xcur, w.xsave);
  N_VScale(1, ce->D[1], w.vsave);
  if ((what & CE_IC_POSITION) != 0) flag = ProjectPosition(&w, func);
  if (flag == CE_SUCCESS && (what & CE_IC_VELOCITY) != 0) flag = ProjectVelocity(&w, func);
  if (flag != CE_SUCCESS) {  // the memory stays as it was
    N_VScale(1, w.xsave, ce->xcur);
    N_VScale(1, w.vsave, ce->D[1]);
    return flag;
  }
  N_VLinearSum(1, ce->xcur, -1, w.xsave, w.dx);
  ce->ic.dx = N_VMaxNorm(w.dx);
  N_VLinearSum(1, ce->D[1], -1, w.vsave, w.dx);
  ce->ic.dv = N_VMaxNorm(w.dx);
  return CE_SUCCESS;
}

}  // namespace

void IcRequestCheck(CEodeMemRec* ce) {
  ce->ic.pending = true;
  ce->ic.dx = ce->ic.dv = 0;
}

int IcCheck(CEodeMemRec* ce, const char* func) {
  if (!ce->ic.pending || !HasConstraints(ce)) return CE_SUCCESS;
  if (!LocalData(ce->xcur) || !LocalData(ce->con.phi)) {
    return CE_SUCCESS;  // refused by the constraint solver with its own message
  }
  IcWork w(ce);
  const sunrealtype t0 = ce->tcur;
  int flag = Alloc(&w, func);
  if (flag == CE_SUCCESS) flag = EvalPhi(ce, t0, ce->xcur, w.phi, func);
  if (flag == CE_SUCCESS) flag = EvalG(&w, t0, ce->xcur, func);
  if (flag == CE_SUCCESS) flag = EvalPhiT(&w, t0, ce->xcur, func);
  if (flag != CE_SUCCESS) return flag;
  const Offset pos = LargestOffset(w, w.phi);
  VelocityResidual(&w, ce->D[1], w.ptmp);
  const Offset vel = LargestOffset(w, w.ptmp);
  const sunrealtype root = std::sqrt(SUN_UNIT_ROUNDOFF);
  const sunrealtype tolx = root * N_VMaxNorm(ce->xcur);
  const sunrealtype tolv = root * VelocityScale(w, ce->D[1]);
  const bool pos_ok = pos.dist <= tolx, vel_ok = vel.dist <= tolv;
  if (pos_ok && vel_ok) {
    ce->ic.pending = false;
    return CE_SUCCESS;
  }
  return ReportInconsistent(ce, func, pos_ok ? nullptr : &pos, tolx, vel_ok ? nullptr : &vel, tolv);
}

}  // namespace ceode

extern "C" {

int CEodeCalcIC(void* mem, int what) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce, true);
  if (flag == CE_SUCCESS) flag = ceode::CheckCalcICInput(ce, __func__, what);
  return flag == CE_SUCCESS ? ceode::CalcIC(ce, __func__, what) : flag;
}

int CEodeGetICCorrection(void* mem, sunrealtype* dx_norm, sunrealtype* dv_norm) {
  CEodeMemRec* ce = nullptr;
  const int flag = ceode::Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (dx_norm == nullptr || dv_norm == nullptr) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__, "An output pointer is NULL.");
  }
  *dx_norm = ce->ic.dx;
  *dv_norm = ce->ic.dv;
  return CE_SUCCESS;
}

int CEodeGetConsistentIC(void* mem, N_Vector x0, N_Vector v0) {
  CEodeMemRec* ce = nullptr;
  const int flag = ceode::Access(mem, __func__, &ce, true);
  if (flag != CE_SUCCESS) return flag;
  if (ce->started) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "The integration has started: the initial conditions are no longer "
                               "held (call this after CEodeCalcIC, before CEodeEvolve).");
  }
  if (x0 == nullptr || v0 == nullptr || N_VGetLength(x0) != ce->n || N_VGetLength(v0) != ce->n) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "x0 and v0 must be vectors cloned from the initial x0.");
  }
  N_VScale(1, ce->xcur, x0);
  N_VScale(1, ce->D[1], v0);
  return CE_SUCCESS;
}

}  // extern "C"
