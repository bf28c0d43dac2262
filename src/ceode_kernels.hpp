// The vector kernels of the algorithms, private: linear combinations of whole vectors, the step's
// update plan, the start's plans and the output copies. Two backends with the same operations in
// the same order, so bit for bit equal results: the reference on N_Vector operations
// (ceode_kernels_ref.cpp, every vector type) and the serial one on raw arrays
// (ceode_kernels_serial.cpp: one sweep through memory, no dispatch per operation). test_fused
// runs the serial backend against the reference. Algorithm files reach vector data only here.
#ifndef CEODE_SRC_CEODE_KERNELS_HPP_
#define CEODE_SRC_CEODE_KERNELS_HPP_

#include <nvector/nvector_serial.h>

#include <cmath>

#include "ceode_impl.hpp"

namespace ceode {

// One linear combination of the step's update: out = sum_i c[i] X[i] (+ old,
// for a quantity that accumulates). Zero coefficients are dropped when the plan
// is built, so they cost no memory pass.
struct Combo {
  int m = 0;  // only the first m entries below are set
  sunrealtype c[kMaxDegree + 2];
  N_Vector X[kMaxDegree + 2];
  N_Vector old = nullptr;  // accumulated quantity, added last (nullptr: none)
  int level = 0;           // compensation slot of an accumulated quantity
  N_Vector out = nullptr;
  // Without compensation: old leads the sum instead, (old + c_0 X_0) + c_1 X_1 + ... (G3_CD's
  // leapfrog form, LeapKernels).
  bool lead_old = false;

