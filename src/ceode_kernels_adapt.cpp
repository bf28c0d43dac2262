// The adaptive step's vector operations (AdaptKernels, ceode_kernels.hpp): the N_Vector
// reference and the serial loops beside it, operation for operation, so that both give the
// same numbers (the N_Vector forms are those of SUNDIALS' serial vector, special cases
// included).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <utility>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "ceode_kernels.hpp"
#include "ceode_lanes.hpp"

namespace ceode {

void AdaptKernels::Lin(int m, const sunrealtype* c, N_Vector* X, N_Vector out) const {
  if (serial && m == 2 && c[1] == -c[0]) {
    // The divided differences' form, r (x - y): N_VLinearSum's arithmetic for a = -b (with
    // a = +-1 the difference itself, the same values).
    const sunrealtype* x = NV_DATA_S(X[0]);
    const sunrealtype* y = NV_DATA_S(X[1]);
    sunrealtype* z = NV_DATA_S(out);
    for (sunindextype i = 0; i < n; ++i) z[i] = c[0] * (x[i] - y[i]);
    return;
  }
  if (serial) {
    CombineSerial(n, m, c, X, NV_DATA_S(out));
  } else {
    Combine(m, c, X, out);
  }
}

namespace {

// LinMany on few entries: each entry's inputs are read once for all outputs, the sums in
// CombineEntriesOf's order (the same values); there the calls per output are most of the cost.
// With the counts constants the outputs' sums run side by side, L at a time (pairs where SSE2 is,
// ceode_lanes.hpp: the same operations per output), from the rows of c by term.
constexpr sunindextype kLinManyFew = 64;
#if defined(__SSE2__) && defined(SUNDIALS_DOUBLE_PRECISION)
using OutputLanes = Pair;
#else
using OutputLanes = sunrealtype;
#endif
template <int M, int NOUT>
void LinManyEntries(sunindextype n, const sunrealtype (*c)[kMaxDegree], const N_Vector* X,
                    const N_Vector* Out) {
  constexpr int L = sizeof(OutputLanes) / sizeof(sunrealtype);
  constexpr int W = NOUT / L;  // groups of L outputs, the rest one by one
  const OutputLanes tag{};
  // The vectors' data looked up once (serial: every vector is NVECTOR_SERIAL)
  const sunrealtype* x[M];
  for (int j = 0; j < M; ++j) x[j] = NV_DATA_S(X[j]);
  sunrealtype* out[NOUT];
  for (int k = 0; k < NOUT; ++k) out[k] = NV_DATA_S(Out[k]);
  for (sunindextype i = 0; i < n; ++i) {
    OutputLanes s[W + 1];
    sunrealtype sums[NOUT];
    const OutputLanes x0 = Splat(x[0][i], tag);
    for (int w = 0; w < W; ++w) s[w] = Load(c[0] + w * L, tag) * x0;
    for (int k = W * L; k < NOUT; ++k) sums[k] = c[0][k] * x[0][i];
    for (int j = 1; j < M; ++j) {
      const sunrealtype xj = x[j][i];
      const OutputLanes xs = Splat(xj, tag);
      for (int w = 0; w < W; ++w) s[w] += Load(c[j] + w * L, tag) * xs;
      for (int k = W * L; k < NOUT; ++k) sums[k] += c[j][k] * xj;
    }
    for (int w = 0; w < W; ++w) Store(sums + w * L, s[w]);
    for (int k = 0; k < NOUT; ++k) out[k][i] = sums[k];
  }
}

using LinManyFn = void (*)(sunindextype, const sunrealtype (*)[kMaxDegree], const N_Vector*,
                           const N_Vector*);
constexpr int kLinManyOut = kMaxDegree - 2;  // the refresh's rows at most

// LinMany's pass for m terms and nout outputs on n entries (below: it needs the pair loops).
LinManyFn LinManyFor(int m, int nout, sunindextype n);

}  // namespace

void AdaptKernels::LinMany(int nout, int m, const sunrealtype (*c)[kMaxDegree], N_Vector* X,
                           N_Vector* out) const {
  if (serial && m >= 3 && nout >= 1 && nout <= kLinManyOut) {
    LinManyFor(m, nout, n)(n, c, X, out);  // Lin's CombineSerial, output by output
    return;
  }
  for (int k = 0; k < nout; ++k) {
    sunrealtype row[kMaxDegree];  // output k's weights by term (Lin's special case of two terms)
    for (int j = 0; j < m; ++j) row[j] = c[j][k];
    Lin(m, row, X, out[k]);
  }
}

void AdaptKernels::Axpy(sunrealtype c, N_Vector y, N_Vector x) const {
  if (!serial) {
    N_VLinearSum(1, x, c, y, x);
    return;
  }
  sunrealtype* xd = NV_DATA_S(x);
  const sunrealtype* yd = NV_DATA_S(y);
  for (sunindextype i = 0; i < n; ++i) xd[i] += c * yd[i];
}

void AdaptKernels::Scale(sunrealtype c, N_Vector x) const {
  if (!serial) {
    N_VScale(c, x, x);
    return;
  }
  sunrealtype* xd = NV_DATA_S(x);
  for (sunindextype i = 0; i < n; ++i) xd[i] *= c;
}

sunrealtype AdaptKernels::WrmsNorm(N_Vector x, N_Vector w) const {
  if (!serial) return N_VWrmsNorm(x, w);
  const sunrealtype* xd = NV_DATA_S(x);
  const sunrealtype* wd = NV_DATA_S(w);
  sunrealtype sum = 0;
  for (sunindextype i = 0; i < n; ++i) {
    const sunrealtype p = xd[i] * wd[i];
    sum += p * p;
  }
  return std::sqrt(sum / static_cast<sunrealtype>(n));
}

sunrealtype AdaptKernels::L1Norm(N_Vector x) const {
  if (!serial) return N_VL1Norm(x);
  const sunrealtype* xd = NV_DATA_S(x);
  sunrealtype sum = 0;
  for (sunindextype i = 0; i < n; ++i) sum += std::fabs(xd[i]);
  return sum;
}

sunrealtype AdaptKernels::Weights(N_Vector x, sunrealtype rtol, sunrealtype atol, N_Vector atolv,
                                  N_Vector ewt) const {
  if (!serial) {
    N_VAbs(x, ewt);
    if (atolv != nullptr) {
      N_VLinearSum(rtol, ewt, 1, atolv, ewt);
    } else {
      N_VScale(rtol, ewt, ewt);
      N_VAddConst(ewt, atol, ewt);
    }
    const sunrealtype dmin = N_VMin(ewt);
    if (dmin > 0) N_VInv(ewt, ewt);
    return dmin;
  }
  const sunrealtype* xd = NV_DATA_S(x);
  const sunrealtype* ad = atolv != nullptr ? NV_DATA_S(atolv) : nullptr;
  sunrealtype* wd = NV_DATA_S(ewt);
  for (sunindextype i = 0; i < n; ++i)
    wd[i] = rtol * std::fabs(xd[i]) + (ad != nullptr ? ad[i] : atol);
  sunrealtype dmin = wd[0];  // as N_VMin: a NaN first entry stays the minimum
  for (sunindextype i = 1; i < n; ++i) {
    if (wd[i] < dmin) dmin = wd[i];
  }
  if (!(dmin > 0)) return dmin;
  for (sunindextype i = 0; i < n; ++i) wd[i] = 1 / wd[i];
  return dmin;
}

}  // namespace ceode

