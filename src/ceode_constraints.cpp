// Index-3 constraints without index reduction (docs/theory.md section 8): the constrained
// acceleration solve as a nonlinear system, with the same parts as the velocity-dependent one
// (ceode_nls.cpp): residual, linear setup, linear solve, convergence test.
//
// At a step at time t the unknowns are a = x''(t) and lambda(t):
//   F1 = f(t, x_t, v(a)) - M a - G(x_t)^T lambda = 0,   v(a) = V0 + kappa a
//   F2 = Phi(x(t+h; a), t+h) = 0,                       x(t+h; a) = X0 + mu (a - B_2)
// Newton in (a, lambda), linearising Phi at the current iterate x_i of x(t+h), H = G(x_i):
//   (M - kappa J) da + G_t^T dlambda = F1,   mu H da = -Phi(x_i).
// In (da, dlambda) the matrix is useless for small h (the second block row carries mu ~ h^2..h^4).
// With the position increment delta = mu da and the scaled multiplier s = mu dlambda, and the
// first block row multiplied by mu:
//   [ M - kappa J   G_t^T ] [ delta ]   [ mu F1  ]
//   [ H             0     ] [   s   ] = [ -Phi_i ]
// Every block is O(1) for every h (assembly and factorisation: ceode_saddle.cpp). The M block is
// M - kappa J, not M - (kappa/mu) J: the ratio of the two terms is fixed by the equation, not by
// the unknowns' scaling, and kappa/mu ~ 1/h would make the damping term dominate for small h.
//
// The residual is always exact (current G_t, current Phi); the matrix may be stale (simplified
// Newton across iterations) and is refreshed when the contraction slows. Convergence is measured
// on delta, the change of x(t+h), down to round-off of x.
#include <nvector/nvector_serial.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <new>

#include "ceode_saddle.hpp"
#include "ceode_testing.h"