  void Add(sunrealtype coef, N_Vector v) {
    if (coef != 0) {
      c[m] = coef;
      X[m++] = v;
    }
  }
};

// Combinations run in order (the step's update: z, the lower derivatives, x(t + h)).
struct UpdatePlan {
  int n = 0;
  Combo combos[kMaxDegree];
};

// The same plan on raw arrays, for the serial backend.
struct FusedTerms {
  int m;
  int form;       // the arithmetic of the sum, fixed when the plan is built (kernels_serial)
  bool in_place;  // out is also the accumulated term X[m - 1] (an in-place plan)
  bool exact;     // compensated, its increment summed error-free (ExactIncrement)
  bool lead_old = false;  // the accumulated term is X[0] (Combo::lead_old), not X[m - 1]
  sunrealtype c[kMaxDegree + 3];
  // c[j] twice, for the small kernels' pairs of entries: each weight is then an aligned operand
  // of the pair's product, with no splat per term and entry pair.
  alignas(16) sunrealtype c2[kMaxDegree + 3][2];
  sunrealtype* X[kMaxDegree + 3];
  sunrealtype* old;
  sunrealtype* compnew;
  sunrealtype* out;
};
struct FusedPlan {
  int n = 0;
  // 1 + the index of the plan's shape among those with a kernel of their own
  // (ceode_kernels_serial.cpp, kShapes: every term count a compile-time constant), 0 for none.
  int shape = 0;
  bool compensated = false;  // the sums carry Kahan compensations (FusedTerms::old)
  FusedTerms terms[kMaxDegree];
};

// Compensation vectors of the accumulated quantities (index = Combo::level), and the scratch
// vectors the reference needs when compensating: tmp, and kCompWork (ceode_impl.hpp) more for
// the error-free increments on vectors without host data (CompensatedSumByOps).
struct Compensation {
  bool on = false;
  N_Vector* comp = nullptr;
  N_Vector* compnew = nullptr;
  N_Vector tmp = nullptr;
  N_Vector* work = nullptr;
};

// ---- Reference backend: N_Vector operations (ceode_kernels_ref.cpp) ----

// z = sum c_i X_i through N_VScale / N_VLinearSum / N_VLinearCombination (by term count).
void Combine(int m, const sunrealtype* c, N_Vector* X, N_Vector z);
// Every combination of the plan, one N_Vector operation per term.
void UpdateReference(const UpdatePlan& plan, const Compensation& cs);

// ---- Serial backend: raw arrays (ceode_kernels_serial.cpp) ----

// The data of a vector that exposes it (NVECTOR_SERIAL's content without a call). Inline: the
// serial backends look up several vectors per step, and at n of a few a call each is visible.
inline sunrealtype* SerialData(N_Vector v) {
  if (v->ops->nvgetarraypointer == N_VGetArrayPointer_Serial) return NV_DATA_S(v);
  return N_VGetArrayPointer(v);
}
// out[0 .. n) = sum_j c[j] x[j][0 .. n), j < m (0 <= m <= kMaxDegree + 3), with the values of
// Combine on serial vectors (N_VLinearSum's a = +-b shortcuts included). out is not an input.
void CombineSerial(sunindextype n, int m, const sunrealtype* c, const sunrealtype* const* x,
                   sunrealtype* out);
// x[j] = the data of X[j], j < m, for vectors all NVECTOR_SERIAL or all of another kind that
// exposes its (local) data, as the solvers' vectors are: one test for all.
inline void SerialDataOf(int m, const N_Vector* X, const sunrealtype** x) {
  const bool serial = m > 0 && X[0]->ops->nvgetarraypointer == N_VGetArrayPointer_Serial;
  for (int j = 0; j < m; ++j) x[j] = serial ? NV_DATA_S(X[j]) : N_VGetArrayPointer(X[j]);
}

// out = sum_j c_j x_j entry by entry, the terms in order (the generic form's arithmetic), for
// 3 <= m <= kMaxDegree terms, where no shortcut form applies; returns false for other m. Inline,
// with the term count a constant in each branch: at n of a few the solvers' combinations are a
// few multiplications, and a call through a table costs as much.
template <int M>
inline void CombineEntriesOf(sunindextype n, const sunrealtype* c, const sunrealtype* const* x,
                             sunrealtype* out) {
  for (sunindextype i = 0; i < n; ++i) {
    sunrealtype s = c[0] * x[0][i];
    for (int j = 1; j < M; ++j) s += c[j] * x[j][i];
    out[i] = s;
  }
}
inline bool CombineEntries(sunindextype n, int m, const sunrealtype* c, const sunrealtype* const* x,
                           sunrealtype* out) {
  static_assert(kMaxDegree == 8, "CombineEntries lists every term count");
  switch (m) {
    case 3:
      CombineEntriesOf<3>(n, c, x, out);
      return true;
    case 4:
      CombineEntriesOf<4>(n, c, x, out);
      return true;
    case 5:
      CombineEntriesOf<5>(n, c, x, out);
      return true;
    case 6:
      CombineEntriesOf<6>(n, c, x, out);
      return true;
    case 7:
      CombineEntriesOf<7>(n, c, x, out);
      return true;
    case 8:
      CombineEntriesOf<8>(n, c, x, out);
      return true;
    default:
      return false;
  }
}
// The same on the data of the vectors X, all NVECTOR_SERIAL or all of another kind exposing
// their (local) data.
void CombineSerial(sunindextype n, int m, const sunrealtype* c, const N_Vector* X,
                   sunrealtype* out);
// to = from: memcpy on serial vectors, N_VScale(1, ...) on others; the same values either way.
void CopyVector(N_Vector from, N_Vector to);
// CopyVector that also tells whether every value copied is finite: on serial vectors the test
// rides on the copy (one pass, no call per vector); on others N_VScale, then IsFinite.
bool CopyFinite(N_Vector from, N_Vector to);
// CopyPairFinite's general form, out of line: CopyFinite on both (serial: whether all four are).
bool CopyPairFiniteAny(N_Vector x, N_Vector v, N_Vector xout, N_Vector vout, bool serial);
// CopyPairFinite at N unknowns, unrolled: the values loaded before any store (the outputs share
// memory with neither input, but the compiler cannot know), and the test one sum of a - a, which
// is 0 for finite a and NaN otherwise.
template <int N>
inline bool CopyPairFiniteOf(const sunrealtype* xs, const sunrealtype* vs, sunrealtype* xo,
                             sunrealtype* vo) {
  sunrealtype a[N];
  sunrealtype b[N];
  sunrealtype zero = 0;
  for (int i = 0; i < N; ++i) {
    a[i] = xs[i];
    b[i] = vs[i];
    zero += (a[i] - a[i]) + (b[i] - b[i]);
  }
  for (int i = 0; i < N; ++i) {
    xo[i] = a[i];
    vo[i] = b[i];
  }
  return zero == 0;
}
// xout = x and vout = v (CopyFinite on both, in one call), all four of one length: whether the
// values copied are finite. Inline for serial vectors of 1 to 4 unknowns (a call of CE_ONE_STEP
// on a small problem): no call and no loop set-up.
inline bool CopyPairFinite(N_Vector x, N_Vector v, N_Vector xout, N_Vector vout) {
  const auto get = N_VGetArrayPointer_Serial;
  const bool serial = x->ops->nvgetarraypointer == get && v->ops->nvgetarraypointer == get &&
                      xout->ops->nvgetarraypointer == get && vout->ops->nvgetarraypointer == get;
  const sunindextype n = serial ? NV_LENGTH_S(x) : 0;
  if (n < 1 || n > 4) return CopyPairFiniteAny(x, v, xout, vout, serial);
  const sunrealtype* xs = NV_DATA_S(x);
  const sunrealtype* vs = NV_DATA_S(v);
  sunrealtype* xo = NV_DATA_S(xout);
  sunrealtype* vo = NV_DATA_S(vout);
  if (n == 1) return CopyPairFiniteOf<1>(xs, vs, xo, vo);
  if (n == 2) return CopyPairFiniteOf<2>(xs, vs, xo, vo);
  if (n == 3) return CopyPairFiniteOf<3>(xs, vs, xo, vo);
  return CopyPairFiniteOf<4>(xs, vs, xo, vo);
}
// CopyPairFinite out of line: the fixed step's one-step path keeps its frame small at one unknown,
// where it copies without it.
bool CopyPairFiniteApart(N_Vector x, N_Vector v, N_Vector xout, N_Vector vout);
// Whether every entry is finite, on the data of a serial vector (or any exposing it) without a
// call per vector; IsFinite (two norms) on the others.
bool AllFinite(N_Vector v);
// N_VGetLength without the two calls through the operations table on serial vectors: the
// output vectors' lengths are checked on every CEodeEvolve call.
inline sunindextype VectorLength(N_Vector v) {
  if (v->ops->nvgetlength == N_VGetLength_Serial) return NV_LENGTH_S(v);
  return N_VGetLength(v);
}
// Whether a fixed-step CEodeEvolve call goes straight to the steps and the outputs (ceode.cpp's
// direct path, ceode_step.cpp's OneStepEvolve): the general path's target logic is needed only for
// a stop time, roots, error control or a pending guard check, and its checks of the start only
// before one. Arguments that CheckEvolveArgs would refuse take the general path, which reports
// them.
// DirectConfiguration: the memory's part of the test, on a started run.
// DirectOptions: its part that the start does not decide (the options set between calls and a
// pending guard check) but the stop time, which ceode_step.cpp's direct paths admit where it lies
// beyond the call's end; mxstep is always positive (CEodeSetMaxNumSteps).
inline bool DirectOptions(const CEodeMemRec* ce) {
  return ce->root == nullptr && ce->adapt == nullptr && !ce->guard.pending;
}
inline bool DirectConfiguration(const CEodeMemRec* ce) {
  return ce->h > 0 && !ce->tstop_set && DirectOptions(ce);
}
inline bool DirectEvolve(const CEodeMemRec* ce, sunrealtype tout, N_Vector xout, N_Vector vout,
                         const sunrealtype* tret) {
  const bool args = xout != nullptr && vout != nullptr && tret != nullptr && std::isfinite(tout) &&
                    VectorLength(xout) == ce->n && VectorLength(vout) == ce->n;
  return args && ce->started && DirectConfiguration(ce);
}
// Whether v is an NVECTOR_SERIAL of length n (v may be NULL).
inline bool SerialOfLength(N_Vector v, sunindextype n) {
  return v != nullptr && v->ops->nvgetarraypointer == N_VGetArrayPointer_Serial &&
         NV_LENGTH_S(v) == n;
}
// The plan on its raw-pointer form (vectors of length n): one pass over the vectors (entry by
// entry for small n). Returns the L1 norm of the last combination's output (the new position)
// for the growth check, summed in four interleaved partial sums, so it may differ from
// N_VL1Norm by rounding (n * unit round-off relative); the outputs are bitwise those of
// UpdateReference.
sunrealtype UpdateSerial(const FusedPlan& fp, sunindextype n);
// The kernel for a caller that runs the plan many times at length n: UpdateSerial's, or at a few
// entries one that reads each value once, which takes a test of the plan's vectors to choose
// (more than the run it spares for a plan run once). The same outputs.
using SerialKernelFn = sunrealtype (*)(const FusedPlan&, sunindextype);
SerialKernelFn SerialKernel(const FusedPlan& fp, sunindextype n);
// Systems smaller than this take the entry-by-entry kernels of the plan's shape, whose cost is a
// few instructions per call; from this length on G3_CD's plan takes the leapfrog's form, whose
// kernels save one vector's traffic per step (LeapForm).
constexpr sunindextype kSmallSystem = 16;
// G3_CD's step on its plan in the leapfrog's form (ceode_step_plans.cpp, LeapForm): v = (v_old +
// c a_old) + c a, u = v + c a, x(t + h) = x(t) + h u. The next step's first rounding, v + c a, is
// this step's u (the half-step velocity), so a run of steps can store u where v was and read
// a_old in its first step alone: first reads v_old and a_old and stores u, mid reads and stores
// u, last reads u and stores v; none writes u's work vector. Each gives the bits of
// UpdateSerial's steps one by one. False, with nothing set, for other plans or lengths.
struct LeapKernels {
  SerialKernelFn first = nullptr;
  SerialKernelFn mid = nullptr;
  SerialKernelFn last = nullptr;
};
bool LeapKernelsOf(const FusedPlan& fp, sunindextype n, LeapKernels* k);
// The raw-pointer form of a plan (vectors that expose their data). Returns false when some
// combination writes a vector it also reads, other than its own accumulated quantity without
// compensation (an in-place plan's, read entry by entry before it is written): the serial
// backend must not run that plan.
bool BuildFusedPlan(const UpdatePlan& plan, const Compensation& cs, FusedPlan* fp);

// The accumulated quantities whose compensated increments are summed error-free: the position
// and the velocity, which f reads (docs/theory.md section 10). The higher derivatives' rounded
// increments do not measurably reach the solution; they keep plain Kahan summation.
inline bool ExactIncrement(int level) { return level <= 1; }
// An accumulated combination with compensation on the (local) data of its vectors, the
// increment summed error-free as the serial backend sums it (the same numbers); false, with
// nothing written, when some vector does not expose its data.
bool CompensatedSumOnData(const Combo& cb, const Compensation& cs);

// ---- A plan with its backend fixed when it is prepared ----

// The serial backend when allowed (every vector NVECTOR_SERIAL, the fused kernel on) and the
// plan can run on it, the reference otherwise: the same numbers either way.
struct KernelPlan {
  UpdatePlan plan;
  FusedPlan fused;
  bool serial = false;
};
void PreparePlan(bool serial_allowed, KernelPlan* kp);
// kp with the coefficients of plan, a plan on the same vectors with the same terms (the same
// step at another h): the raw-pointer form keeps its pointers. Returns false, leaving kp to be
// prepared again, when the terms or a sum's form differ.
bool RefreshPlanCoefficients(const UpdatePlan& plan, KernelPlan* kp);
void RunPlan(const KernelPlan& kp, sunindextype n);

// ---- The adaptive step's vector work (ceode_kernels_adapt.cpp) ----

struct AdaptAfterF;
struct AdaptPosition;

// Each operation on the backend chosen once per start: N_Vector operations, or loops on the
// raw arrays of serial vectors with the same arithmetic in the same order (the same numbers;
// test_fused compares them).
struct AdaptKernels {
  bool serial = false;  // every vector of the run is NVECTOR_SERIAL and the fused kernel is on
  sunindextype n = 0;
  // out = sum_j c[j] X[j] (Combine's values; out is not an input).
  void Lin(int m, const sunrealtype* c, N_Vector* X, N_Vector out) const;
  // out[k] = sum_j c[j][k] X[j], k < nout (Lin's values; no out among the X), m <= kMaxDegree:
  // the weights by term, row j those of X[j].
  void LinMany(int nout, int m, const sunrealtype (*c)[kMaxDegree], N_Vector* X,
               N_Vector* out) const;
  // x += c y (N_VLinearSum(1, x, c, y, x)).
  void Axpy(sunrealtype c, N_Vector y, N_Vector x) const;
  void Scale(sunrealtype c, N_Vector x) const;  // x *= c
  sunrealtype WrmsNorm(N_Vector x, N_Vector w) const;
  sunrealtype L1Norm(N_Vector x) const;
  // ewt = 1 / (rtol |x| + atol) with a scalar atol (atolv == nullptr) or a vector one; returns
  // the smallest denominator (ewt is not formed when it is not positive).
  sunrealtype Weights(N_Vector x, sunrealtype rtol, sunrealtype atol, N_Vector atolv,
                      N_Vector ewt) const;
  // The whole vector work of a step once f is known at its end (AdaptAfterF); returns the
  // estimate's WRMS norm in the node's weights (0 with kEstNone) and the smallest denominator
  // of the new weights in *dmin (1 without them); with the next position (spec_m > 0, serial
  // pass only) its L1 norm in *l1.
  // (Inline, as AfterFIsFused: on few unknowns the calls cost as much as the pass.)
  inline sunrealtype AfterF(const AdaptAfterF& w, sunrealtype* dmin, sunrealtype* l1) const;
  // Chooses AfterF's serial pass for w (kept in w while what it depends on stays); whether AfterF
  // runs w in one serial pass (then w.kp is not read). AfterF runs the choice of the last call:
  // call it whenever w's fields change.
  inline bool AfterFIsFused(AdaptAfterF* w) const;
  // AfterF by the N_Vector operations one by one (the reference; no serial pass chosen).
  sunrealtype AfterFByOperations(const AdaptAfterF& w, sunrealtype* dmin) const;
  // AfterFIsFused's choice for the key of w's fields.
  void ChooseAfterF(AdaptAfterF* w, int key) const;
  // The history's remap and the position (AdaptPosition); returns the position's L1 norm and
  // the smallest denominator of its weights in *dmin (1 without them).
  sunrealtype Position(AdaptPosition* w, sunrealtype* dmin) const;
};

// What an adaptive step computes once f is known at its end x(t_{n+1}) (docs/theory.md 12.3),
// in this order on the reference backend (each operation as above) and entry by entry in one
// pass on the serial one for the named sets' shapes (the same operations per entry):
//  1. the derivatives at t_{n+1}: the plan's sums (z, D_1, D_3 .. D_{d-2} into Dn);
//  2. the divided differences dout[j] = r[j] (dnew[j] - dold[j]), j < ndiff, in order;
//  3. the estimate est: the last difference (kEstLast), a copy of est_src (kEstCopy), times
//     scale; or zero (kEstNone, no norm);
//  4. its WRMS norm in the node's weights ewt;
//  5. the top derivative's rate yd = yc (Dn[d-1] - D[d-1]);
//  6. the weights of x = x(t_{n+1}) into ewt_next: 1 / (rtol |x| + atol) with a scalar atol
//     (kWeightsScalar) or the vector atolv (kWeightsVector); none (kWeightsNone) with the
//     user's weights or where the position's pass made them (AdaptPosition);
//  7. with spec_m > 0 (the serial pass only, weights kWeightsNone): the position of a next step
//     of the same h, AdaptPosition's sum and arithmetic over {x, Dn[1] .. Dn[d-1], yd} (the
//     values this pass writes) with the weights spec_c[0 .. spec_m - 1] (spec_c[0] = 1), into
//     spec_x, its weights (spec_weights, positive) into spec_ewt and its L1 norm as Position's.
struct AdaptAfterF {
  enum { kEstLast, kEstCopy, kEstNone };
  enum { kWeightsScalar, kWeightsVector, kWeightsNone };
  // The derivatives' sums: the reference runs the plan (BuildUpdatePlan's sums without the
  // position); the serial pass takes their weights from cw, sum s (z first when d > 3, then D_1,
  // D_3, .., D_{d-2}), term j in the plan's order without the accumulated value's 1, when full
  // (no weight zero, so that the plan dropped none). kp is needed only when the pass is not
  // fused (AfterFIsFused).
  const KernelPlan* kp = nullptr;
  bool full = false;
  int fused_key = -1;     // AfterFIsFused's choice for these fields: the serial pass,
  void* fused = nullptr;  // or nullptr for the operations one by one
  sunrealtype cw[kMaxDegree][kMaxDegree] = {};
  int d = 0;
  N_Vector* D = nullptr;   // the node's history (index 1 .. d - 1)
  N_Vector* Dn = nullptr;  // the new node's (Dn[2] = a, the plan writes the others)
  // The serial pass on fewer entries than its pair loop takes reads the histories' data instead
  // from hist_data[0][k] (D's) and hist_data[1][k] (Dn's), 1 <= k < d: the adaptive step looks
  // them up once for each of the two configurations of the buffers.
  sunrealtype* const (*hist_data)[kMaxDegree] = nullptr;
  int ndiff = 0;
  sunrealtype r[kMaxDegree] = {};
  // dnew[j] = j == 0 ? Dn[2] : the node's new difference j (dout[j - 1]); dold[j] = j == 0 ? D[2]
  // : the node's difference j; dout[j] = the new difference j + 1, the last one est. The serial
  // pass reads the differences' data instead from dd_data[dd_cur][j] (the node's) and
  // dd_data[1 - dd_cur][j] (the new ones), 1 <= j < ndiff: the adaptive step fills dnew, dold
  // and dout only for the operations one by one.
  N_Vector dnew[kMaxDegree] = {};
  N_Vector dold[kMaxDegree] = {};
  N_Vector dout[kMaxDegree] = {};
  sunrealtype* const (*dd_data)[kMaxDegree] = nullptr;
  int dd_cur = 0;
  int est_kind = kEstNone;
  N_Vector est_src = nullptr;
  sunrealtype scale = 0;
  N_Vector est = nullptr;
  N_Vector ewt = nullptr;
  sunrealtype yc = 0;
  N_Vector yd = nullptr;
  int weights = kWeightsNone;
  bool positive = false;  // atol > 0 in every entry: the denominators are positive for finite x
  N_Vector x = nullptr;
  sunrealtype rtol = 0;
  sunrealtype atol = 0;
  N_Vector atolv = nullptr;
  N_Vector ewt_next = nullptr;
  int spec_m = 0;
  int spec_weights = kWeightsNone;
  sunrealtype spec_c[kMaxDegree + 2] = {};
  N_Vector spec_x = nullptr;
  N_Vector spec_ewt = nullptr;
};

// What AfterFIsFused's choice depends on.
inline int AfterFKey(const AdaptAfterF& w) {
  const int shape =
      ((((w.d * 16 + w.ndiff) * 4 + w.est_kind) * 4 + w.weights) * 2 + (w.full ? 1 : 0)) * 2 +
      (w.positive ? 1 : 0);
  return (shape * 16 + w.spec_m) * 4 + w.spec_weights;
}

inline bool AdaptKernels::AfterFIsFused(AdaptAfterF* w) const {
  const int key = AfterFKey(*w);
  if (key != w->fused_key) ChooseAfterF(w, key);
  return w->fused != nullptr;
}

inline sunrealtype AdaptKernels::AfterF(const AdaptAfterF& w, sunrealtype* dmin,
                                        sunrealtype* l1) const {
  using Fn = sunrealtype (*)(const AdaptAfterF&, sunindextype, sunrealtype*, sunrealtype*);
  *l1 = 0;
  if (w.fused != nullptr) return reinterpret_cast<Fn>(w.fused)(w, n, dmin, l1);
  return AfterFByOperations(w, dmin);
}

// The remap of the history and the position (docs/theory.md 12.1, 12.2): first rD[i] += rc[i]
// rY[i], i < nremap, in order (Axpy's arithmetic), then out = sum_j c[j] X[j], j < m (m >= 3,
// Lin's arithmetic, X possibly among the remapped vectors; c[0] = 1, the weight of x(t_n)).
// With weights other than kWeightsNone (the fields of AdaptAfterF), the weights of the new
// position follow into ewt in the same pass.
struct AdaptPosition {
  int weights = AdaptAfterF::kWeightsNone;
  bool positive = false;
  sunrealtype rtol = 0;
  sunrealtype atol = 0;
  N_Vector atolv = nullptr;
  N_Vector ewt = nullptr;
  int nremap = 0;
  sunrealtype rc[kMaxDegree * kMaxDegree] = {};
  N_Vector rY[kMaxDegree * kMaxDegree] = {};
  N_Vector rD[kMaxDegree * kMaxDegree] = {};
  int m = 0;
  sunrealtype c[kMaxDegree + 2] = {};
  N_Vector X[kMaxDegree + 2] = {};
  N_Vector out = nullptr;
  int fused_key = -1;     // Position's choice of its serial pass for m and the weights,
  void* fused = nullptr;  // kept while they stay
};

}  // namespace ceode

#endif  // CEODE_SRC_CEODE_KERNELS_HPP_
