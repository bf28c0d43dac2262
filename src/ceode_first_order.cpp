// First-order adapter: an unchanged ARKODE/CVODE right-hand side F(t, y, ydot) with
// y = [x; v] and ydot = [v; a] drives the second-order integrator. CEODE keeps x and v
// separate; the adapter presents them to F as y (an NVECTOR_MANYVECTOR whose two parts
// are CEODE's own vectors, or a serial vector of length 2n filled by copies) and hands
// the second half of ydot back as the acceleration. See docs/user_guide.md.
#include <nvector/nvector_manyvector.h>
#include <nvector/nvector_serial.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <new>

#include "ceode_impl.hpp"

namespace ceode {

// The adapter's state (Adapters::first_order); F gets the memory's user_data.
struct FirstOrder {
  CEodeFirstOrderRhsFn F = nullptr;
  bool many = false;  // ManyVector [x; v], else serial of length 2n
  sunindextype n = 0;
  N_Vector y = nullptr;     // what F sees as y
  N_Vector ydot = nullptr;  // what F writes
  N_Vector xdot = nullptr;  // ManyVector form: the first half of ydot (x' = v, discarded)
  N_Vector view[2] = {};    // serial form: x and v windows on a user vector y (SplitHalves)
  bool checked = false;     // the first half of ydot was compared with v
};

namespace {

N_Vector* Parts(N_Vector mv) {
  return static_cast<N_VectorContent_ManyVector>(mv->content)->subvec_array;
}

// y0 (or yout) must be [x; v]: a ManyVector of two equal parts or a serial 2n.
int CheckShape(CEodeMemRec* ce, const char* func, N_Vector y, const char* name,
               const FirstOrder* fo) {
  if (y == nullptr) return ProcessError(ce, CE_ILL_INPUT, func, "%s = NULL.", name);
  const N_Vector_ID id = N_VGetVectorID(y);
  if (id == SUNDIALS_NVEC_MANYVECTOR) {
    const sunindextype parts = N_VGetNumSubvectors_ManyVector(y);
    if (parts != 2) {
      return ProcessError(ce, CE_ILL_INPUT, func,
                          "%s is a ManyVector of %ld parts: the first-order adapter needs two, "
                          "[x; v].",
                          name, static_cast<long>(parts));
    }
    N_Vector x = N_VGetSubvector_ManyVector(y, 0);
    N_Vector v = N_VGetSubvector_ManyVector(y, 1);
    if (N_VGetLength(x) != N_VGetLength(v) || N_VGetVectorID(x) != N_VGetVectorID(v)) {
      return ProcessError(ce, CE_ILL_INPUT, func,
                          "The parts of %s differ (lengths %ld and %ld, vector ids %d and %d): "
                          "x and v must be vectors of one kind and length.",
                          name, static_cast<long>(N_VGetLength(x)),
                          static_cast<long>(N_VGetLength(v)), static_cast<int>(N_VGetVectorID(x)),
                          static_cast<int>(N_VGetVectorID(v)));
    }
  } else if (id == SUNDIALS_NVEC_SERIAL) {
    const sunindextype len = N_VGetLength(y);
    if (len <= 0 || len % 2 != 0) {
      return ProcessError(ce, CE_ILL_INPUT, func,
                          "%s is a serial vector of length %ld: [x; v] needs an even, positive "
                          "length 2n.",
                          name, static_cast<long>(len));
    }
  } else {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "%s has vector id %d: the first-order adapter takes an NVECTOR_MANYVECTOR "
                        "of two parts [x; v] or a serial vector of length 2n.",
                        name, static_cast<int>(id));
  }
  if (fo != nullptr &&
      (fo->many != (id == SUNDIALS_NVEC_MANYVECTOR) || N_VGetLength(y) != 2 * fo->n)) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "%s (length %ld) is not shaped like y0 of CEodeInitFirstOrder (length %ld, "
                        "%s).",
                        name, static_cast<long>(N_VGetLength(y)), static_cast<long>(2 * fo->n),
                        fo->many ? "ManyVector" : "serial");
  }
  return CE_SUCCESS;
}

// x and v of a user vector y, checked by CheckShape.
void Split(FirstOrder* fo, N_Vector y, N_Vector* x, N_Vector* v) {
  SplitHalves(y, fo->n, nullptr, fo->view, x, v);  // the views exist (Build)
}