namespace ceode {

namespace {

// Defaults of the constrained iteration. They differ from the implicit path's (6 iterations,
// reltol 1e-12 on the acceleration) because the test is on x(t+h) to round-off: the DAE results
// in docs/results were produced with these, and CEodeSetMaxNonlinIters/CEodeSetNonlinTolerances
// replace them when called.
constexpr int kMaxIters = 12;            // Newton iterations per solve, refreshes included
constexpr sunrealtype kSlowRate = 0.2;   // refresh the matrix when the contraction is slower
constexpr sunrealtype kTolUlps = 8;      // convergence: |delta| below this many ulps of |x|
constexpr sunrealtype kFloorUlps = 1e3;  // round-off stagnation is accepted below this
constexpr int kMaxStaleIters = 10;       // iterations with a matrix of an earlier step
// Every constrained solve runs inside a step or a start, so inside CEodeEvolve (TakeStep and
// StartMethod name no other entry): its errors name that one.
constexpr const char* kFunc = "CEodeEvolve";

// Private workspace of the constrained solve (ce->con.work).
struct ConWork {
  int degree = 0;
  Saddle sad;
  SUNMatrix Gt = nullptr;  // G(x(t), t): the direction of the constraint forces
  SUNMatrix Gh = nullptr;  // G at the iterate of x(t+h): linearises Phi
  SUNMatrix J = nullptr;   // df/dv (the user's kind of matrix, or dense difference quotients)
  N_Vector xtrial = nullptr, fval = nullptr, r1 = nullptr, delta = nullptr, vtmp = nullptr;
  N_Vector inc = nullptr, xpt = nullptr, a0 = nullptr;
  N_Vector vbase = nullptr;  // velocity offset V0 of v(a) = V0 + kappa a
  N_Vector lam = nullptr, lam_prev = nullptr, s = nullptr, gam = nullptr;
  bool factored = false;  // the LS holds a step matrix usable for simplified Newton
  sunrealtype kappa_fact = 0, mu_fact = 0;
  long int nst_fact = -1;
  sunrealtype kappa_jac = 0;  // df/dv in J was evaluated at step nst_jac for this kappa
  long int nst_jac = -1;
  long int jac_gen = 0;  // evaluations of df/dv into J so far
  // The block A = M - kappa J the Schur complement factored (Setup): its kappa (0 without J),
  // the J evaluation and the step of the refresh.
  bool a_valid = false;
  sunrealtype kappa_a = 0;
  long int jac_gen_a = -1, nst_a = -1;
  // x(t+h; a) = xoff[0] x(t) + sum_j xoff[j] D_j(t-h) + mu a: the step's update restricted to
  // the position, affine in the acceleration (AffineWeights).
  sunrealtype xoff[kMaxDegree] = {};
  sunrealtype mu_step = 0;      // the step's mu: the method's, or error control's for its two steps
  bool lam_prev_valid = false;  // lam_prev holds lambda(t - 2h) for the predictor
};

ConWork* Work(CEodeMemRec* ce) { return static_cast<ConWork*>(ce->con.work); }

void Destroy(N_Vector* v) {
  if (*v != nullptr) N_VDestroy(*v);
  *v = nullptr;
}
void Destroy(SUNMatrix* m) {
  if (*m != nullptr) SUNMatDestroy(*m);
  *m = nullptr;
}

void FreeWork(CEodeMemRec* ce) {
  ConWork* w = Work(ce);
  if (w == nullptr) return;
  N_Vector* vecs[] = {&w->xtrial, &w->fval,  &w->r1,  &w->delta,    &w->vtmp, &w->inc, &w->xpt,
                      &w->a0,     &w->vbase, &w->lam, &w->lam_prev, &w->s,    &w->gam};
  for (N_Vector* v : vecs) Destroy(v);
  SaddleFree(&w->sad);
  Destroy(&w->Gt);
  Destroy(&w->Gh);
  Destroy(&w->J);
  delete w;
  ce->con.work = nullptr;
}

// y += alpha G^T lam (G is nc x n); arrays of local data.
void AddGTransposeTimes(SUNMatrix G, sunrealtype alpha, const sunrealtype* lam, sunrealtype* y) {
  ForEachEntry(G,
               [&](sunindextype r, sunindextype c, sunrealtype v) { y[c] += alpha * v * lam[r]; });
}

// The position of the update (BuildUpdatePlan) written out in the history: with
// D_i(t) = sum_j T[i][j] D_j + c_i z for i != 2, a = B_2 + c_2 z, B_2 = sum_j T[2][j] D_j,
//   x(t+h) = x(t) + sum_i w_i D_i(t) + wz_old D_{d-1} + wz_new z
//          = x(t) + sum_j (sum_i w_i T[i][j] - mu T[2][j]) D_j + wz_old D_{d-1} + mu a.
// TakeStep's update forms the same x(t+h) from the converged a, to rounding.
void AffineWeights(int d, const StepCoeffs& co, sunrealtype* xoff) {
  xoff[0] = 1;
  for (int j = 1; j < d; ++j) {
    sunrealtype e = -co.mu * co.T[2][j];
    for (int i = 1; i <= d - 2; ++i) e += co.w[i] * co.T[i][j];
    xoff[j] = e;
  }
  xoff[d - 1] += co.wz_old;
}

// x(t+h; a) for the acceleration a (one linear combination, no update of the derivatives).
void StepPosition(CEodeMemRec* ce, const ConWork* w, N_Vector x, N_Vector a, N_Vector xout) {
  const int d = ce->degree;
  sunrealtype c[kMaxDegree + 2];
  N_Vector X[kMaxDegree + 2];
  int m = 0;
  for (int j = 0; j < d; ++j) {
    c[m] = w->xoff[j];
    X[m++] = j == 0 ? x : ce->D[j];
  }
  c[m] = w->mu_step;
  X[m++] = a;
  if (ce->compensated) {  // the update adds its increment minus the carried compensation
    c[m] = -1;
    X[m++] = ce->comp[0];
  }
  N_VLinearCombination(m, c, X, xout);
}

// The first position of the method: the Taylor polynomial of the derivatives at t0 with the
// acceleration a (the unknown of the constrained first step).
void StartPosition(CEodeMemRec* ce, ConWork* w, N_Vector x0, N_Vector a, N_Vector xout) {
  const int d = ce->degree;
  sunrealtype cw[kMaxDegree];
  N_Vector vw[kMaxDegree];
  TaylorWeights(ce->h, d, cw);
  for (int i = 1; i < d; ++i) vw[i - 1] = (i == 2) ? a : ce->D[i];
  N_VLinearCombination(d - 1, cw + 1, vw, w->inc);
  N_VLinearSum(1, x0, 1, w->inc, xout);
}

int EvalPhi(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector phi) {
  const int rv = ce->con.phi_fn(t, x, phi, ce->user_data);
  ++ce->con.nce;
  if (rv != 0) {
    return ProcessError(ce, CE_CONSTR_FAIL, kFunc,
                        "The constraint function failed (returned %d) at t = %.17g. The step was "
                        "not taken; the state is the last good one.",
                        rv, static_cast<double>(t));
  }
  if (!IsFinite(phi)) {
    return ProcessError(ce, CE_CONSTR_FAIL, kFunc,
                        "The constraint function returned NaN or Inf at t = %.17g: check Phi (and "
                        "that h is small enough to keep the positions in its domain).",
                        static_cast<double>(t));
  }
  return CE_SUCCESS;
}

int EvalG(CEodeMemRec* ce, sunrealtype t, N_Vector x, SUNMatrix G) {
  SUNMatZero(G);
  const int rv = ce->con.G_fn(t, x, G, ce->user_data);
  ++ce->con.nge;
  if (rv != 0) {
    return ProcessError(ce, CE_CONSTR_FAIL, kFunc,
                        "The constraint Jacobian function failed (returned %d) at t = %.17g.", rv,
                        static_cast<double>(t));
  }
  bool finite = true;
  ForEachEntry(G, [&](sunindextype, sunindextype, sunrealtype v) { finite &= std::isfinite(v); });
  if (!finite) {
    return ProcessError(ce, CE_CONSTR_FAIL, kFunc,
                        "The constraint Jacobian contains NaN or Inf at t = %.17g.",
                        static_cast<double>(t));
  }
  return CE_SUCCESS;
}

int EvalF(CEodeMemRec* ce, sunrealtype t, N_Vector x, N_Vector v, N_Vector f) {
  const int flag = EvalRhs(ce, t, x, v, f, kFunc);
  if (flag != CE_SUCCESS) return flag;
  if (!IsFinite(f)) {
    return ProcessError(ce, CE_RHSFUNC_FAIL, kFunc,
                        "The right-hand side returned NaN or Inf at t = %.17g.",
                        static_cast<double>(t));
  }
  return CE_SUCCESS;
}

// The Schur complement's block A = M - kappa J serves again while M is fixed, kappa and the J
// evaluation are the same, for at most msbj steps (its G0 ages with the motion; docs/theory.md
// section 8.3).
bool ABlockUsable(const CEodeMemRec* ce, const ConWork* w, sunrealtype kappa, SUNMatrix J) {
  const bool mass_fixed = ce->ls.mfn == nullptr || ce->ls.mass_constant;
  return mass_fixed && w->a_valid && w->kappa_a == (J != nullptr ? kappa : 0) &&
         (J == nullptr || w->jac_gen_a == w->jac_gen) && ce->nst - w->nst_a < ce->ls.msbj;
}

// Factors the saddle-point matrix; a failure leaves no usable step matrix. A refresh of the
// Schur complement's B without df/dv is what nje counts for f independent of v (with df/dv,
// VelJacobian counts its evaluation).
int Setup(CEodeMemRec* ce, ConWork* w, sunrealtype kappa, SUNMatrix J, SUNMatrix H, sunrealtype t) {
  bool refreshed = false;
  const int flag = SaddleSetup(ce, &w->sad, kappa, J, w->Gt, H, t, kFunc,
                               ABlockUsable(ce, w, kappa, J), &refreshed);
  if (refreshed) {
    w->a_valid = true;
    w->kappa_a = J != nullptr ? kappa : 0;
    w->jac_gen_a = w->jac_gen;
    w->nst_a = ce->nst;
    if (J == nullptr) ++ce->con.nje;
  }
  if (flag != CE_SUCCESS) w->factored = false;
  return flag;
}

int Solve(CEodeMemRec* ce, ConWork* w, sunrealtype top_scale, N_Vector top, sunrealtype bot_scale,
          N_Vector bottom, sunrealtype t) {
  const int flag = SaddleSolve(ce, &w->sad, top_scale, top, bot_scale, bottom, t, kFunc);
  if (flag != CE_SUCCESS) w->factored = false;
  return flag;
}

// gamma = d^2/ds^2 Phi(x + s v, t + s) at s = 0: the part of the second time derivative of Phi
// along the motion that does not involve the acceleration (d^2 Phi/dt^2 = G a + gamma).
// Sixth-order central differences: the truncation error is O(s^6), round-off O(eps / s^2).
int ConstraintCurvature(CEodeMemRec* ce, ConWork* w, sunrealtype t, N_Vector x, N_Vector v,
                        N_Vector gam) {
  static const sunrealtype kW[4] = {-49.0 / 18.0, 3.0 / 2.0, -3.0 / 20.0, 1.0 / 90.0};
  const sunrealtype vn = N_VMaxNorm(v);
  const sunrealtype ell = std::max(N_VMaxNorm(x), SUN_RCONST(1e-3));
  const sunrealtype eta = std::pow(SUN_UNIT_ROUNDOFF, SUN_RCONST(1.0) / 8);
  sunrealtype s = 100 * ce->h;  // explicit time dependence: resolved on the step's time scale
  if (vn > 0) s = std::min(s, eta * ell / vn);
  N_VConst(0, gam);
  int flag = EvalPhi(ce, t, x, w->s);
  if (flag != CE_SUCCESS) return flag;
  N_VLinearSum(kW[0], w->s, 1, gam, gam);
  for (int j = 1; j <= 3 && flag == CE_SUCCESS; ++j) {
    for (int sg = -1; sg <= 1 && flag == CE_SUCCESS; sg += 2) {
      const sunrealtype sj = sg * j * s;
      N_VLinearSum(1, x, sj, v, w->xpt);
      flag = EvalPhi(ce, t + sj, w->xpt, w->s);
      if (flag == CE_SUCCESS) N_VLinearSum(kW[j], w->s, 1, gam, gam);
    }
  }
  if (flag == CE_SUCCESS) N_VScale(1 / (s * s), gam, gam);
  return flag;
}

// The index-1 acceleration: [[M, G^T], [G, 0]] [a; lambda] = [f; -gamma] at (t, x, v).
int Index1Accel(CEodeMemRec* ce, ConWork* w, sunrealtype t, N_Vector x, N_Vector v, N_Vector a,
                N_Vector lam) {
  w->factored = false;  // A is about to hold a matrix that is not a step matrix
  int flag = MassUpdate(ce, t, x, kFunc);
  if (flag == CE_SUCCESS) flag = EvalG(ce, t, x, w->Gt);
  if (flag == CE_SUCCESS) flag = EvalF(ce, t, x, v, w->fval);
  if (flag == CE_SUCCESS) flag = ConstraintCurvature(ce, w, t, x, v, w->gam);
  if (flag == CE_SUCCESS) flag = Setup(ce, w, 0, nullptr, w->Gt, t);
  if (flag == CE_SUCCESS) flag = Solve(ce, w, 1, w->fval, -1, w->gam, t);
  if (flag != CE_SUCCESS) return flag;
  SaddleSplit(w->sad, a, lam);
  return CE_SUCCESS;
}

// What one constrained solve is: the force equation at (t, x_t), the constraint at tc.
struct SolveSpec {
  sunrealtype t;
  N_Vector xt;
  sunrealtype tc;
  sunrealtype mu;
  sunrealtype kappa;  // v(a) = V0 + kappa a when vdep
  bool vdep;
  N_Vector V0;  // the velocity f sees when !vdep
  bool start;   // position from StartPosition instead of StepPosition
  bool reuse;   // a step matrix factored at an earlier step may be reused
};

// The state of one iteration: its residual's force-balance part and the change of x(t+h).
struct Iterate {
  sunrealtype fscale = 0;  // size of the terms of the force balance
  sunrealtype r1norm = 0;  // max |f - M a - Gt^T lam|
  sunrealtype dnorm = 0;   // max |delta|, the change of x(t+h)
  sunrealtype dprev = 0;
  sunrealtype r1prev = 0;
  bool x_done = false;       // x(t+h) converged with a stale matrix: the constraint is left out
  bool have_matrix = false;  // the factored matrix serves this iteration
  bool fresh_jac = false;    // the next setup evaluates df/dv anew
  int limit = 0;             // iterations allowed (MaxIters from the last stale refresh)
  sunrealtype tol = 0;
  sunrealtype xscale = 0;
  bool fresh = false;  // the matrix was formed in this solve
};

// The residual at the iterate (a, lam, w->xtrial): Phi into ce->con.phi, r1 = f - M a - Gt^T lam.
int Residual(CEodeMemRec* ce, ConWork* w, const SolveSpec& sp, N_Vector a, N_Vector lam,
             Iterate* it) {
  int flag = EvalPhi(ce, sp.tc, w->xtrial, ce->con.phi);
  if (flag != CE_SUCCESS) return flag;
  if (sp.vdep) {
    N_VLinearSum(1, sp.V0, sp.kappa, a, w->vtmp);
    flag = EvalF(ce, sp.t, sp.xt, w->vtmp, w->fval);
    if (flag != CE_SUCCESS) return flag;
  }
  it->fscale = N_VMaxNorm(w->fval);
  if (ce->ls.M != nullptr) {
    if (SUNMatMatvec(ce->ls.M, a, w->r1) != 0) {
      return ProcessError(ce, CE_LSETUP_FAIL, kFunc, "M a failed: check the mass matrix size.");
    }
    it->fscale += N_VMaxNorm(w->r1);
    N_VLinearSum(1, w->fval, -1, w->r1, w->r1);
  } else {
    it->fscale += N_VMaxNorm(a);
    N_VLinearSum(1, w->fval, -1, a, w->r1);
  }
  it->fscale += N_VMaxNorm(w->r1);  // ~ |Gt^T lam|
  AddGTransposeTimes(w->Gt, -1, N_VGetArrayPointer(lam), N_VGetArrayPointer(w->r1));
  it->r1norm = N_VMaxNorm(w->r1);
  return CE_SUCCESS;
}

// f depending on v: the saddle matrix is formed at every step with the current G, and only df/dv
// is reused (for msbj steps, the same kappa, until the iteration contracts slowly), as CVODE
// reuses its Jacobian: forming it costs n evaluations of f, G costs one call.
bool JacUsable(const CEodeMemRec* ce, const ConWork* w, const SolveSpec& sp) {
  return sp.reuse && w->nst_jac >= 0 && w->kappa_jac == sp.kappa &&
         ce->nst - w->nst_jac < ce->ls.msbj;
}

// The Newton matrix at the current iterate: H = G(x_i), df/dv when f depends on v (evaluated
// anew when fresh_jac or when the last one may not be reused). nje counts the evaluations of
// the Jacobian that the matrix reuses: df/dv (VelJacobian) or, f independent of v, the block
// B of the Schur complement (Setup) or, on the full saddle path, the whole matrix with G.
int LinSetup(CEodeMemRec* ce, ConWork* w, const SolveSpec& sp, bool fresh_jac) {
  int flag = EvalG(ce, sp.tc, w->xtrial, w->Gh);
  if (flag == CE_SUCCESS && sp.vdep && (fresh_jac || !JacUsable(ce, w, sp))) {
    w->nst_jac = -1;
    flag = VelJacobian(ce, sp.t, sp.xt, w->vtmp, w->fval, w->J, kFunc);
    if (flag == CE_SUCCESS) {
      w->nst_jac = ce->nst;
      w->kappa_jac = sp.kappa;
      ++w->jac_gen;
    }
  }
  if (flag == CE_SUCCESS) flag = Setup(ce, w, sp.kappa, sp.vdep ? w->J : nullptr, w->Gh, sp.t);
  if (flag != CE_SUCCESS) return flag;
  // The full saddle matrix, G in it, is refreshed.
  if (!sp.vdep && !w->sad.sc.active) ++ce->con.nje;
  w->factored = true;
  w->kappa_fact = sp.kappa;
  w->mu_fact = sp.mu;
  w->nst_fact = ce->nst;
  return CE_SUCCESS;
}

// A step matrix of an earlier step serves (simplified Newton) until msbj steps have passed, h
// (kappa, mu) or M changed; the iteration refreshes it when it contracts slowly (ConvTest).
// Only when the user set msbj: with f independent of v the matrix needs no evaluation of f, and
// a stale one costs more iterations than a factorisation on small systems (measured on the DAE
// pendulum: 2.4x the time per step with msbj = 20; docs/theory.md section 8).
bool MatrixUsable(const CEodeMemRec* ce, const ConWork* w, const SolveSpec& sp) {
  const bool mass_fixed = ce->ls.mfn == nullptr || ce->ls.mass_constant;
  return sp.reuse && !sp.vdep && ce->ls.msbj_set && w->factored && mass_fixed &&
         w->kappa_fact == sp.kappa && w->mu_fact == sp.mu && ce->nst - w->nst_fact < ce->ls.msbj;
}

// One Newton correction: x(t+h; a) is affine in a with slope mu, so it moves by delta itself.
int LinSolve(CEodeMemRec* ce, ConWork* w, const SolveSpec& sp, N_Vector a, N_Vector lam,
             Iterate* it) {
  const int flag = Solve(ce, w, sp.mu, w->r1, it->x_done ? 0 : -1, ce->con.phi, sp.t);
  if (flag != CE_SUCCESS) return flag;
  SaddleSplit(w->sad, w->delta, w->s);
  ++ce->con.nni;
  N_VLinearSum(1, w->xtrial, 1, w->delta, w->xtrial);
  N_VLinearSum(1, a, 1 / sp.mu, w->delta, a);
  N_VLinearSum(1, lam, 1 / sp.mu, w->s, lam);
  it->dnorm = N_VMaxNorm(w->delta);
  it->xscale = std::max(N_VMaxNorm(w->xtrial), SUN_RCONST(1e-300));
  it->tol = ce->nls.tol_set ? ce->nls.reltol * it->xscale + ce->nls.abstol
                            : kTolUlps * SUN_UNIT_ROUNDOFF * it->xscale;
  return CE_SUCCESS;
}

enum class Conv { kConverged, kContinue, kRefresh, kFailed };

// A matrix of an earlier step: G(x) and df/dv in it are stale, so one correction solves neither
// the force balance nor the linearised constraint exactly and the iteration contracts linearly.
// The change of x(t+h) cannot show the error of a along the constraint manifold, the part the
// energy sees (it is scaled by mu ~ h^2), so the force residual must reach round-off as well, as
// with a fresh matrix and f depending on v. Once x(t+h) has converged, the corrections leave the
// constraint out (Iterate::x_done): Phi at the quantised x(t+h) is noise of ~ 1 ulp that moves a
// along the constraint normals by ~ ulp(x)/mu, and with a stale G(x(t)) every such move leaves
// (G_old - G_t)^T dlambda in the force residual, a floor far above round-off. Slow contraction of
// the force residual, or of x(t+h) from the third iterate on (the first change carries the
// multiplier predictor's error too), asks for a fresh matrix. Measured on the DAE pendulum
// (G5_ONES, msbj = 20, h = 1e-4): testing x(t+h) alone raised the energy error from 5.2e-13 to
// 4.7e-11; with the constraint kept in, the force residual stalled near 1e-12 and 62 % of the
// steps at h = 1e-3 refreshed the matrix.
Conv StaleConvTest(int m, const Iterate& it, sunrealtype ftol) {
  const bool force_ok = it.r1norm <= ftol * it.fscale;
  if (it.dnorm <= it.tol && force_ok) return Conv::kConverged;
  if (m == 0) return Conv::kContinue;
  // x(t+h) has converged: the next corrections polish the force balance (x_done).
  if (it.dnorm <= it.tol) return m >= kMaxStaleIters ? Conv::kRefresh : Conv::kContinue;
  const bool x_slow = m >= 2 && it.dnorm > kSlowRate * it.dprev;
  return x_slow || m >= kMaxStaleIters ? Conv::kRefresh : Conv::kContinue;
}

Conv ConvTest(const CEodeMemRec* ce, const SolveSpec& sp, int m, const Iterate& it) {
  if (!std::isfinite(it.dnorm)) return Conv::kFailed;
  const sunrealtype ftol = ce->nls.tol_set ? ce->nls.reltol : kTolUlps * SUN_UNIT_ROUNDOFF;
  if (!it.fresh) return StaleConvTest(m, it, ftol);
  const bool force_ok = !sp.vdep || it.r1norm <= ftol * it.fscale;
  if (it.dnorm <= it.tol && force_ok) return Conv::kConverged;
  if (m == 0 || it.dprev <= 0) return Conv::kContinue;
  const sunrealtype rate = it.dnorm / it.dprev;
  if (force_ok && rate < 1 && it.dnorm * rate / (1 - rate) <= it.tol) return Conv::kConverged;
  // Round-off stagnation: the change no longer shrinks but is already at the noise level.
  if (force_ok && rate >= 0.5 && it.dnorm <= kFloorUlps * SUN_UNIT_ROUNDOFF * it.xscale) {
    return Conv::kConverged;
  }
  if (rate <= kSlowRate) return Conv::kContinue;
  const bool noise = it.dnorm <= kFloorUlps * SUN_UNIT_ROUNDOFF * it.xscale;
  if (it.fresh && rate > 2 && !noise) return Conv::kFailed;  // diverging with a fresh matrix
  return Conv::kRefresh;                                     // slow: refresh at the next iterate
}

int MaxIters(const CEodeMemRec* ce) { return ce->nls.maxcor_set ? ce->nls.maxcor : kMaxIters; }

int ConvFailure(CEodeMemRec* ce, const SolveSpec& sp, const Iterate& it) {
  ++ce->con.nnf;
  return ProcessError(ce, CE_CONV_FAILURE, kFunc,
                      "The constraint Newton iteration did not converge at t = %.17g (last change "
                      "of x(t+h) %g, target %g, %d iterations): reduce h, and check that "
                      "CEodeConstrJacFn is the exact derivative of the constraint function and "
                      "that the constraints are consistent.",
                      static_cast<double>(sp.t), static_cast<double>(it.dnorm),
                      static_cast<double>(it.tol), MaxIters(ce));
}

// One iteration: the residual at the iterate, a fresh matrix when none is usable, the correction.
int Iteration(CEodeMemRec* ce, ConWork* w, const SolveSpec& sp, N_Vector a, N_Vector lam,
              Iterate* it) {
  int flag = Residual(ce, w, sp, a, lam, it);
  if (flag == CE_SUCCESS && !it->have_matrix) {
    flag = LinSetup(ce, w, sp, it->fresh_jac);
    it->have_matrix = it->fresh = flag == CE_SUCCESS;
  }
  return flag == CE_SUCCESS ? LinSolve(ce, w, sp, a, lam, it) : flag;
}

// After a test that did not converge: what the next iteration uses. Iterations with a stale
// matrix come before the limit, as CVODE's retry with a fresh Jacobian gets its own maxcor.
void NextIteration(const CEodeMemRec* ce, Conv c, int m, Iterate* it) {
  if (!it->fresh && it->dnorm <= it->tol) it->x_done = true;
  if (c == Conv::kRefresh) {
    if (it->fresh) {
      it->fresh_jac = true;  // a fresh matrix with a reused df/dv contracted slowly
    } else {
      it->limit = m + 1 + MaxIters(ce);
    }
    it->have_matrix = it->x_done = false;
  }
  it->dprev = it->dnorm;
  it->r1prev = it->r1norm;
}

// Newton on (a, lam) for one step; a and lam hold the predictor on entry, the solution on exit;
// xout (if not NULL) receives x(t+h; a) for the final a.
//
// The matrix of an earlier step is reused (MatrixUsable, JacUsable), as CVODE reuses its Newton
// matrix; the residual stays exact: G(x(t)) and f are evaluated at every step. How a stale
// matrix is tested and when it is refreshed: StaleConvTest.
int ConstrainedNewton(CEodeMemRec* ce, ConWork* w, const SolveSpec& sp, N_Vector a, N_Vector lam,
                      N_Vector xout) {
  int flag = MassUpdate(ce, sp.t, sp.xt, kFunc);
  if (flag == CE_SUCCESS) flag = EvalG(ce, sp.t, sp.xt, w->Gt);
  if (flag == CE_SUCCESS && !sp.vdep) flag = EvalF(ce, sp.t, sp.xt, sp.V0, w->fval);
  if (flag != CE_SUCCESS) return flag;
  if (sp.start) {
    StartPosition(ce, w, sp.xt, a, w->xtrial);
  } else {
    StepPosition(ce, w, sp.xt, a, w->xtrial);
  }
  Iterate it;
  it.have_matrix = MatrixUsable(ce, w, sp);
  it.limit = MaxIters(ce);
  for (int m = 0; m < it.limit; ++m) {
    if ((flag = Iteration(ce, w, sp, a, lam, &it)) != CE_SUCCESS) return flag;
    const Conv c = ConvTest(ce, sp, m, it);
    if (c == Conv::kFailed) break;
    if (c == Conv::kConverged) {
      if (!IsFinite(a) || !IsFinite(lam)) break;
      if (xout != nullptr) N_VScale(1, w->xtrial, xout);
      return CE_SUCCESS;
    }
    NextIteration(ce, c, m, &it);
  }
  return ConvFailure(ce, sp, it);
}

bool LocalData(N_Vector v) { return N_VGetArrayPointer(v) != nullptr && sun::IsLocal(v); }

// Constraint (and velocity) Jacobians come in the kind of the saddle matrix, as the user fills
// them; the difference-quotient df/dv is dense.
SUNMatrix MakeMatrix(CEodeMemRec* ce, const Saddle& s, sunindextype r, sunindextype c) {
  if (!s.sparse) return SUNDenseMatrix(r, c, ce->sunctx);
  const sunindextype nnz = std::min<sunindextype>(r * c, 4 * (r + c) + 16);
  return SUNSparseMatrix(r, c, nnz, s.csr ? CSR_MAT : CSC_MAT, ce->sunctx);
}

int AllocWork(CEodeMemRec* ce, ConWork* w, const char* func) {
  const sunindextype n = ce->n;
  w->Gt = MakeMatrix(ce, w->sad, ce->con.nc, n);
  w->Gh = MakeMatrix(ce, w->sad, ce->con.nc, n);
  if (ce->vel_dependent) {
    w->J = ce->ls.jac != nullptr ? MakeMatrix(ce, w->sad, n, n) : SUNDenseMatrix(n, n, ce->sunctx);
  }
  N_Vector* svecs[] = {&w->xtrial, &w->fval, &w->r1, &w->delta, &w->vtmp,
                       &w->inc,    &w->xpt,  &w->a0, &w->vbase};
  for (N_Vector* v : svecs) *v = CloneVector(ce->xcur);
  N_Vector* lvecs[] = {&w->lam, &w->lam_prev, &w->s, &w->gam};
  for (N_Vector* v : lvecs) *v = CloneVector(ce->con.lambda);
  bool ok = w->Gt != nullptr && w->Gh != nullptr && (w->J != nullptr || !ce->vel_dependent);
  for (N_Vector* v : svecs) ok = ok && *v != nullptr;
  for (N_Vector* v : lvecs) ok = ok && *v != nullptr;
  return ok ? CE_SUCCESS : ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
}

// The consistent start: a0, lambda0 from the index-1 system; higher derivatives by symmetric
// differences of the index-1 acceleration along the Taylor curve of what is already known
// (StartDerivatives, with the index-1 acceleration as the right-hand side). lambda0 ends in
// w->lam_prev and w->lam.
int ConsistentStart(CEodeMemRec* ce, ConWork* w) {
  const sunrealtype t0 = ce->tcur;
  int flag = Index1Accel(ce, w, t0, ce->xcur, ce->D[1], ce->D[2], w->lam);
  if (flag != CE_SUCCESS) return flag;
  N_VScale(1, w->lam, w->lam_prev);  // lambda0, kept while the differences reuse w->lam
  flag = StartDerivatives(ce, t0, w->xtrial, w->r1, w->a0,
                          [&](sunrealtype ts, N_Vector xs, N_Vector vs, N_Vector as) {
                            return Index1Accel(ce, w, ts, xs, vs, as, w->lam);
                          });
  if (flag != CE_SUCCESS) return flag;
  N_VScale(1, w->lam_prev, w->lam);
  return CE_SUCCESS;
}

}  // namespace

bool HasConstraints(const CEodeMemRec* ce) { return ce->con.phi_fn != nullptr; }

int ConstrInitialize(CEodeMemRec* ce, const char* func) {
  if (!HasConstraints(ce)) return CE_SUCCESS;
  FreeWork(ce);
  if (!LocalData(ce->xcur) || !LocalData(ce->con.lambda)) {
    return ProcessError(ce, CE_LINIT_FAIL, func,
                        "Constraints need state and multiplier vectors with local data "
                        "(N_VGetArrayPointer, e.g. serial or OpenMP N_Vectors): the saddle-point "
                        "system is solved by a direct solver on one process.");
  }
  auto* w = new (std::nothrow) ConWork;
  if (w == nullptr) return ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
  ce->con.work = w;
  w->degree = ce->degree;
  const int flag = SaddleInit(ce, &w->sad, func);
  return flag == CE_SUCCESS ? AllocWork(ce, w, func) : flag;
}

int ConstrStart(CEodeMemRec* ce, const char* func) {
  ConWork* w = Work(ce);
  const int d = ce->degree;
  const sunrealtype t0 = ce->tcur;
  w->factored = false;
  w->nst_jac = -1;
  w->a_valid = false;  // h, M or the options may have changed at the restart
  w->lam_prev_valid = false;
  AffineWeights(d, ce->co, w->xoff);
  w->mu_step = ce->co.mu;
  if (ce->zero_start) {
    // The paper's start: history (v0, a0, 0, ...), a0 the acceleration of the constrained
    // Taylor step x(t0 + h) = x0 + h v0 + h^2/2 a0.
    for (int k = 2; k < d; ++k) N_VConst(0, ce->D[k]);
    N_VConst(0, w->lam);
  } else {
    const int flag = ConsistentStart(ce, w);
    if (flag != CE_SUCCESS) return flag;
  }
  // The first position: a constrained Taylor step. Its acceleration is the unknown; the velocity
  // is v0 (kappa = 0), so the force equation is f(t0, x0, v0).
  N_VScale(1, ce->D[2], w->a0);
  N_VScale(1, w->lam, w->lam_prev);
  const SolveSpec sp{t0, ce->xcur, t0 + ce->h, ce->h * ce->h / 2, 0, false, ce->D[1], true, false};
  const int flag = ConstrainedNewton(ce, w, sp, w->a0, w->lam, w->xpt);
  if (flag != CE_SUCCESS) return flag;
  w->factored = false;  // the start matrix has kappa = 0 and the start's mu: not a step matrix
  N_VScale(1, w->xpt, ce->xnext);
  if (ce->zero_start) {
    N_VScale(1, w->a0, ce->D[2]);
    N_VScale(1, w->lam, ce->con.lambda);
  } else {
    // The index-1 values are the consistent derivatives at t0; the start's own (a, lambda) only
    // served to put x(t0 + h) on the constraint manifold.
    N_VScale(1, w->lam_prev, ce->con.lambda);
  }
  if (!IsFinite(ce->D[2]) || !IsFinite(ce->con.lambda) || !IsFinite(ce->xnext)) {
    return ProcessError(ce, CE_FIRST_RHSFUNC_ERR, func,
                        "The constrained start produced NaN or Inf at t0 = %.17g.",
                        static_cast<double>(t0));
  }
  return CE_SUCCESS;
}

void ConstrSetStepPosition(CEodeMemRec* ce, const sunrealtype* xoff, sunrealtype mu) {
  ConWork* w = Work(ce);
  std::copy(xoff, xoff + kMaxDegree, w->xoff);
  w->mu_step = mu;
}

// The signature of every acceleration solve (the step module's SolveFn); the errors name kFunc.
int ConstrSolveStep(CEodeMemRec* ce, sunrealtype t, sunrealtype tnext, N_Vector x, N_Vector a,
                    const char* /*func*/) {
  ConWork* w = Work(ce);
  // Predictors: Taylor of the acceleration from t - h, linear extrapolation of lambda.
  PredictAccel(ce, a);
  if (w->lam_prev_valid) {
    N_VLinearSum(2, ce->con.lambda, -1, w->lam_prev, w->lam);
  } else {
    N_VScale(1, ce->con.lambda, w->lam);
  }
  N_Vector V0 = ce->D[1];  // f independent of v: it sees the last velocity, as the ODE path
  if (ce->vel_dependent) {
    VelocityOffset(ce->degree, ce->co, ce->D, w->vbase);
    V0 = w->vbase;
  }
  const StepCoeffs& co = ce->co;
  const SolveSpec sp{
      t,  x,     tnext, w->mu_step, ce->vel_dependent ? co.kappa : 0, ce->vel_dependent,
      V0, false, true};
  const int flag = ConstrainedNewton(ce, w, sp, a, w->lam, nullptr);
  if (flag != CE_SUCCESS) return flag;
  N_VScale(1, ce->con.lambda, w->lam_prev);
  N_VScale(1, w->lam, ce->con.lambda);
  w->lam_prev_valid = true;
  return CE_SUCCESS;
}

namespace {

// A NaN with a payload no arithmetic produces: an entry still holding it was not written.
constexpr std::uint64_t kSentinelBits = 0x7FF80000000CE0DEULL;
static_assert(sizeof(sunrealtype) == sizeof(kSentinelBits), "sunrealtype must be double");

sunrealtype Sentinel() {
  sunrealtype s;
  std::memcpy(&s, &kSentinelBits, sizeof(s));
  return s;
}

bool IsSentinel(sunrealtype v) {
  std::uint64_t bits;
  std::memcpy(&bits, &v, sizeof(bits));
  return bits == kSentinelBits;
}

}  // namespace

// The constraints' validation point (ValidateConfiguration calls it): one Phi call on a
// template filled with sentinels says whether Phi writes every entry.
int ValidateConstraintTemplate(CEodeMemRec* ce, const char* func) {
  if (!HasConstraints(ce) || ce->con.template_checked || ce->con.phi == nullptr) return CE_SUCCESS;
  sunrealtype* pd = N_VGetArrayPointer(ce->con.phi);
  if (pd == nullptr) return CE_SUCCESS;  // no local data: refused later by the constraint solver
  const sunindextype nc = N_VGetLength(ce->con.phi);
  for (sunindextype i = 0; i < nc; ++i) pd[i] = Sentinel();
  const int rv = ce->con.phi_fn(ce->tcur, ce->xcur, ce->con.phi, ce->user_data);
  ++ce->con.nce;
  if (rv != 0) return CE_SUCCESS;  // the start reports the failure with its own message
  sunindextype untouched = 0, first = -1;
  for (sunindextype i = 0; i < nc; ++i) {
    if (IsSentinel(pd[i])) {
      if (first < 0) first = i;
      ++untouched;
    }
  }
  if (untouched > 0) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "The constraint template has nc = %ld entries but the constraint "
                        "function wrote only %ld of them (entry %ld and %ld more left unset): the "
                        "template's length must equal the number of constraints Phi writes.",
                        static_cast<long>(nc), static_cast<long>(nc - untouched),
                        static_cast<long>(first), static_cast<long>(untouched - 1));
  }
  ce->con.template_checked = true;
  return CE_SUCCESS;
}