// ---- The fused passes of the adaptive step -------------------------------------------------

namespace ceode {

namespace {

// s += each entry of v in the order of the entries (the reference's sums are sequential).
inline void AddInOrder(sunrealtype* s, sunrealtype v) { *s += v; }

// The L1 norm's lanes: a vector's (folded into a pair's two after its loop), one entry's one.
inline void AddLanes(sunrealtype* s, sunrealtype v) { *s += v; }
[[maybe_unused]] inline void FoldLanes(sunrealtype* s, sunrealtype v) { *s += v; }
[[maybe_unused]] inline sunrealtype LaneSum(sunrealtype v) { return v; }

#if defined(__SSE2__) && defined(SUNDIALS_DOUBLE_PRECISION)
constexpr bool kPairs = true;
inline void AddInOrder(sunrealtype* s, Pair v) {
  *s += _mm_cvtsd_f64(v);
  *s += _mm_cvtsd_f64(_mm_unpackhi_pd(v, v));
}
inline void AddLanes(Pair* s, Pair v) { *s += v; }
inline void FoldLanes(Pair* s, Pair v) { *s += v; }
inline sunrealtype LaneSum(Pair v) { return v[0] + v[1]; }
#else
constexpr bool kPairs = false;
using Pair = sunrealtype;  // the pair loops are discarded (kPairs), their types still checked
#endif

#if defined(CEODE_AVX)
__attribute__((always_inline)) inline void AddInOrder(sunrealtype* s, const Quad& v) {
  for (int l = 0; l < 4; ++l) *s += v[l];
}
__attribute__((always_inline)) inline void AddLanes(Quad* s, const Quad& v) { *s += v; }
// A loop's four lanes into the pair loop's two, once after the loop.
__attribute__((always_inline)) inline void FoldLanes(Pair* s, const Quad& v) {
  *s += Pair{v[0], v[1]} + Pair{v[2], v[3]};
}
#endif
// The pair loops start at this many entries: below it splatting their coefficients costs more
// than it saves (the L1 sums of n < 4 entries are the same either way).
constexpr sunindextype kPairsFrom = 4;

// LinMany on more entries: V's entries at a time (four in the AVX entry, then pairs), every
// output's sum in a register of its own and each input read once for all outputs; per entry and
// output the sums of CombineEntriesOf in its order (the same values).
template <int M, int NOUT, typename V>
__attribute__((always_inline)) inline sunindextype LinManyVectors(
    sunindextype i, sunindextype n, const sunrealtype (*c)[kMaxDegree], const sunrealtype* const* x,
    sunrealtype* const* out) {
  constexpr sunindextype kWidth = sizeof(V) / sizeof(sunrealtype);
  const V tag{};
  V cw[M][NOUT];
  for (int j = 0; j < M; ++j) {
    for (int k = 0; k < NOUT; ++k) cw[j][k] = Splat(c[j][k], tag);
  }
  for (; i + kWidth <= n; i += kWidth) {
    V s[NOUT];
    const V x0 = Load(x[0] + i, tag);
    for (int k = 0; k < NOUT; ++k) s[k] = cw[0][k] * x0;
    for (int j = 1; j < M; ++j) {
      const V xj = Load(x[j] + i, tag);
      for (int k = 0; k < NOUT; ++k) s[k] += cw[j][k] * xj;
    }
    for (int k = 0; k < NOUT; ++k) Store(out[k] + i, s[k]);
  }
  return i;
}

template <int M, int NOUT, typename W>
__attribute__((always_inline)) inline void LinManyPass(sunindextype n,
                                                       const sunrealtype (*c)[kMaxDegree],
                                                       const N_Vector* X, const N_Vector* Out) {
  const sunrealtype* x[M];
  for (int j = 0; j < M; ++j) x[j] = NV_DATA_S(X[j]);
  sunrealtype* out[NOUT];
  for (int k = 0; k < NOUT; ++k) out[k] = NV_DATA_S(Out[k]);
  sunindextype i = 0;
  if constexpr (kPairs) {
    if constexpr (sizeof(W) > sizeof(Pair)) i = LinManyVectors<M, NOUT, W>(i, n, c, x, out);
    i = LinManyVectors<M, NOUT, Pair>(i, n, c, x, out);
  }
  for (; i < n; ++i) {
    for (int k = 0; k < NOUT; ++k) {
      sunrealtype s = c[0][k] * x[0][i];
      for (int j = 1; j < M; ++j) s += c[j][k] * x[j][i];
      out[k][i] = s;
    }
  }
}

template <int M, int NOUT>
void LinManyWide(sunindextype n, const sunrealtype (*c)[kMaxDegree], const N_Vector* X,
                 const N_Vector* Out) {
  LinManyPass<M, NOUT, Pair>(n, c, X, Out);
}
#if defined(CEODE_AVX)
template <int M, int NOUT>
__attribute__((target("avx"))) void LinManyWideAvx(sunindextype n,
                                                   const sunrealtype (*c)[kMaxDegree],
                                                   const N_Vector* X, const N_Vector* Out) {
  LinManyPass<M, NOUT, Quad>(n, c, X, Out);
}
#endif

// LinMany's passes: on few entries (kFew), on more (kWide) and their AVX entry (kAvx).
enum class LinKind { kFew, kWide, kAvx };
template <LinKind K, int M, int NOUT>
constexpr LinManyFn LinManyOf() {
#if defined(CEODE_AVX)
  if constexpr (K == LinKind::kAvx) return &LinManyWideAvx<M, NOUT>;
#endif
  if constexpr (K == LinKind::kWide) return &LinManyWide<M, NOUT>;
  return &LinManyEntries<M, NOUT>;
}
template <LinKind K, int M, std::size_t... N>
constexpr std::array<LinManyFn, sizeof...(N)> LinManyRow(std::index_sequence<N...> /*nout*/) {
  return {LinManyOf<K, M, static_cast<int>(N) + 1>()...};
}
template <LinKind K, std::size_t... I>
constexpr std::array<std::array<LinManyFn, kLinManyOut>, sizeof...(I)> LinManyTable(
    std::index_sequence<I...> /*m*/) {
  return {LinManyRow<K, static_cast<int>(I) + 3>(std::make_index_sequence<kLinManyOut>{})...};
}
// By the term count m = 3 .. kMaxDegree and the output count nout = 1 .. kLinManyOut.
template <LinKind K>
constexpr auto kLinManyFns = LinManyTable<K>(std::make_index_sequence<kMaxDegree - 2>{});

// In the best encoding the processor runs.
LinManyFn LinManyFor(int m, int nout, sunindextype n) {
  if (n <= kLinManyFew) return kLinManyFns<LinKind::kFew>[m - 3][nout - 1];
#if defined(CEODE_AVX)
  if (__builtin_cpu_supports("avx")) return kLinManyFns<LinKind::kAvx>[m - 3][nout - 1];
#endif
  return kLinManyFns<LinKind::kWide>[m - 3][nout - 1];
}

// The slots of the histories and the differences in AfterFArrays: copied into the object
// (Small false: the entry loop keeps them in registers or on the stack; read through the tables,
// they would be loaded again for every entry), or the tables themselves (Small: on fewer entries
// than a pair loop takes the copies are most of the pass's set-up).
template <typename T, int M, bool Small>
struct Slots {
  using type = T[M];
};
template <typename T, int M>
struct Slots<T, M, true> {
  using type = T const*;
};

// The raw arrays of an AdaptAfterF of degree D with ND differences (the last one the estimate).
template <int D, int ND, bool Small>
struct AfterFArrays {
  sunrealtype* xs;  // the next position (spec_x) and its weights
  sunrealtype* ewts;
  typename Slots<const sunrealtype*, D, Small>::type Do;  // the node's history, 1 .. D - 1
  typename Slots<sunrealtype*, D, Small>::type Dn;        // the new node's (Dn[2] = a)
  typename Slots<const sunrealtype*, ND + 1, Small>::type ddo;
  typename Slots<sunrealtype*, ND + 1, Small>::type ddn;  // copied: ddn[ND] is the estimate
  const sunrealtype* ewt;
  sunrealtype* yd;
  const sunrealtype* x;
  const sunrealtype* atolv;
  sunrealtype* ewt_next;
  sunrealtype* est;  // the estimate (Small)
  explicit AfterFArrays(const AdaptAfterF& w) {
    if constexpr (Small) {
      Do = w.hist_data[0];
      Dn = w.hist_data[1];
      ddo = w.dd_data[w.dd_cur];
      ddn = w.dd_data[1 - w.dd_cur];
      est = NV_DATA_S(w.est);
    } else {
      for (int k = 1; k < D; ++k) {
        Do[k] = NV_DATA_S(w.D[k]);
        Dn[k] = NV_DATA_S(w.Dn[k]);
      }
      for (int j = 1; j < ND; ++j) {
        ddo[j] = w.dd_data[w.dd_cur][j];
        ddn[j] = w.dd_data[1 - w.dd_cur][j];
      }
      ddn[ND] = NV_DATA_S(w.est);
    }
    ewt = NV_DATA_S(w.ewt);
    yd = NV_DATA_S(w.yd);
    x = NV_DATA_S(w.x);
    atolv = w.atolv != nullptr ? NV_DATA_S(w.atolv) : nullptr;
    ewt_next = w.weights != AdaptAfterF::kWeightsNone ? NV_DATA_S(w.ewt_next) : nullptr;
    xs = w.spec_m > 0 ? NV_DATA_S(w.spec_x) : nullptr;
    ewts = w.spec_m > 0 ? NV_DATA_S(w.spec_ewt) : nullptr;
  }
  sunrealtype* Estimate() const {
    if constexpr (Small) {
      return est;
    } else {
      return ddn[ND];
    }
  }
};

// The coefficients of an AdaptAfterF as values of type V (splatted once for the pair loop).
template <int D, int ND, typename V>
struct AfterFCoeffs {
  V c[D][D + 1];  // sum s (the plan's order), term j
  V r[ND];
  V pc[D + 1];  // spec_c
  V scale, yc, rtol, atol;
  __attribute__((always_inline)) AfterFCoeffs(const AdaptAfterF& w, const V& tag) {
    const int nsum = D > 3 ? D - 2 : 1;
    for (int s = 0; s < nsum; ++s) {
      // sum 0 has D - 1 terms (z, or D_1 when D = 3), the sum of D_k has D - k
      const int m = s == 0 ? D - 1 : (s == 1 ? D - 1 : D - s - 1);
      for (int j = 0; j < m; ++j) c[s][j] = Splat(w.cw[s][j], tag);
    }
    for (int j = 0; j < ND; ++j) r[j] = Splat(w.r[j], tag);
    for (int j = 0; j < w.spec_m && j <= D; ++j) pc[j] = Splat(w.spec_c[j], tag);
    scale = Splat(w.scale, tag);
    yc = Splat(w.yc, tag);
    rtol = Splat(w.rtol, tag);
    atol = Splat(w.atol, tag);
  }
};

// 7. of AdaptAfterF: the next position of SM terms from x and the new history nw (its values
// as written) and the rate yd, PositionEntry's arithmetic; its weights (SWK) follow.
template <int D, int ND, bool S, int SM, int SWK, typename V, typename C, typename L>
__attribute__((always_inline)) inline void NextPositionEntry(const AfterFArrays<D, ND, S>& p,
                                                             const C& co, sunindextype i,
                                                             const V* nw, const V& yd, L* l1) {
  const V tag{};
  V acc = Load(p.x + i, tag);
  for (int j = 1; j < (SM < D ? SM : D); ++j) acc += co.pc(j) * nw[j];
  if constexpr (SM > D) acc += co.pc(D) * yd;
  Store(p.xs + i, acc);
  const V ax = Abs(acc);
  AddLanes(l1, ax);
  const V at = SWK == AdaptAfterF::kWeightsVector ? Load(p.atolv + i, tag) : co.atol();
  Store(p.ewts + i, Splat(1, tag) / (co.rtol() * ax + at));
}

// One entry (or pair) i of AdaptAfterF for the full shape of degree D (no zero weight dropped
// from the plan's sums) with ND differences; C yields the coefficients (V values). SM > 0: the
// next position of SM terms (7.), its L1 norm summed into *l1.
template <int D, int ND, bool S, int WK, int SM, int SWK, typename V, typename C, typename L>
__attribute__((always_inline)) inline void AfterFEntry(const AfterFArrays<D, ND, S>& p, const C& co,
                                                       sunindextype i, sunrealtype* ssq, L* l1) {
  const V tag{};
  const V a = Load(p.Dn[2] + i, tag);
  V old[D];
  for (int k = 1; k < D; ++k) old[k] = Load(p.Do[k] + i, tag);
  V nw[D];  // the new history as written (7. reads it)
  nw[2] = a;
  // 1. z (D > 3), then D_1, D_3 .. D_{D-2}: BuildUpdatePlan's terms in its order, the
  // accumulated value last (its weight 1 exactly: added, not multiplied).
  V z = a;
  int s = 0;
  if constexpr (D > 3) {
    z = co.c(0, 0) * a;
    for (int j = 2; j < D; ++j) z += co.c(0, j - 1) * old[j];
    Store(p.Dn[D - 1] + i, z);
    nw[D - 1] = z;
    s = 1;
  }
  for (int k = 1; k <= D - 2; ++k) {
    if (k == 2) continue;
    V acc = co.c(s, 0) * old[k + 1];
    for (int j = k + 2; j < D; ++j) acc += co.c(s, j - k - 1) * old[j];
    acc += co.c(s, D - k - 1) * z;
    acc += old[k];
    Store(p.Dn[k] + i, acc);
    nw[k] = acc;
    ++s;
  }
  // 2., 3. the differences, the last one scaled into the estimate
  V prev_new = a;
  V prev_old = old[2];
  for (int j = 1; j <= ND; ++j) {
    V e = co.r(j - 1) * (prev_new - prev_old);
    if (j == ND) {
      e = co.scale() * e;
      Store(p.Estimate() + i, e);
      // 4. the weighted square
      const V q = e * Load(p.ewt + i, tag);
      AddInOrder(ssq, q * q);
    } else {
      Store(p.ddn[j] + i, e);
      prev_old = Load(p.ddo[j] + i, tag);
      prev_new = e;
    }
  }
  // 5. the top derivative's rate
  const V yd = co.yc() * (z - old[D - 1]);
  Store(p.yd + i, yd);
  // 6. the new weights
  if constexpr (WK != AdaptAfterF::kWeightsNone) {
    const V at = WK == AdaptAfterF::kWeightsVector ? Load(p.atolv + i, tag) : co.atol();
    const V den = co.rtol() * Abs(Load(p.x + i, tag)) + at;
    Store(p.ewt_next + i, Splat(1, tag) / den);
  }
  if constexpr (SM > 0) NextPositionEntry<D, ND, S, SM, SWK, V>(p, co, i, nw, yd, l1);
}

// Coefficient access for the entry: splatted values (pairs) or the plan's own (the tail, n = 1).
template <int D, int ND, typename V>
struct SplatCo {
  const AfterFCoeffs<D, ND, V>& k;
  const V& c(int s, int j) const { return k.c[s][j]; }
  const V& r(int j) const { return k.r[j]; }
  const V& pc(int j) const { return k.pc[j]; }
  const V& scale() const { return k.scale; }
  const V& yc() const { return k.yc; }
  const V& rtol() const { return k.rtol; }
  const V& atol() const { return k.atol; }
};
struct PlanCo {
  const AdaptAfterF& w;
  sunrealtype c(int s, int j) const { return w.cw[s][j]; }
  sunrealtype r(int j) const { return w.r[j]; }
  sunrealtype pc(int j) const { return w.spec_c[j]; }
  sunrealtype scale() const { return w.scale; }
  sunrealtype yc() const { return w.yc; }
  sunrealtype rtol() const { return w.rtol; }
  sunrealtype atol() const { return w.atol; }
};

// Entries i, i + 1, ... of AdaptAfterF in vectors of type V while whole ones fit in n; returns
// the first entry left.
template <int D, int ND, int WK, int SM, int SWK, typename V>
__attribute__((always_inline)) inline sunindextype AfterFVectors(
    const AfterFArrays<D, ND, false>& p, const AdaptAfterF& w, sunindextype i, sunindextype n,
    sunrealtype* ssq, Pair* l1p) {
  constexpr sunindextype kWidth = sizeof(V) / sizeof(sunrealtype);
  const AfterFCoeffs<D, ND, V> k(w, V{});
  const SplatCo<D, ND, V> co{k};
  V l1 = Splat(0, V{});
#pragma GCC unroll 2
  for (; i + kWidth <= n; i += kWidth)
    AfterFEntry<D, ND, false, WK, SM, SWK, V>(p, co, i, ssq, &l1);
  FoldLanes(l1p, l1);
  return i;
}

// The weights' denominators are positive (FusedAfterF): no smallest one to find. The next
// position's L1 norm (SM > 0) is summed as PositionLoop sums it. S: fewer entries than the pair
// loop takes (AfterFArrays' tables, no pair loop). W: the widest vector, Pair or (in the AVX
// entry) Quad, whose loop the pair loop follows. Inlined into each instruction set's entry.
template <int D, int ND, int WK, int SM, int SWK, bool S, typename W = Pair>
__attribute__((always_inline)) inline sunrealtype AfterFPass(const AdaptAfterF& w, sunindextype n,
                                                             sunrealtype* dmin, sunrealtype* l1) {
  const AfterFArrays<D, ND, S> p(w);
  sunrealtype ssq = 0;
  sunrealtype sum = 0;
  sunindextype i = 0;
  if constexpr (kPairs && !S) {
    if (n >= kPairsFrom) {
      Pair l1p = Splat(0, Pair{});
      if constexpr (sizeof(W) > sizeof(Pair)) {
        i = AfterFVectors<D, ND, WK, SM, SWK, W>(p, w, i, n, &ssq, &l1p);
      }
      i = AfterFVectors<D, ND, WK, SM, SWK, Pair>(p, w, i, n, &ssq, &l1p);
      sum = LaneSum(l1p);
    }
  }
  const PlanCo co{w};
  for (; i < n; ++i) AfterFEntry<D, ND, S, WK, SM, SWK, sunrealtype>(p, co, i, &ssq, &sum);
  *dmin = 1;
  *l1 = sum;
  return std::sqrt(ssq / static_cast<sunrealtype>(n));
}

template <int D, int ND, int WK, int SM, int SWK, bool S = false>
sunrealtype AfterFFused(const AdaptAfterF& w, sunindextype n, sunrealtype* dmin, sunrealtype* l1) {
  return AfterFPass<D, ND, WK, SM, SWK, S>(w, n, dmin, l1);
}

using AfterFFn = sunrealtype (*)(const AdaptAfterF&, sunindextype, sunrealtype*, sunrealtype*);

#if defined(CEODE_AVX)
// The same operations on four entries at a time, in AVX's three-operand encoding (SSE2's
// two-operand form copies every factor that is read again first: some 16 copies per entry at
// degree 8), then on a pair and on single entries as the pair loop does: the same values.
template <int D, int ND, int WK, int SM, int SWK>
__attribute__((target("avx"))) sunrealtype AfterFFusedAvx(const AdaptAfterF& w, sunindextype n,
                                                          sunrealtype* dmin, sunrealtype* l1) {
  return AfterFPass<D, ND, WK, SM, SWK, false, Quad>(w, n, dmin, l1);
}
#endif

// The pair loop's pass in the best encoding the processor runs.
template <int D, int ND, int WK, int SM, int SWK>
AfterFFn AfterFPairs() {
#if defined(CEODE_AVX)
  if (__builtin_cpu_supports("avx")) return &AfterFFusedAvx<D, ND, WK, SM, SWK>;
#endif
  return &AfterFFused<D, ND, WK, SM, SWK>;
}

// With the next position: SM terms, its weights of kind SWK; small: fewer entries than the pair
// loop takes.
template <int D, int ND, int SM>
AfterFFn AfterFNextOf(int spec_weights, bool small) {
  constexpr int kNone = AdaptAfterF::kWeightsNone;
  constexpr int kVector = AdaptAfterF::kWeightsVector;
  constexpr int kScalar = AdaptAfterF::kWeightsScalar;
  if (spec_weights == kVector) {
    return small ? &AfterFFused<D, ND, kNone, SM, kVector, true>
                 : AfterFPairs<D, ND, kNone, SM, kVector>();
  }
  return small ? &AfterFFused<D, ND, kNone, SM, kScalar, true>
               : AfterFPairs<D, ND, kNone, SM, kScalar>();
}

// The named sets' shapes: (degree, differences = order - 1).
template <int D, int ND>
AfterFFn AfterFOf(const AdaptAfterF& w, bool small) {
  constexpr int kNone = AdaptAfterF::kWeightsNone;
  if (w.spec_m > 0) {  // the next position's sum has d or d + 1 terms (AdaptPosition)
    if (w.weights != kNone || w.spec_weights == kNone || !w.positive) return nullptr;
    if (w.spec_m == D) return AfterFNextOf<D, ND, D>(w.spec_weights, small);
    return w.spec_m == D + 1 ? AfterFNextOf<D, ND, D + 1>(w.spec_weights, small) : nullptr;
  }
  switch (w.weights) {
    case AdaptAfterF::kWeightsScalar:
      return AfterFPairs<D, ND, AdaptAfterF::kWeightsScalar, 0, kNone>();
    case AdaptAfterF::kWeightsVector:
      return AfterFPairs<D, ND, AdaptAfterF::kWeightsVector, 0, kNone>();
    default:
      return AfterFPairs<D, ND, kNone, 0, kNone>();
  }
}

AfterFFn FusedAfterF(const AdaptAfterF& w, bool small) {
  if (!w.full || w.est_kind != AdaptAfterF::kEstLast) return nullptr;
  if (w.weights != AdaptAfterF::kWeightsNone && !w.positive) return nullptr;
  const int d = w.d;
  const int key = 10 * d + w.ndiff;
  switch (key) {
    case 31:
      return AfterFOf<3, 1>(w, small);
    case 42:
      return AfterFOf<4, 2>(w, small);
    case 53:
      return AfterFOf<5, 3>(w, small);
    case 64:
      return AfterFOf<6, 4>(w, small);
    case 76:
      return AfterFOf<7, 6>(w, small);
    case 87:
      return AfterFOf<8, 7>(w, small);
    default:
      return nullptr;
  }
}

}  // namespace

void AdaptKernels::ChooseAfterF(AdaptAfterF* w, int key) const {
  w->fused_key = key;
  w->fused = serial ? reinterpret_cast<void*>(FusedAfterF(*w, n < kPairsFrom)) : nullptr;
}

sunrealtype AdaptKernels::AfterFByOperations(const AdaptAfterF& w, sunrealtype* dmin) const {
  RunPlan(*w.kp, n);
  for (int j = 0; j < w.ndiff; ++j) {
    const sunrealtype c[2] = {w.r[j], -w.r[j]};
    N_Vector X[2] = {w.dnew[j], w.dold[j]};
    Lin(2, c, X, w.dout[j]);
  }
  sunrealtype norm = 0;
  if (w.est_kind == AdaptAfterF::kEstNone) {
    N_VConst(0, w.est);
  } else {
    if (w.est_kind == AdaptAfterF::kEstCopy) CopyVector(w.est_src, w.est);
    Scale(w.scale, w.est);
    norm = WrmsNorm(w.est, w.ewt);
  }
  const sunrealtype c[2] = {w.yc, -w.yc};
  N_Vector X[2] = {w.Dn[w.d - 1], w.D[w.d - 1]};
  Lin(2, c, X, w.yd);
  *dmin = 1;
  if (w.weights != AdaptAfterF::kWeightsNone) {
    *dmin = Weights(w.x, w.rtol, w.atol,
                    w.weights == AdaptAfterF::kWeightsVector ? w.atolv : nullptr, w.ewt_next);
  }
  return norm;
}

namespace {

// The raw arrays of an AdaptPosition.
struct PositionArrays {
  int nr = 0;
  sunrealtype* rD[kMaxDegree * kMaxDegree];
  const sunrealtype* rY[kMaxDegree * kMaxDegree];
  const sunrealtype* X[kMaxDegree + 2];
  sunrealtype* out;
  const sunrealtype* atolv;
  sunrealtype* ewt;
};

// Entry (or pair) i of the position of M terms, with the remap before it (R) and the new
// weights after it (WK, as AfterFEntry's): x(t_n)'s weight c[0] is 1, so its term is the value
// itself (1 x exactly). Returns |x(t_n + h)|.
template <int M, bool R, int WK, typename V>
__attribute__((always_inline)) inline V PositionEntry(const PositionArrays& p, const V* c,
                                                      const V* rc, V rtol, V atol, sunindextype i) {
  const V tag{};
  if constexpr (R) {
    for (int r = 0; r < p.nr; ++r) {
      Store(p.rD[r] + i, Load(p.rD[r] + i, tag) + rc[r] * Load(p.rY[r] + i, tag));
    }
  }
  V acc = Load(p.X[0] + i, tag);
  for (int j = 1; j < M; ++j) acc += c[j] * Load(p.X[j] + i, tag);
  Store(p.out + i, acc);
  const V ax = Abs(acc);
  if constexpr (WK != AdaptAfterF::kWeightsNone) {
    const V at = WK == AdaptAfterF::kWeightsVector ? Load(p.atolv + i, tag) : atol;
    Store(p.ewt + i, Splat(1, tag) / (rtol * ax + at));
  }
  return ax;
}

// Entries i, i + 1, ... of the position in vectors of type V while whole ones fit in n, their
// magnitudes summed in V's lanes and folded into the pair loop's; returns the first entry left.
template <int M, bool R, int WK, typename V>
__attribute__((always_inline)) inline sunindextype PositionVectors(const AdaptPosition& w,
                                                                   const PositionArrays& p,
                                                                   sunindextype i, sunindextype n,
                                                                   Pair* l1p) {
  constexpr sunindextype kWidth = sizeof(V) / sizeof(sunrealtype);
  V c[M];
  V rc[kMaxDegree * kMaxDegree];
  for (int j = 0; j < M; ++j) c[j] = Splat(w.c[j], V{});
  for (int r = 0; r < p.nr; ++r) rc[r] = Splat(w.rc[r], V{});
  const V rtol = Splat(w.rtol, V{});
  const V atol = Splat(w.atol, V{});
  V l1 = Splat(0, V{});
#pragma GCC unroll 2
  for (; i + kWidth <= n; i += kWidth) l1 += PositionEntry<M, R, WK>(p, c, rc, rtol, atol, i);
  FoldLanes(l1p, l1);
  return i;
}

// The L1 norm only feeds the growth check: each loop sums in its vector's lanes (its rounding, not
// N_VL1Norm's order, does not reach the state). W: the widest vector, Pair or (in the AVX entry)
// Quad, whose loop the pair loop follows.
template <int M, bool R, int WK, typename W>
__attribute__((always_inline)) inline sunrealtype PositionLoop(const AdaptPosition& w,
                                                               const PositionArrays& p,
                                                               sunindextype n) {
  sunrealtype l1 = 0;
  sunindextype i = 0;
  if constexpr (kPairs) {
    if (n >= kPairsFrom) {
      Pair l1p = Splat(0, Pair{});
      if constexpr (sizeof(W) > sizeof(Pair)) i = PositionVectors<M, R, WK, W>(w, p, i, n, &l1p);
      i = PositionVectors<M, R, WK, Pair>(w, p, i, n, &l1p);
      l1 = LaneSum(l1p);
    }
  }
  for (; i < n; ++i) l1 += PositionEntry<M, R, WK>(p, w.c, w.rc, w.rtol, w.atol, i);
  return l1;
}

template <int M, int WK, typename W>
__attribute__((always_inline)) inline sunrealtype PositionPass(const AdaptPosition& w,
                                                               sunindextype n) {
  PositionArrays p;
  p.nr = w.nremap;
  for (int r = 0; r < p.nr; ++r) {
    p.rD[r] = NV_DATA_S(w.rD[r]);
    p.rY[r] = NV_DATA_S(w.rY[r]);
  }
  for (int j = 0; j < M; ++j) p.X[j] = NV_DATA_S(w.X[j]);
  p.out = NV_DATA_S(w.out);
  p.atolv = WK == AdaptAfterF::kWeightsVector ? NV_DATA_S(w.atolv) : nullptr;
  p.ewt = WK != AdaptAfterF::kWeightsNone ? NV_DATA_S(w.ewt) : nullptr;
  return p.nr > 0 ? PositionLoop<M, true, WK, W>(w, p, n) : PositionLoop<M, false, WK, W>(w, p, n);
}

template <int M, int WK>
sunrealtype PositionFused(const AdaptPosition& w, sunindextype n) {
  return PositionPass<M, WK, Pair>(w, n);
}

#if defined(CEODE_AVX)
// Four entries at a time in AVX's three-operand encoding, then pairs and single entries as the
// pair loop takes them: the same values, the L1 norm in their lanes.
template <int M, int WK>
__attribute__((target("avx"))) sunrealtype PositionFusedAvx(const AdaptPosition& w,
                                                            sunindextype n) {
  return PositionPass<M, WK, Quad>(w, n);
}
#endif

using PositionFn = sunrealtype (*)(const AdaptPosition&, sunindextype);

template <bool Avx, int WK, int M>
constexpr PositionFn PositionOf() {
#if defined(CEODE_AVX)
  if constexpr (Avx) return &PositionFusedAvx<M, WK>;
#endif
  return &PositionFused<M, WK>;
}
template <bool Avx, int WK, std::size_t... I>
constexpr std::array<PositionFn, sizeof...(I)> PositionRow(std::index_sequence<I...> /*m*/) {
  return {PositionOf<Avx, WK, static_cast<int>(I) + 3>()...};
}
// By the weights' kind and the term count m = 3 .. kMaxDegree + 2; Avx: the AVX entries.
template <bool Avx>
constexpr std::array<PositionFn, kMaxDegree> kPositionFns[3] = {
    PositionRow<Avx, AdaptAfterF::kWeightsScalar>(std::make_index_sequence<kMaxDegree>{}),
    PositionRow<Avx, AdaptAfterF::kWeightsVector>(std::make_index_sequence<kMaxDegree>{}),
    PositionRow<Avx, AdaptAfterF::kWeightsNone>(std::make_index_sequence<kMaxDegree>{})};

// The pass for the weights' kind and m terms in the best encoding the processor runs; below the
// pair loop's size the AVX entry would only add its set-up.
PositionFn PositionPassFor(int weights, int m, sunindextype n) {
#if defined(CEODE_AVX)
  if (n >= kPairsFrom && __builtin_cpu_supports("avx")) return kPositionFns<true>[weights][m - 3];
#endif
  return kPositionFns<false>[weights][m - 3];
}

}  // namespace

sunrealtype AdaptKernels::Position(AdaptPosition* pw, sunrealtype* dmin) const {
  const AdaptPosition& w = *pw;
  *dmin = 1;
  const bool weights = w.weights != AdaptAfterF::kWeightsNone;
  const int key = (w.m * 4 + w.weights) * 2 + (w.positive ? 1 : 0);
  if (key != w.fused_key) {
    pw->fused_key = key;
    const bool fusable = serial && w.m >= 3 && w.m < kMaxDegree + 3 && (!weights || w.positive);
    pw->fused = fusable ? reinterpret_cast<void*>(PositionPassFor(w.weights, w.m, n)) : nullptr;
  }
  // x(t_n)'s weight is 1 (AdaptPosition)
  if (w.fused != nullptr && w.c[0] == 1) return reinterpret_cast<PositionFn>(w.fused)(w, n);
  for (int r = 0; r < w.nremap; ++r) Axpy(w.rc[r], w.rY[r], w.rD[r]);
  Lin(w.m, w.c, const_cast<N_Vector*>(w.X), w.out);
  const sunrealtype l1 = L1Norm(w.out);
  if (weights) {
    *dmin = Weights(w.out, w.rtol, w.atol,
                    w.weights == AdaptAfterF::kWeightsVector ? w.atolv : nullptr, w.ewt);
  }
  return l1;
}

}  // namespace ceode