void Destroy(FirstOrder* fo) {
  N_Vector* all[] = {&fo->y, &fo->ydot, &fo->xdot, &fo->view[0], &fo->view[1]};
  for (N_Vector* w : all) {
    if (*w != nullptr) N_VDestroy(*w);
    *w = nullptr;
  }
  delete fo;
}

// The wrappers F sees. ManyVector: parts are swapped in per call (no copies);
// serial: y and ydot own 2n entries.
bool Build(FirstOrder* fo, N_Vector y0, SUNContext ctx) {
  if (fo->many) {
    N_Vector parts[2] = {N_VGetSubvector_ManyVector(y0, 0), N_VGetSubvector_ManyVector(y0, 1)};
    fo->xdot = CloneVector(parts[0]);
    fo->y = N_VNew_ManyVector(2, parts, ctx);
    fo->ydot = N_VNew_ManyVector(2, parts, ctx);
    return fo->xdot != nullptr && fo->y != nullptr && fo->ydot != nullptr;
  }
  fo->y = N_VNew_Serial(2 * fo->n, ctx);
  fo->ydot = N_VNew_Serial(2 * fo->n, ctx);
  N_Vector x = nullptr, v = nullptr;
  return fo->y != nullptr && fo->ydot != nullptr && SplitHalves(y0, fo->n, ctx, fo->view, &x, &v);
}

// F at (t, [x; v]) with the user's data; the first half of ydot goes to xd, the second to a.
int CallF(FirstOrder* fo, void* user_data, sunrealtype t, N_Vector x, N_Vector v, N_Vector xd,
          N_Vector a) {
  if (fo->many) {
    N_Vector* yp = Parts(fo->y);
    N_Vector* dp = Parts(fo->ydot);
    yp[0] = x;
    yp[1] = v;
    dp[0] = xd;
    dp[1] = a;
    return fo->F(t, fo->y, fo->ydot, user_data);
  }
  const auto bytes = static_cast<size_t>(fo->n) * sizeof(sunrealtype);
  sunrealtype* yd = N_VGetArrayPointer(fo->y);
  std::memcpy(yd, N_VGetArrayPointer(x), bytes);
  std::memcpy(yd + fo->n, N_VGetArrayPointer(v), bytes);
  const int rv = fo->F(t, fo->y, fo->ydot, user_data);
  sunrealtype* dd = N_VGetArrayPointer(fo->ydot);
  std::memcpy(N_VGetArrayPointer(a), dd + fo->n, bytes);
  if (xd != nullptr) std::memcpy(N_VGetArrayPointer(xd), dd, bytes);
  return rv;
}

// Largest |x'_i - v_i| relative to max(|v|, tiny) after F at (t, x, v).
int FirstHalfMismatch(CEodeMemRec* ce, FirstOrder* fo, N_Vector x, N_Vector v, sunrealtype* rel) {
  N_Vector xd = ce->tmp1;
  const int rv = CallF(fo, ce->user_data, ce->tcur, x, v, xd, ce->tmp2);
  if (rv != 0) return rv;
  N_VLinearSum(1, xd, -1, v, xd);
  const sunrealtype vmax = N_VMaxNorm(v);
  *rel = N_VMaxNorm(xd) / std::max(vmax, SUN_SMALL_REAL);
  return 0;
}

// Once per (re)initialisation: F must return x' = v (generalised velocities x' = T(x) v
// need the native form). At rest (v = 0) a unit velocity is tried as well.
int CheckFirstHalf(CEodeMemRec* ce, FirstOrder* fo, const char* func) {
  constexpr sunrealtype kTol = 16 * SUN_UNIT_ROUNDOFF;
  sunrealtype rel = 0;
  N_VScale(1, ce->D[1], ce->tmp3);
  int rv = FirstHalfMismatch(ce, fo, ce->xcur, ce->tmp3, &rel);
  if (rv == 0 && rel <= kTol && N_VMaxNorm(ce->tmp3) == 0) {
    N_VConst(1, ce->tmp3);
    rv = FirstHalfMismatch(ce, fo, ce->xcur, ce->tmp3, &rel);
  }
  if (rv != 0) {
    return ProcessError(ce, CE_FIRST_RHSFUNC_ERR, func,
                        "F failed (returned %d) at t = %.17g when the adapter first called it.", rv,
                        static_cast<double>(ce->tcur));
  }
  if (!(rel <= kTol)) {
    return ProcessError(
        ce, CE_ILL_INPUT, func,
        "The first half of F's ydot is not v (max |ydot_x - v| / max |v| = %.3g at "
        "t = %.17g): the adapter needs y = [x; v] with x' = v. For generalised "
        "velocities (x' = T(x) v) use the native form, CEodeInit with f(t, x, v) = a.",
        static_cast<double>(rel), static_cast<double>(ce->tcur));
  }
  fo->checked = true;
  return CE_SUCCESS;
}