void ConstrReset(CEodeMemRec* ce) {
  ConstrMem& c = ce->con;
  c.nce = c.nge = c.nni = c.nnf = c.nje = c.nsetups = c.nsolves = 0;
}

void ConstrFree(CEodeMemRec* ce) {
  FreeWork(ce);
  if (ce->con.lambda != nullptr) N_VDestroy(ce->con.lambda);
  if (ce->con.phi != nullptr) N_VDestroy(ce->con.phi);
  ce->con.lambda = ce->con.phi = nullptr;
  ce->con.phi_fn = nullptr;
  ce->con.G_fn = nullptr;
  ce->con.nc = 0;
}

}  // namespace ceode

extern "C" {

int CEodeSetConstraints(void* mem, N_Vector phi_template, CEodeConstrFn phi, CEodeConstrJacFn G) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (phi == nullptr && G == nullptr) {  // remove the constraints
    ceode::ConstrFree(ce);
    ceode::Restart(ce);
    return CE_SUCCESS;
  }
  if (phi == nullptr || G == nullptr || phi_template == nullptr) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "Pass the constraint function, its Jacobian G = dPhi/dx and a "
                               "template vector of length nc (or phi = G = NULL to remove the "
                               "constraints).");
  }
  const sunindextype nc = N_VGetLength(phi_template);
  if (nc <= 0) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "The constraint template vector is empty: its length is nc.");
  }
  ceode::ConstrFree(ce);
  ce->con.lambda = ceode::CloneVector(phi_template);
  ce->con.phi = ceode::CloneVector(phi_template);
  if (ce->con.lambda == nullptr || ce->con.phi == nullptr) {
    ceode::ConstrFree(ce);
    return ceode::ProcessError(ce, CE_MEM_FAIL, __func__, "Out of memory.");
  }
  N_VConst(0, ce->con.lambda);
  ce->con.phi_fn = phi;
  ce->con.G_fn = G;
  ce->con.nc = nc;
  ce->con.template_checked = false;  // checked against Phi at the next start
  ceode::Restart(ce);
  return CE_SUCCESS;
}

int CEodeSetSchurComplement(void* mem, sunbooleantype use) {
  CEodeMemRec* ce = nullptr;
  const int flag = ceode::Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  ce->con.schur = use != SUNFALSE;
  return CE_SUCCESS;
}

int CEodeGetMultipliers(void* mem, N_Vector lambda) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce, true);
  if (flag != CE_SUCCESS) return flag;
  if (!ceode::HasConstraints(ce)) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "No constraints are set (CEodeSetConstraints): there are no "
                               "multipliers.");
  }
  if (lambda == nullptr || N_VGetLength(lambda) != ce->con.nc) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "lambda must be a vector of length nc = %ld (clone the constraint "
                               "template).",
                               static_cast<long>(ce->con.nc));
  }
  if (!ce->started) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "No multipliers yet: call CEodeEvolve first.");
  }
  // lambda(t) belongs to the acceleration at the last step time (CEodeGetCurrentTime).
  N_VScale(1, ce->con.lambda, lambda);
  return CE_SUCCESS;
}

}  // extern "C"
