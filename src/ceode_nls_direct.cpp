// The serial backend of the Newton iteration (serial vectors, a direct linear solver):
// SUNNonlinSol_Newton's algorithm (SUNDIALS 6.4 and 7.x alike: residual, -F, solve, update,
// test; one retry with a fresh matrix when the matrix was not current) with ceode_nls.cpp's
// residual, setup and test, on raw arrays in N_Vector serial's order of operations. The
// numbers are those of the generic path (test_pc compares them bit for bit). At n of a few the
// generic path's vector dispatch costs more than f (docs/performance.md); at any n the raw
// loops make fewer passes over the vectors (the weights in two instead of five, the residual's
// sums and the update with its norm in one each).
#include <sunmatrix/sunmatrix_dense.h>

#include <algorithm>
#include <cmath>

#include "ceode_impl.hpp"
#include "ceode_kernels.hpp"

namespace ceode {

namespace {

// ewt = 1 / (reltol |apred| + atol), atol from max |apred| (ErrorWeights' N_VMaxNorm, N_VAbs,
// N_VScale, N_VAddConst, N_VInv, in their order).
void Weights(const CEodeMemRec* ce, const NlsRaw& r) {
  sunrealtype amax = 0;
  for (sunindextype i = 0; i < r.n; ++i) amax = std::max(amax, std::fabs(r.apred[i]));
  const sunrealtype atol =
      ce->nls.abstol > 0 ? ce->nls.abstol : ce->nls.reltol * (amax > 0 ? amax : 1);
  for (sunindextype i = 0; i < r.n; ++i) {
    r.ewt[i] = 1 / ((ce->nls.reltol * std::fabs(r.apred[i])) + atol);
  }
}

// F(ycor) = M a - f(t, x, V0 + kappa a), a = apred + ycor (the generic residual's operations).
int Residual(CEodeMemRec* ce, const NlsRaw& r) {
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
int Iterate(CEodeMemRec* ce, const NlsRaw& r, bool own_lu, int m) {
  sunrealtype* d = r.delta;
  for (sunindextype i = 0; i < r.n; ++i) d[i] = -d[i];
  // Both solves leave the solution in delta: the own LU works in place, NlsLinearSolve copies it
  // back from its solution vector.
  if (own_lu) {
    LsSolveOwnLu(ce, d);
  } else {
    const int rv = NlsLinearSolve(ce->nls.delta, ce);
    if (rv != 0) return rv;
  }
  sunrealtype sum = 0;
  for (sunindextype i = 0; i < r.n; ++i) {
    r.ycor[i] = r.ycor[i] + d[i];
    const sunrealtype p = d[i] * r.ewt[i];
    sum += p * p;
  }
  return NlsConvTest(ce, m, std::sqrt(sum / static_cast<sunrealtype>(r.n)), 1);
}

// One SUNNonlinSolSolve: the Newton loop and its one retry with a fresh matrix.
int Newton(CEodeMemRec* ce, const NlsRaw& r, bool own_lu, bool setup) {
  bool jbad = false;
  bool& jcur = ce->nls.jcur;  // kept between solves, as SUNNonlinSol_Newton keeps its own
  for (;;) {
    int rv = Residual(ce, r);
    if (rv == 0 && setup) {
      sunbooleantype cur = SUNFALSE;
      rv = NlsLinearSetup(jbad ? SUNTRUE : SUNFALSE, &cur, ce);
      jcur = cur != SUNFALSE;
    }
    // A failing first residual or setup ends the solve, as in SUNNonlinSol_Newton: retrying it
    // with a fresh matrix would evaluate the same f at the same point again, without end.
    if (rv != 0) return rv;
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
  return ce->nls.own && FusedKernelOn(ce) && N_VGetVectorID(ce->ycor) == SUNDIALS_NVEC_SERIAL &&
         ce->ls.A != nullptr && ce->ls.LS != nullptr &&
         SUNLinSolGetType(ce->ls.LS) == SUNLINEARSOLVER_DIRECT &&
         SUNNonlinSolGetType(ce->nls.NLS) == SUNNONLINEARSOLVER_ROOTFIND;
}

void DirectArrays(CEodeMemRec* ce) {
  // The solve's work vectors keep their buffers from one (re)start to the next, so their data
  // pointers are looked up once, here.
  ce->nls.raw = NlsRaw{ce->n,
                       SerialData(ce->apred),
                       SerialData(ce->atmp),
                       SerialData(ce->vtmp),
                       SerialData(ce->V0),
                       SerialData(ce->ftmp),
                       SerialData(ce->ewt),
                       SerialData(ce->ycor),
                       SerialData(ce->nls.delta)};
}

void DirectPrepare(CEodeMemRec* ce) {
  const NlsRaw& r = ce->nls.raw;
  const int d = ce->degree;
  CombineSerial(r.n, d - 1, ce->co.V0 + 1, ce->D + 1, r.V0);
  CombineSerial(r.n, d - 2, ce->co.pred, ce->D + 2, r.apred);
  Weights(ce, r);
}

int DirectSolve(CEodeMemRec* ce, bool setup) {
  const NlsRaw& r = ce->nls.raw;
  std::fill(r.ycor, r.ycor + r.n, SUN_RCONST(0.0));
  return Newton(ce, r, ce->ls.own_lu, setup);
}

void DirectAccel(CEodeMemRec* ce, N_Vector a) {
  const NlsRaw& r = ce->nls.raw;
  sunrealtype* ad = SerialData(a);
  for (sunindextype i = 0; i < r.n; ++i) ad[i] = r.apred[i] + r.ycor[i];
}

}  // namespace ceode