// The preamble of the entries that act on an attached first-order problem: the access guard,
// the adapter, and y split into [x; v] views after its shape is checked.
int AccessFirstOrder(void* mem, const char* func, N_Vector y, const char* name, CEodeMemRec** ce,
                     FirstOrder** fo, N_Vector* x, N_Vector* v) {
  int flag = Access(mem, func, ce, true);
  if (flag != CE_SUCCESS) return flag;
  *fo = (*ce)->adapters.first_order;
  if (*fo == nullptr) {
    return ProcessError(*ce, CE_NO_MALLOC, func,
                        "No first-order problem: call CEodeInitFirstOrder first.");
  }
  if ((flag = CheckShape(*ce, func, y, name, *fo)) != CE_SUCCESS) return flag;
  Split(*fo, y, x, v);
  return CE_SUCCESS;
}

}  // namespace

bool SplitHalves(N_Vector y, sunindextype n, SUNContext ctx, N_Vector* view, N_Vector* x,
                 N_Vector* v) {
  if (N_VGetVectorID(y) == SUNDIALS_NVEC_MANYVECTOR) {
    *x = N_VGetSubvector_ManyVector(y, 0);
    *v = N_VGetSubvector_ManyVector(y, 1);
    return true;
  }
  for (int i = 0; i < 2; ++i) {
    if (view[i] == nullptr && (view[i] = N_VNewEmpty_Serial(n, ctx)) == nullptr) return false;
    N_VSetArrayPointer(N_VGetArrayPointer(y) + i * n, view[i]);
  }
  *x = view[0];
  *v = view[1];
  return true;
}

int SplitFirstOrder(CEodeMemRec* ce, N_Vector y, N_Vector* view, N_Vector* x, N_Vector* v,
                    const char* func) {
  if (y == nullptr) return ProcessError(ce, CE_ILL_INPUT, func, "The state vector is NULL.");
  const N_Vector_ID id = N_VGetVectorID(y);
  const N_Vector_ID want = N_VGetVectorID(ce->xcur);
  if (id == SUNDIALS_NVEC_MANYVECTOR) {
    const sunindextype np = N_VGetNumSubvectors_ManyVector(y);
    const N_Vector px = np == 2 ? N_VGetSubvector_ManyVector(y, 0) : nullptr;
    const N_Vector pv = np == 2 ? N_VGetSubvector_ManyVector(y, 1) : nullptr;
    if (np != 2 || N_VGetLength(px) != ce->n || N_VGetLength(pv) != ce->n ||
        N_VGetVectorID(px) != want || N_VGetVectorID(pv) != want) {
      return ProcessError(ce, CE_ILL_INPUT, func,
                          "The ManyVector state has %ld parts: it must have two, y = [x; v], "
                          "each of length %ld and of the vector type of CEODE's x0.",
                          static_cast<long>(np), static_cast<long>(ce->n));
    }
  } else if (id != SUNDIALS_NVEC_SERIAL || want != SUNDIALS_NVEC_SERIAL ||
             N_VGetLength(y) != 2 * ce->n) {
    return ProcessError(ce, CE_ILL_INPUT, func,
                        "The state vector (id %d, length %ld) is neither a ManyVector [x; v] of "
                        "two parts of length %ld nor a serial vector of length %ld (2n, with a "
                        "serial x0 in CEodeInit).",
                        static_cast<int>(id), static_cast<long>(N_VGetLength(y)),
                        static_cast<long>(ce->n), static_cast<long>(2 * ce->n));
  }
  return SplitHalves(y, ce->n, ce->sunctx, view, x, v)
             ? CE_SUCCESS
             : ProcessError(ce, CE_MEM_FAIL, func, "Out of memory.");
}

