// The serial backend of the Newton iteration (small serial systems, a direct linear solver):
// SUNNonlinSol_Newton's algorithm (SUNDIALS 6.4 and 7.x alike: residual, -F, solve, update,
// test; one retry with a fresh matrix when the matrix was not current) with ceode_nls.cpp's
// residual, setup and test, on raw arrays in N_Vector serial's order of operations. The
// numbers are those of the generic path (test_implicit compares them bit for bit); at n of a
// few the generic path's vector dispatch costs more than f (docs/performance.md).
#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <algorithm>
#include <cmath>

#include "ceode_impl.hpp"

namespace ceode {

namespace {

constexpr sunindextype kDirectNewtonMaxN = 64;

// The raw arrays of the iteration, looked up once per step. The backend runs on serial vectors
// only, so the data pointers are read from the vectors' content (NV_DATA_S) rather than through
// the vector operations' dispatch (a sixth of a Newton step at n of a few).
struct Raw {
  sunindextype n;
  sunrealtype *apred, *atmp, *vtmp, *V0, *ftmp, *lstmp, *ewt, *ycor, *delta;
};

Raw RawArrays(const CEodeMemRec* ce) {
  return Raw{ce->n,
             NV_DATA_S(ce->apred),
             NV_DATA_S(ce->atmp),
             NV_DATA_S(ce->vtmp),
             NV_DATA_S(ce->V0),
             NV_DATA_S(ce->ftmp),
             NV_DATA_S(ce->lstmp),
             NV_DATA_S(ce->ewt),
             NV_DATA_S(ce->ycor),
             NV_DATA_S(ce->nls.delta)};
}

// z = sum_j c_j X_j (j < m) on raw arrays, with N_VLinearCombination_Serial's values: its
// m = 1 and m = 2 cases are N_VScale and N_VLinearSum, whose a = b and a = -b branches factor.
void RawCombination(sunindextype n, int m, const sunrealtype* c, N_Vector* X, sunrealtype* z) {
  const sunrealtype* x0 = NV_DATA_S(X[0]);
  const sunrealtype* x1 = m >= 2 ? NV_DATA_S(X[1]) : nullptr;
  if (m == 2 && (c[0] == c[1] || c[0] == -c[1])) {
    const sunrealtype sgn = c[0] == c[1] ? 1 : -1;
    for (sunindextype i = 0; i < n; ++i) z[i] = c[0] * (x0[i] + (sgn * x1[i]));
    return;
  }
  for (sunindextype i = 0; i < n; ++i) z[i] = c[0] * x0[i];
  for (int j = 1; j < m; ++j) {
    const sunrealtype* xj = NV_DATA_S(X[j]);
    for (sunindextype i = 0; i < n; ++i) z[i] += c[j] * xj[i];
  }
}

// ewt = 1 / (reltol |apred| + atol), atol from max |apred| (ErrorWeights' N_VMaxNorm, N_VAbs,
// N_VScale, N_VAddConst, N_VInv, in their order).
void Weights(const CEodeMemRec* ce, const Raw& r) {
  sunrealtype amax = 0;
  for (sunindextype i = 0; i < r.n; ++i) amax = std::max(amax, std::fabs(r.apred[i]));
  const sunrealtype atol =
      ce->nls.abstol > 0 ? ce->nls.abstol : ce->nls.reltol * (amax > 0 ? amax : 1);
  for (sunindextype i = 0; i < r.n; ++i) {
    r.ewt[i] = 1 / ((ce->nls.reltol * std::fabs(r.apred[i])) + atol);
  }
}

// F(ycor) = M a - f(t, x, V0 + kappa a), a = apred + ycor (the generic residual's operations).
int Residual(CEodeMemRec* ce, const Raw& r) {
  const sunrealtype* y = r.ycor;
  const sunrealtype kappa = ce->co.kappa;
  for (sunindextype i = 0; i < r.n; ++i) {
    r.atmp[i] = r.apred[i] + y[i];
    r.vtmp[i] = (kappa * r.atmp[i]) + r.V0[i];
  }
  const int rv = NlsRhs(ce);
  if (rv != 0) return rv;
  sunrealtype* Fd = r.delta;
  if (ce->ls.M != nullptr && SUNMatMatvec(ce->ls.M, ce->atmp, ce->nls.delta) != 0) return -1;
  const sunrealtype* lhs = ce->ls.M != nullptr ? Fd : r.atmp;
  for (sunindextype i = 0; i < r.n; ++i) Fd[i] = lhs[i] - r.ftmp[i];
  return 0;
}

// delta <- (M - kappa J)^{-1} (-delta), ycor += delta, then the test (one Newton iteration).
int Iterate(CEodeMemRec* ce, const Raw& r, bool own_lu, int m) {
  sunrealtype* d = r.delta;
  for (sunindextype i = 0; i < r.n; ++i) d[i] = -d[i];
  if (own_lu) {
    std::copy(d, d + r.n, r.lstmp);
    LsSolveOwnLu(ce, r.lstmp);
  } else {
    const int rv = NlsLinearSolve(ce->nls.delta, ce);
    if (rv != 0) return rv;
  }
  sunrealtype sum = 0;
  for (sunindextype i = 0; i < r.n; ++i) {
    d[i] = r.lstmp[i];
    r.ycor[i] = r.ycor[i] + d[i];
    const sunrealtype p = d[i] * r.ewt[i];
    sum += p * p;
  }
  return NlsConvTest(ce, m, std::sqrt(sum / static_cast<sunrealtype>(r.n)), 1);
}

// One SUNNonlinSolSolve: the Newton loop and its one retry with a fresh matrix.
int Newton(CEodeMemRec* ce, const Raw& r, bool own_lu, bool setup) {
  bool jbad = false;
  bool& jcur = ce->nls.jcur;  // kept between solves, as SUNNonlinSol_Newton keeps its own
  for (;;) {
    int rv = Residual(ce, r);
    if (rv == 0 && setup) {
      sunbooleantype cur = SUNFALSE;
      rv = NlsLinearSetup(jbad ? SUNTRUE : SUNFALSE, &cur, ce);
      jcur = cur != SUNFALSE;
    }
    for (int m = 0; rv == 0;) {
      rv = Iterate(ce, r, own_lu, m);
      if (rv == SUN_NLS_SUCCESS) {
        jcur = false;
        return SUN_NLS_SUCCESS;
      }
      if (rv != SUN_NLS_CONTINUE) break;
      if (++m >= ce->nls.maxcor) {
        rv = SUN_NLS_CONV_RECVR;
        break;
      }
      rv = Residual(ce, r);
    }
    if (rv > 0 && !jcur) {
      setup = jbad = true;
      for (sunindextype i = 0; i < r.n; ++i) r.ycor[i] = 0;
      continue;
    }
    return rv;
  }
}

}  // namespace

bool DirectNewtonApplies(const CEodeMemRec* ce) {
  return ce->nls.own && ce->fused && N_VGetVectorID(ce->ycor) == SUNDIALS_NVEC_SERIAL &&
         ce->n <= kDirectNewtonMaxN && ce->ls.A != nullptr && ce->ls.LS != nullptr &&
         SUNLinSolGetType(ce->ls.LS) == SUNLINEARSOLVER_DIRECT &&
         SUNNonlinSolGetType(ce->nls.NLS) == SUNNONLINEARSOLVER_ROOTFIND;
}

void DirectPrepare(CEodeMemRec* ce) {
  const Raw r = RawArrays(ce);
  const int d = ce->degree;
  RawCombination(r.n, d - 1, ce->co.V0 + 1, ce->D + 1, r.V0);
  RawCombination(r.n, d - 2, ce->co.pred, ce->D + 2, r.apred);
  Weights(ce, r);
}

int DirectSolve(CEodeMemRec* ce, bool setup) {
  const Raw r = RawArrays(ce);
  std::fill(r.ycor, r.ycor + r.n, SUN_RCONST(0.0));
  return Newton(ce, r, ce->ls.own_lu, setup);
}

void DirectAccel(CEodeMemRec* ce, N_Vector a) {
  const Raw r = RawArrays(ce);
  sunrealtype* ad = NV_DATA_S(a);
  for (sunindextype i = 0; i < r.n; ++i) ad[i] = r.apred[i] + r.ycor[i];
}

}  // namespace ceode