int FirstOrderRhs(sunrealtype t, N_Vector x, N_Vector v, N_Vector a, void* mem) {
  auto* ce = static_cast<CEodeMemRec*>(mem);
  FirstOrder* fo = ce->adapters.first_order;
  return CallF(fo, ce->user_data, t, x, v, fo->many ? fo->xdot : nullptr, a);
}

void FirstOrderFree(CEodeMemRec* ce) {
  FirstOrder* fo = ce->adapters.first_order;
  if (fo == nullptr) return;
  ce->adapters.first_order = nullptr;
  SelectRhs(ce);
  Destroy(fo);
}

}  // namespace ceode

extern "C" {

int CEodeInitFirstOrder(void* mem, CEodeFirstOrderRhsFn F, sunrealtype t0, N_Vector y0) {
  CEodeMemRec* ce = nullptr;
  int flag = ceode::Access(mem, __func__, &ce);
  if (flag != CE_SUCCESS) return flag;
  if (F == nullptr) {
    return ceode::ProcessError(
        ce, CE_ILL_INPUT, __func__,
        "F = NULL: pass the first-order right-hand side F(t, y, ydot, data).");
  }
  if ((flag = ceode::CheckShape(ce, __func__, y0, "y0", nullptr)) != CE_SUCCESS) return flag;
  auto* fo = new (std::nothrow) ceode::FirstOrder;
  if (fo == nullptr) return ceode::ProcessError(ce, CE_MEM_FAIL, __func__, "Out of memory.");
  fo->F = F;
  fo->many = N_VGetVectorID(y0) == SUNDIALS_NVEC_MANYVECTOR;
  fo->n = N_VGetLength(y0) / 2;
  if (!ceode::Build(fo, y0, ce->sunctx)) {
    ceode::Destroy(fo);
    return ceode::ProcessError(ce, CE_MEM_FAIL, __func__, "Out of memory.");
  }
  N_Vector x0 = nullptr;
  N_Vector v0 = nullptr;
  ceode::Split(fo, y0, &x0, &v0);
  // A previous adapter stays in place until this problem is initialised, so a failure leaves the
  // memory as it was. There is no native f: the adapter's FirstOrderRhs is evaluated instead.
  flag = ceode::InitProblem(ce, __func__, nullptr, t0, x0, v0);
  if (flag != CE_SUCCESS) {
    ceode::Destroy(fo);
    return flag;
  }
  ceode::FirstOrderFree(ce);
  ce->adapters.first_order = fo;
  ceode::SelectRhs(ce);
  return CE_SUCCESS;
}

int CEodeReInitFirstOrder(void* mem, sunrealtype t0, N_Vector y0) {
  CEodeMemRec* ce = nullptr;
  ceode::FirstOrder* fo = nullptr;
  N_Vector x0 = nullptr;
  N_Vector v0 = nullptr;
  int flag = ceode::AccessFirstOrder(mem, __func__, y0, "y0", &ce, &fo, &x0, &v0);
  if (flag != CE_SUCCESS) return flag;
  flag = CEodeReInit(mem, t0, x0, v0);
  if (flag == CE_SUCCESS) fo->checked = false;
  return flag;
}

int CEodeEvolveFirstOrder(void* mem, sunrealtype tout, N_Vector yout, sunrealtype* tret,
                          int itask) {
  CEodeMemRec* ce = nullptr;
  ceode::FirstOrder* fo = nullptr;
  N_Vector x = nullptr;
  N_Vector v = nullptr;
  int flag = ceode::AccessFirstOrder(mem, __func__, yout, "yout", &ce, &fo, &x, &v);
  if (flag != CE_SUCCESS) return flag;
  if (ce->ls.mfn != nullptr || ce->con.phi_fn != nullptr || ce->ls.jac != nullptr) {
    return ceode::ProcessError(ce, CE_ILL_INPUT, __func__,
                               "A mass matrix, constraints or a velocity Jacobian is attached: "
                               "with those use the native form (CEodeInit, CEodeEvolve).");
  }
  if (!fo->checked && (flag = ceode::CheckFirstHalf(ce, fo, __func__)) != CE_SUCCESS) {
    return flag;
  }
  return CEodeEvolve(mem, tout, x, v, tret, itask);
}

}  // extern "C"
