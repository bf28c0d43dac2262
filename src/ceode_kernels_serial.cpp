// The serial backend of the kernels (ceode_kernels.hpp) on raw arrays: the step's whole update
// in one sweep through memory with the growth check's norm folded in (for the named sets' shapes
// two entries at a time through every sum, otherwise block by block), the raw combinations and
// the output copy. Each performs the reference's floating-point operations in the same order,
// so the state it produces is bit for bit the same.
#include <nvector/nvector_serial.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <utility>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "ceode_kernels.hpp"
#include "ceode_lanes.hpp"

namespace ceode {

namespace {

// The arithmetic of one sum, decided when the plan is built so that the step only dispatches:
// FusedTerms::form is kZero, a term count 1 .. kMaxTerms (sum term by term in order, as
// N_VLinearCombination and N_VScale), or one of N_VLinearSum's shortcuts (a = +-b is computed
// as a * (x +- y) unless a or b is +-1).
constexpr int kMaxTerms = kMaxDegree + 3;
constexpr int kZero = 0;
constexpr int kSum = kMaxTerms + 1;
constexpr int kDifference = kMaxTerms + 2;
constexpr int kNumForms = kMaxTerms + 3;

// The number of vectors a form reads (kZero: none, one slot kept for the arrays' sake).
constexpr int TermsOf(int form) {
  if (form == kSum || form == kDifference) return 2;
  if (form == kZero) return 1;
  return form;
}

int FormOf(int m, const sunrealtype* c) {
  if (m == 2) {
    const bool unit = c[0] == 1 || c[1] == 1 || c[0] == -1 || c[1] == -1;
    if (!unit && c[0] == c[1]) return kSum;
    if (!unit && c[0] == -c[1]) return kDifference;
  }
  return m;
}

// One entry of a sum with M terms; M is a constant, so the loop unrolls.
template <int M>
inline sunrealtype TermsAt(const FusedTerms& tk, sunindextype i) {
  sunrealtype acc = tk.c[0] * tk.X[0][i];
  for (int j = 1; j < M; ++j) acc += tk.c[j] * tk.X[j][i];
  return acc;
}

template <int F>
sunrealtype SumAt(const FusedTerms& tk, sunindextype i) {
  if constexpr (F == kZero) {
    return 0;
  } else if constexpr (F == kSum) {
    return tk.c[0] * (tk.X[0][i] + tk.X[1][i]);
  } else if constexpr (F == kDifference) {
    return tk.c[0] * (tk.X[0][i] - tk.X[1][i]);
  } else {
    return TermsAt<F>(tk, i);
  }
}

// out[0 .. len) = the sum on entries off .. off + len. An output is never an input of its own
// sum (BuildFusedPlan checks), hence restrict: the loop vectorises without alias checks.
template <int F>
void SumBlock(const FusedTerms& tk, sunindextype off, sunindextype len,
              sunrealtype* __restrict out) {
  if constexpr (F == kZero) {
    std::fill(out, out + len, SUN_RCONST(0.0));
  } else {
    constexpr int kM = TermsOf(F);
    const sunrealtype* x[kM];
    sunrealtype c[kM];
    for (int j = 0; j < kM; ++j) {
      x[j] = tk.X[j] + off;
      c[j] = tk.c[j];
    }
    for (sunindextype i = 0; i < len; ++i) {
      sunrealtype acc;
      if constexpr (F == kSum) {
        acc = c[0] * (x[0][i] + x[1][i]);
      } else if constexpr (F == kDifference) {
        acc = c[0] * (x[0][i] - x[1][i]);
      } else {
        acc = c[0] * x[0][i];
        for (int j = 1; j < kM; ++j) acc += c[j] * x[j][i];
      }
      out[i] = acc;
    }
  }
}

using BlockFn = void (*)(const FusedTerms&, sunindextype, sunindextype, sunrealtype* __restrict);

template <std::size_t... F>
constexpr std::array<BlockFn, kNumForms> BlockTable(std::index_sequence<F...> /*forms*/) {
  return {&SumBlock<static_cast<int>(F)>...};
}
constexpr std::array<BlockFn, kNumForms> kBlock = BlockTable(std::make_index_sequence<kNumForms>{});

// A switch, not a table of function pointers: the small kernel's sums inline into it.
inline sunrealtype SumAtForm(const FusedTerms& tk, sunindextype i) {
  switch (tk.form) {
    case 1:
      return SumAt<1>(tk, i);
    case 2:
      return SumAt<2>(tk, i);
    case 3:
      return SumAt<3>(tk, i);
    case 4:
      return SumAt<4>(tk, i);
    case 5:
      return SumAt<5>(tk, i);
    case 6:
      return SumAt<6>(tk, i);
    case 7:
      return SumAt<7>(tk, i);
    case 8:
      return SumAt<8>(tk, i);
    case 9:
      return SumAt<9>(tk, i);
    case 10:
      return SumAt<10>(tk, i);
    case 11:
      return SumAt<11>(tk, i);
    case kSum:
      return SumAt<kSum>(tk, i);
    case kDifference:
      return SumAt<kDifference>(tk, i);
    case kZero:
      return 0;
    default:
      __builtin_unreachable();  // FormOf returns only the forms above: no range check per sum
  }
}
static_assert(kMaxTerms == 11, "SumAtForm lists every term count");

// Entry i of one sum, y its compensated increment (increment - comp): a plain value, or added to
// the old one with the new compensation.
inline void StoreSum(const FusedTerms& tk, sunindextype i, sunrealtype y) {
  if (tk.old == nullptr) {
    tk.out[i] = y;
  } else {
    const sunrealtype nw = tk.old[i] + y;
    tk.out[i] = nw;
    tk.compnew[i] = (nw - tk.old[i]) - y;
  }
}

// The rounding error of the product p = a b, exactly: one fused multiply-add where the target
// has it (and the compiler may contract, so Dekker's form would not be safe), otherwise
// Dekker's product of the two halves of a and b (no FMA instruction to contract into). Both
// give the exact error, so the results do not depend on the target.
inline sunrealtype ProductError(sunrealtype a, sunrealtype b, sunrealtype p) {
#if defined(__FMA__) || defined(FP_FAST_FMA) || !defined(SUNDIALS_DOUBLE_PRECISION)
  return std::fma(a, b, -p);
#else
  constexpr sunrealtype kSplit = 134217729.0;  // 2^27 + 1
  const sunrealtype ta = kSplit * a, ah = ta - (ta - a), al = a - ah;
  const sunrealtype tb = kSplit * b, bh = tb - (tb - b), bl = b - bh;
  return ((ah * bh - p) + ah * bl + al * bh) + al * bl;
#endif
}

// Entry i of an accumulated sum with compensation (docs/theory.md section 10): the increment
// sum_j c_j x_j (the carried compensation one of its terms, coefficient -1) is formed
// error-free, as s + e with s the rounded sum and e its rounding error (Ogita, Rump and Oishi's
// Dot2: each product's error exactly, each addition's by TwoSum), and e joins the new
// compensation beside the rounding of old + s. A rounded increment would lose about one unit
// of its last place every step, which on long runs is the round-off that remains (theory.md).
inline void StoreCompensatedExact(const FusedTerms& tk, sunindextype i) {
  sunrealtype s = tk.c[0] * tk.X[0][i];
  sunrealtype e = ProductError(tk.c[0], tk.X[0][i], s);
  for (int j = 1; j < tk.m; ++j) {
    const sunrealtype p = tk.c[j] * tk.X[j][i];
    const sunrealtype t = s + p;
    const sunrealtype bb = t - s;
    e += ProductError(tk.c[j], tk.X[j][i], p) + ((s - (t - bb)) + (p - bb));
    s = t;
  }
  const sunrealtype o = tk.old[i];
  const sunrealtype nw = o + s;
  tk.out[i] = nw;
  tk.compnew[i] = ((nw - o) - s) - e;
}

// Small systems: entry by entry, every sum of the plan on it, no loop set-up per sum.
inline sunrealtype UpdateSmall(const FusedPlan& fp, sunindextype n) {
  const sunrealtype* xout = fp.terms[fp.n - 1].out;  // the position comes last
  sunrealtype sum = 0;
  for (sunindextype i = 0; i < n; ++i) {
    for (int k = 0; k < fp.n; ++k) {
      const FusedTerms& tk = fp.terms[k];
      StoreSum(tk, i, SumAtForm(tk, i));
    }
    sum += std::fabs(xout[i]);
  }
  return sum;
}

// The term counts of the step's sums for degree d (BuildUpdatePlan, each with its accumulated
// term appended): z from a and D_2 .. D_{d-1} (d > 3), D_1 and D_3 .. D_{d-2} from the history
// above them, z and the old value, the position from D_1 .. D_{d-2}, both z and x(t). A blend
// parameter p_k = 1 zeroes one weight (of D_{d-1}(t - h) in the sum of level k, level 0 the
// position), and BuildUpdatePlan drops zero weights: bit k of ones says p_k = 1.
constexpr int StepSums(int d) { return d - 1; }
constexpr int StepTerms(int d, unsigned ones, int s) {
  const bool position = s == StepSums(d) - 1;
  const int level = position ? 0 : (d > 3 ? (s == 0 ? 2 : (s == 1 ? 1 : s + 1)) : 1);
  const int full = position ? d + 1 : (level == 2 ? d - 1 : d + 1 - level);
  return full - static_cast<int>((ones >> level) & 1U);
}

// One entry of sum S of a plan of a known shape: its term count is a constant, so no dispatch.
// Always inlined: the small kernels are these sums unrolled, and a call each would double them.
template <int D, unsigned Ones, int S>
__attribute__((always_inline)) inline void ShapedSum(const FusedPlan& fp, sunindextype i) {
  const FusedTerms& tk = fp.terms[S];
  StoreSum(tk, i, TermsAt<StepTerms(D, Ones, S)>(tk, i));
}

#if defined(__SSE2__) && defined(SUNDIALS_DOUBLE_PRECISION)
// Entries i and i + 1 of sum S in a pair: TermsAt's operations lane by lane (the same values).
template <int D, unsigned Ones, int S>
__attribute__((always_inline)) inline void ShapedSumPair(const FusedPlan& fp, sunindextype i) {
  const FusedTerms& tk = fp.terms[S];
  const auto weight = [&tk](int j) { return *reinterpret_cast<const Pair*>(tk.c2[j]); };
  Pair acc = weight(0) * Load(tk.X[0] + i, Pair{});
  for (int j = 1; j < StepTerms(D, Ones, S); ++j) acc += weight(j) * Load(tk.X[j] + i, Pair{});
  if (tk.old == nullptr) {
    Store(tk.out + i, acc);
  } else {
    StoreSum(tk, i, acc[0]);
    StoreSum(tk, i + 1, acc[1]);
  }
}
#endif

// UpdateSmall with the sums of one shape unrolled: the same operations in the same order, two
// entries at a time where SSE2 is (an entry's sums read only that entry of the sums before them).
template <int D, unsigned Ones, std::size_t... S>
inline sunrealtype UpdateShaped(const FusedPlan& fp, sunindextype n,
                                std::index_sequence<S...> /*sums*/) {
  const sunrealtype* xout = fp.terms[StepSums(D) - 1].out;
  sunrealtype sum = 0;
  sunindextype i = 0;
#if defined(__SSE2__) && defined(SUNDIALS_DOUBLE_PRECISION)
  for (; i + 2 <= n; i += 2) {
    (ShapedSumPair<D, Ones, static_cast<int>(S)>(fp, i), ...);
    sum += std::fabs(xout[i]);
    sum += std::fabs(xout[i + 1]);
  }
#endif
  for (; i < n; ++i) {
    (ShapedSum<D, Ones, static_cast<int>(S)>(fp, i), ...);
    sum += std::fabs(xout[i]);
  }
  return sum;
}

template <int D, unsigned Ones>
sunrealtype UpdateShape(const FusedPlan& fp, sunindextype n) {
  constexpr auto kSums = std::make_index_sequence<StepSums(D)>{};
  return n == 1 ? UpdateShaped<D, Ones>(fp, 1, kSums) : UpdateShaped<D, Ones>(fp, n, kSums);
}

// The shapes with kernels of their own (SmallKernel, PairKernel): every degree with no p_k = 1,
// and the named sets that have some (G3_CD: p_0; G5: p_1 .. p_3; G5_ONES: all). Other plans take
// UpdateSmall.
struct Shape {
  int d;
  unsigned ones;
};
constexpr Shape kShapes[] = {{3, 0},  {3, 1}, {4, 0}, {5, 0}, {5, 14},
                             {5, 15}, {6, 0}, {7, 0}, {8, 0}};
constexpr int kNumShapes = static_cast<int>(sizeof(kShapes) / sizeof(kShapes[0]));

// Four partial sums: the norm is a dependency chain of additions otherwise, slower than the
// update itself on large vectors. It only feeds the growth check, so its rounding (not that of
// N_VL1Norm's order) does not reach the state.
void AddAbs(const sunrealtype* x, sunindextype len, sunrealtype* s) {
  sunindextype i = 0;
#if defined(__SSE2__) && defined(SUNDIALS_DOUBLE_PRECISION)
  // The same four sums two lanes at a time (the compiler does not vectorise a reduction).
  const __m128d sign = _mm_set1_pd(-0.0);
  __m128d s01 = _mm_loadu_pd(s);
  __m128d s23 = _mm_loadu_pd(s + 2);
  for (; i + 4 <= len; i += 4) {
    s01 = _mm_add_pd(s01, _mm_andnot_pd(sign, _mm_loadu_pd(x + i)));
    s23 = _mm_add_pd(s23, _mm_andnot_pd(sign, _mm_loadu_pd(x + i + 2)));
  }
  _mm_storeu_pd(s, s01);
  _mm_storeu_pd(s + 2, s23);
#endif
  for (; i + 4 <= len; i += 4) {
    s[0] += std::fabs(x[i]);
    s[1] += std::fabs(x[i + 1]);
    s[2] += std::fabs(x[i + 2]);
    s[3] += std::fabs(x[i + 3]);
  }
  for (; i < len; ++i) s[0] += std::fabs(x[i]);
}

#if defined(__SSE2__) && defined(SUNDIALS_DOUBLE_PRECISION)
constexpr bool kCanStream = true;
// The new position on systems too large for the cache: stored past it (nothing reads it again
// in this step, and a normal store would first read the old line), its |x| summed from the
// registers into the same partial sums as AddAbs. The same multiplications and additions in
// the same order as SumBlock, two entries at a time. out is 16-byte aligned.
template <int F>
void SumBlockStream(const FusedTerms& tk, sunindextype off, sunindextype len, sunrealtype* out,
                    sunrealtype* s) {
  constexpr int kM = TermsOf(F);
  const sunrealtype* x[kM];
  __m128d c[kM];
  for (int j = 0; j < kM; ++j) {
    x[j] = tk.X[j] + off;
    c[j] = _mm_set1_pd(tk.c[j]);
  }
  auto pair = [&](sunindextype i) {
    if constexpr (F == kZero) return _mm_setzero_pd();
    if constexpr (F == kSum)
      return _mm_mul_pd(c[0], _mm_add_pd(_mm_loadu_pd(x[0] + i), _mm_loadu_pd(x[1] + i)));
    if constexpr (F == kDifference)
      return _mm_mul_pd(c[0], _mm_sub_pd(_mm_loadu_pd(x[0] + i), _mm_loadu_pd(x[1] + i)));
    __m128d acc = _mm_mul_pd(c[0], _mm_loadu_pd(x[0] + i));
    for (int j = 1; j < kM; ++j) acc = _mm_add_pd(acc, _mm_mul_pd(c[j], _mm_loadu_pd(x[j] + i)));
    return acc;
  };
  const __m128d sign = _mm_set1_pd(-0.0);
  __m128d s01 = _mm_loadu_pd(s);
  __m128d s23 = _mm_loadu_pd(s + 2);
  sunindextype i = 0;
  for (; i + 4 <= len; i += 4) {
    const __m128d a = pair(i);
    const __m128d b = pair(i + 2);
    _mm_stream_pd(out + i, a);
    _mm_stream_pd(out + i + 2, b);
    s01 = _mm_add_pd(s01, _mm_andnot_pd(sign, a));
    s23 = _mm_add_pd(s23, _mm_andnot_pd(sign, b));
  }
  _mm_storeu_pd(s, s01);
  _mm_storeu_pd(s + 2, s23);
  for (; i < len; ++i) {
    sunrealtype acc = 0;
    if constexpr (F == kSum) {
      acc = tk.c[0] * (x[0][i] + x[1][i]);
    } else if constexpr (F == kDifference) {
      acc = tk.c[0] * (x[0][i] - x[1][i]);
    } else if constexpr (F != kZero) {
      acc = tk.c[0] * x[0][i];
      for (int j = 1; j < kM; ++j) acc += tk.c[j] * x[j][i];
    }
    out[i] = acc;
    s[0] += std::fabs(acc);
  }
}
using StreamFn = void (*)(const FusedTerms&, sunindextype, sunindextype, sunrealtype*,
                          sunrealtype*);
template <std::size_t... F>
constexpr std::array<StreamFn, kNumForms> StreamTable(std::index_sequence<F...> /*forms*/) {
  return {&SumBlockStream<static_cast<int>(F)>...};
}
constexpr std::array<StreamFn, kNumForms> kStream =
    StreamTable(std::make_index_sequence<kNumForms>{});
void StreamFence() { _mm_sfence(); }
#else
constexpr bool kCanStream = false;
constexpr std::array<
    void (*)(const FusedTerms&, sunindextype, sunindextype, sunrealtype*, sunrealtype*), 1>
    kStream = {nullptr};
void StreamFence() {}
#endif

// Plans with compensation, entry by entry: the position's and the velocity's increments
// error-free (StoreCompensatedExact), the other sums as every other kernel. The uncompensated
// kernels stay as they are.
sunrealtype UpdateCompensated(const FusedPlan& fp, sunindextype n) {
  for (sunindextype i = 0; i < n; ++i) {
    for (int k = 0; k < fp.n; ++k) {
      const FusedTerms& tk = fp.terms[k];
      if (tk.exact) {
        StoreCompensatedExact(tk, i);
      } else {
        StoreSum(tk, i, SumAtForm(tk, i));
      }
    }
  }
  sunrealtype s[4] = {0, 0, 0, 0};
  AddAbs(fp.terms[fp.n - 1].out, n, s);
  return (s[0] + s[1]) + (s[2] + s[3]);
}

// From this size on the vectors of a step no longer fit in a (32 MiB) last-level cache.
constexpr sunindextype kStreamSystem = sunindextype{1} << 19;

// Each block stays in cache while every sum of the plan runs on it: one pass over the vectors.
sunrealtype UpdateBlocked(const FusedPlan& fp, sunindextype n) {
  constexpr sunindextype kBlockLen = 256;
  sunrealtype y[kBlockLen];
  const FusedTerms& last = fp.terms[fp.n - 1];
  const sunrealtype* xout = last.out;
  const bool stream = kCanStream && n >= kStreamSystem && last.old == nullptr && !last.in_place &&
                      reinterpret_cast<std::uintptr_t>(last.out) % 16 == 0;
  sunrealtype s[4] = {0, 0, 0, 0};
  for (sunindextype off = 0; off < n; off += kBlockLen) {
    const sunindextype len = std::min(kBlockLen, n - off);
    for (int k = 0; k < fp.n; ++k) {
      const FusedTerms& tk = fp.terms[k];
      if (stream && k == fp.n - 1) {
        kStream[tk.form](tk, off, len, tk.out + off, s);
        continue;
      }
      if (tk.in_place) {  // through the block buffer: SumBlock's output must not alias an input
        kBlock[tk.form](tk, off, len, y);
        std::copy(y, y + len, tk.out + off);
        continue;
      }
      if (tk.old == nullptr) {
        kBlock[tk.form](tk, off, len, tk.out + off);
        continue;
      }
      kBlock[tk.form](tk, off, len, y);  // y = increment - comp
      const sunrealtype* o = tk.old + off;
      sunrealtype* __restrict nw = tk.out + off;
      sunrealtype* __restrict cn = tk.compnew + off;
      for (sunindextype i = 0; i < len; ++i) {
        const sunrealtype v = o[i] + y[i];
        nw[i] = v;
        cn[i] = (v - o[i]) - y[i];
      }
    }
    if (!stream) AddAbs(xout + off, len, s);
  }
  if (stream) StreamFence();  // the streamed stores are visible before f reads x(t + h)
  return (s[0] + s[1]) + (s[2] + s[3]);
}

#if defined(__SSE2__) && defined(SUNDIALS_DOUBLE_PRECISION)
// Entries i .. i + 3 through k.At (which stores the step's results on the entries of one vector
// of type V and returns the new position's), |x| summed into four partial sums, entry i + l into
// s[l]: two pairs or one quad, the same additions. Returns the first entry left.
template <typename V, typename K>
__attribute__((always_inline)) inline sunindextype NormFours(const K& k, sunindextype n,
                                                             sunrealtype* s) {
  constexpr int kW = sizeof(V) / sizeof(sunrealtype);
  V acc[4 / kW];
  for (V& a : acc) a = Splat(0, V{});
  sunindextype i = 0;
  for (; i + 4 <= n; i += 4) {
    for (int l = 0; l < 4 / kW; ++l) acc[l] += Abs(k.At(i + l * kW));
  }
  std::memcpy(s, acc, sizeof acc);
  return i;
}

// The pass's |x| over all n entries: NormFours' four partial sums, the entries it leaves one by one
// (one(i) steps entry i and returns its new position) into the first, then the sums in a fixed
// order. Stream: the streamed stores are made visible after the vector part, before f reads
// x(t + h).
template <typename V, bool Stream = false, typename K, typename One>
__attribute__((always_inline)) inline sunrealtype NormPass(const K& k, sunindextype n, One one) {
  sunrealtype s[4];
  sunindextype i = NormFours<V>(k, n, s);
  if constexpr (Stream) StreamFence();
  for (; i < n; ++i) s[0] += std::fabs(one(i));
  return (s[0] + s[1]) + (s[2] + s[3]);
}

// The entries of one vector of type V from i of a sum of M terms: the same multiplications and
// additions in the same order as SumBlock.
template <int M, typename V>
__attribute__((always_inline)) inline V PairAt(const sunrealtype* const* x, const V* c,
                                               sunindextype i) {
  V acc = c[0] * Load(x[0] + i, V{});
  for (int j = 1; j < M; ++j) acc = acc + c[j] * Load(x[j] + i, V{});
  return acc;
}

template <int D, unsigned Ones, bool Stream, typename V>
struct PairPlan;
template <int D, unsigned Ones, bool Stream, int S, typename V>
V PairSums(const PairPlan<D, Ones, Stream, V>& pp, sunindextype i);

// Pointers and weights of a plan of a known shape, held where the loop keeps them in registers;
// the weights splatted into vectors of type V (Pair or Quad; streaming only with Pair).
template <int D, unsigned Ones, bool Stream, typename V>
struct PairPlan {
  static constexpr int kS = StepSums(D);
  // Zeroed: the shape fixes how many terms each sum reads (== FusedTerms::m, ShapeOf).
  const sunrealtype* x[kS][kMaxTerms] = {};
  V c[kS][kMaxTerms] = {};
  sunrealtype* out[kS] = {};
  __attribute__((always_inline)) explicit PairPlan(const FusedPlan& fp) {
    for (int k = 0; k < kS; ++k) {
      for (int j = 0; j < fp.terms[k].m; ++j) {
        x[k][j] = fp.terms[k].X[j];
        c[k][j] = Splat(fp.terms[k].c[j], V{});
      }
      out[k] = fp.terms[k].out;
    }
  }
  __attribute__((always_inline)) V At(sunindextype i) const {
    return PairSums<D, Ones, Stream, 0>(*this, i);
  }
};

// Sums S .. of the entries of one vector from i, in the plan's order; returns the last (the new
// position).
template <int D, unsigned Ones, bool Stream, int S, typename V>
__attribute__((always_inline)) inline V PairSums(const PairPlan<D, Ones, Stream, V>& pp,
                                                 sunindextype i) {
  const V r = PairAt<StepTerms(D, Ones, S)>(pp.x[S], pp.c[S], i);
  if constexpr (S + 1 < StepSums(D)) {
    Store(pp.out[S] + i, r);
    return PairSums<D, Ones, Stream, S + 1>(pp, i);
  } else {
    if constexpr (Stream) {
      _mm_stream_pd(pp.out[S] + i, r);
    } else {
      Store(pp.out[S] + i, r);
    }
    return r;
  }
}

template <int D, unsigned Ones, std::size_t... S>
inline void ShapedEntry(const FusedPlan& fp, sunindextype i, std::index_sequence<S...> /*sums*/) {
  (ShapedSum<D, Ones, static_cast<int>(S)>(fp, i), ...);
}

// Large systems of a known shape without compensation, as a hand loop runs them: a vector of
// entries at a time through every sum of the plan, the position's |x| summed from the register.
// No block buffer, so an in-place sum writes its output directly: it reads those entries first,
// and no later sum reads the old values. Entry by entry the operations and their order are
// SumBlock's, so the state is bit for bit that of UpdateBlocked (and of the N_Vector reference).
// Inlined into each instruction set's entry.
template <int D, unsigned Ones, bool Stream, typename V = Pair>
__attribute__((always_inline)) inline sunrealtype PairsPass(const FusedPlan& fp, sunindextype n) {
  const PairPlan<D, Ones, Stream, V> pp(fp);
  return NormPass<V, Stream>(
      pp, n, [&](sunindextype i) __attribute__((always_inline)) {
        ShapedEntry<D, Ones>(fp, i, std::make_index_sequence<StepSums(D)>{});
        return pp.out[StepSums(D) - 1][i];
      });
}
template <int D, unsigned Ones, bool Stream>
sunrealtype UpdatePairs(const FusedPlan& fp, sunindextype n) {
  return PairsPass<D, Ones, Stream>(fp, n);
}
#if defined(CEODE_AVX)
// Four entries at a time in AVX's three-operand encoding: the same operations per entry.
template <int D, unsigned Ones>
__attribute__((target("avx"))) sunrealtype UpdatePairsAvx(const FusedPlan& fp, sunindextype n) {
  return PairsPass<D, Ones, false, Quad>(fp, n);
}
#endif

// ---- Each value read once: the step's update as a hand loop runs it ----
// UpdatePairs reads every term from memory, so a history vector that several sums weigh (D_{d-1}
// enters all of them) is loaded once per sum, through a pointer loaded as often. The plans of
// BuildUpdatePlan read few distinct values, each in a role: a = D_2(t) (0), the history
// D_j(t - h) (j = 1 .. d-1), x(t) (d), and the results of earlier sums, z(t) (d + 1; a itself
// for d = 3) and the new D_k(t) (d + 1 + k). UpdateRoles loads each input role once per two
// entries, keeps the results in registers for the sums after them and stores each output once.
constexpr int kRoleA = 0;
constexpr int RoleZ(int d) { return d > 3 ? d + 1 : kRoleA; }
constexpr int RoleNew(int d, int k) { return k == 2 ? kRoleA : d + 1 + k; }
constexpr int NumRoles(int d) { return 2 * d; }
// The derivative level of sum s other than the position's (StepTerms' numbering).
constexpr int SumLevel(int d, int s) { return d > 3 ? (s == 1 ? 1 : s + 1) : 1; }

// The role of term j of sum s in the shape (d, ones), in BuildUpdatePlan's order: z from a and
// D_2 .. D_{d-1}; level k from D_{k+1} .. D_{d-1}, z and D_k (the accumulated term); the position
// from the new D_1 .. D_{d-2}, D_{d-1}(t - h), z and x(t). A weight p_k = 1 drops D_{d-1}.
constexpr int TermRole(int d, unsigned ones, int s, int j) {
  if (s == StepSums(d) - 1) {
    if (j < d - 2) return RoleNew(d, j + 1);
    int r = j - (d - 2);
    if ((ones & 1U) == 0) {
      if (r == 0) return d - 1;
      --r;
    }
    return r == 0 ? RoleZ(d) : d;
  }
  if (d > 3 && s == 0) return j == 0 ? kRoleA : j + 1;
  const int k = SumLevel(d, s);
  const int hk = d - 1 - k - static_cast<int>((ones >> k) & 1U);
  if (j < hk) return k + 1 + j;
  return j == hk ? RoleZ(d) : k;
}
// The role sum s writes (the position, the last sum, has none: it is stored and summed only).
constexpr int OutRole(int d, int s) {
  return d > 3 && s == 0 ? RoleZ(d) : RoleNew(d, SumLevel(d, s));
}
// Whether term j of sum s is the accumulated one (the old D_k of a level, x(t) of the position:
// the last term), whose weight is 1: its product is the value itself, bit for bit, and is not
// formed (RolesMatch checks the weight).
constexpr bool UnitTerm(int d, unsigned ones, int s, int j) {
  return j == StepTerms(d, ones, s) - 1 && !(d > 3 && s == 0);
}
// An input role (a, the history, x(t)) is loaded only when some sum reads it.
constexpr bool RoleRead(int d, unsigned ones, int r) {
  for (int s = 0; s < StepSums(d); ++s) {
    for (int j = 0; j < StepTerms(d, ones, s); ++j) {
      if (TermRole(d, ones, s, j) == r) return true;
    }
  }
  return false;
}

// Whether a plan of the shape (d, ones) reads its vectors in these roles, so that loading every
// input first gives the terms the values the plan's order gives them: each input role one
// vector, written by no earlier sum (the results of earlier sums are read as their roles), and
// each result read from the output of the sum that computes it; the accumulated terms weigh 1
// (UnitWeightsHold).
template <int D, unsigned Ones>
bool UnitWeightsHold(const FusedPlan& fp) {
  for (int s = 0; s < fp.n; ++s) {
    for (int j = 0; j < fp.terms[s].m; ++j) {
      if (UnitTerm(D, Ones, s, j) && fp.terms[s].c[j] != 1) return false;
    }
  }
  return true;
}
template <int D, unsigned Ones>
bool RolesMatch(const FusedPlan& fp) {
  if (fp.compensated || fp.n != StepSums(D) || !UnitWeightsHold<D, Ones>(fp)) return false;
  const sunrealtype* in[NumRoles(D)] = {};
  const sunrealtype* made[NumRoles(D)] = {};
  for (int s = 0; s < fp.n; ++s) {
    const FusedTerms& tk = fp.terms[s];
    if (tk.m != StepTerms(D, Ones, s) || tk.old != nullptr || tk.lead_old) return false;
    for (int j = 0; j < tk.m; ++j) {
      const int r = TermRole(D, Ones, s, j);
      const sunrealtype* x = tk.X[j];
      if (r > D) {
        if (made[r] != x) return false;
        continue;
      }
      if (in[r] != nullptr && in[r] != x) return false;
      in[r] = x;
      for (int e = 0; e < s; ++e) {
        if (fp.terms[e].out == x) return false;
      }
    }
    if (s + 1 < fp.n) made[OutRole(D, s)] = tk.out;
  }
  return true;
}

template <int D, unsigned Ones, typename V>
struct RolePlan;
template <int D, unsigned Ones, typename V>
V RolePair(const RolePlan<D, Ones, V>& rp, sunindextype i);

// The pointers and weights of a plan in its roles, held where the loop keeps them in registers;
// the weights splatted into vectors of type V (Pair or Quad).
template <int D, unsigned Ones, typename V>
struct RolePlan {
  static constexpr int kS = StepSums(D);
  const sunrealtype* in[NumRoles(D)] = {};
  V c[kS][kMaxTerms] = {};
  sunrealtype* out[kS] = {};
  __attribute__((always_inline)) explicit RolePlan(const FusedPlan& fp) {
    for (int s = 0; s < kS; ++s) {
      for (int j = 0; j < StepTerms(D, Ones, s); ++j) {
        c[s][j] = Splat(fp.terms[s].c[j], V{});
        const int r = TermRole(D, Ones, s, j);
        if (r <= D) in[r] = fp.terms[s].X[j];
      }
      out[s] = fp.terms[s].out;
    }
  }
  __attribute__((always_inline)) V At(sunindextype i) const { return RolePair(*this, i); }
};

// Terms J .. of sum S on the role values v, added to acc in the plan's order.
template <int D, unsigned Ones, int S, int J, typename V>
__attribute__((always_inline)) inline V RoleTerms(const RolePlan<D, Ones, V>& rp, const V* v,
                                                  const V& acc) {
  if constexpr (J == StepTerms(D, Ones, S)) {
    return acc;
  } else {
    const V x = v[TermRole(D, Ones, S, J)];
    const V t = UnitTerm(D, Ones, S, J) ? x : rp.c[S][J] * x;
    return RoleTerms<D, Ones, S, J + 1>(rp, v, acc + t);
  }
}
// Sums S .. in order, each result kept as its role; returns the position's.
template <int D, unsigned Ones, int S, typename V>
__attribute__((always_inline)) inline V RoleSums(const RolePlan<D, Ones, V>& rp, V* v) {
  const V first = rp.c[S][0] * v[TermRole(D, Ones, S, 0)];
  const V r = RoleTerms<D, Ones, S, 1>(rp, v, first);
  if constexpr (S + 1 < StepSums(D)) {
    v[OutRole(D, S)] = r;
    return RoleSums<D, Ones, S + 1>(rp, v);
  } else {
    return r;
  }
}
template <int D, unsigned Ones, int R, typename V>
__attribute__((always_inline)) inline void LoadRoles(const RolePlan<D, Ones, V>& rp, V* v,
                                                     sunindextype i) {
  if constexpr (R <= D) {
    if constexpr (RoleRead(D, Ones, R)) v[R] = Load(rp.in[R] + i, V{});
    LoadRoles<D, Ones, R + 1>(rp, v, i);
  }
}
template <int D, unsigned Ones, int S, typename V>
__attribute__((always_inline)) inline void StoreRoles(const RolePlan<D, Ones, V>& rp, const V* v,
                                                      const V& x, sunindextype i) {
  if constexpr (S + 1 < StepSums(D)) {
    Store(rp.out[S] + i, v[OutRole(D, S)]);
    StoreRoles<D, Ones, S + 1>(rp, v, x, i);
  } else {
    Store(rp.out[S] + i, x);
  }
}
// The entries of one vector of type V from i through every sum; returns the new position's.
template <int D, unsigned Ones, typename V>
__attribute__((always_inline)) inline V RolePair(const RolePlan<D, Ones, V>& rp, sunindextype i) {
  V v[NumRoles(D)];
  LoadRoles<D, Ones, 0>(rp, v, i);
  const V x = RoleSums<D, Ones, 0>(rp, v);
  StoreRoles<D, Ones, 0>(rp, v, x, i);
  return x;
}

// UpdatePairs (without streaming) on a plan whose roles match: the same operations in the same
// order on each entry, and the norm's partial sums as UpdatePairs forms them. Inlined into each
// instruction set's entry.
template <int D, unsigned Ones, typename V = Pair>
__attribute__((always_inline)) inline sunrealtype RolesPass(const FusedPlan& fp, sunindextype n) {
  const RolePlan<D, Ones, V> rp(fp);
  return NormPass<V>(
      rp, n, [&](sunindextype i) __attribute__((always_inline)) {
        ShapedEntry<D, Ones>(fp, i, std::make_index_sequence<StepSums(D)>{});
        return rp.out[StepSums(D) - 1][i];
      });
}
template <int D, unsigned Ones>
sunrealtype UpdateRoles(const FusedPlan& fp, sunindextype n) {
  return RolesPass<D, Ones>(fp, n);
}
#if defined(CEODE_AVX)
// Four entries at a time in AVX's three-operand encoding (SSE2's two-operand form copies each
// weight and value that is read again first): the same operations per entry, the same sums.
template <int D, unsigned Ones>
__attribute__((target("avx"))) sunrealtype UpdateRolesAvx(const FusedPlan& fp, sunindextype n) {
  return RolesPass<D, Ones, Quad>(fp, n);
}
#endif
// The roles' kernel in the best encoding the processor runs, chosen with the kernel.
template <int D, unsigned Ones>
SerialKernelFn RolesKernel() {
#if defined(CEODE_AVX)
  if (__builtin_cpu_supports("avx")) return &UpdateRolesAvx<D, Ones>;
#endif
  return &UpdateRoles<D, Ones>;
}

// Systems of a few unknowns whose plan reads its vectors in the roles: entry by entry, each value
// loaded once and each result kept in a register for the sums after it (UpdateShape loads a
// value again, through its pointer, for every sum that weighs it, and reads each result back from
// its store). The pointers and weights are read from the plan where they lie (a RolePlan's copy
// of them costs more than a few entries' sums). UpdateShape's operations in its order, and its
// norm, summed entry by entry. From kRolesFew entries on, UpdateShape's pairs of entries take
// fewer instructions.
constexpr sunindextype kRolesFew = 4;
// The first term that reads input role r, as sum * kMaxTerms + term (-1: none).
constexpr int FirstRead(int d, unsigned ones, int r) {
  for (int s = 0; s < StepSums(d); ++s) {
    for (int j = 0; j < StepTerms(d, ones, s); ++j) {
      if (TermRole(d, ones, s, j) == r) return s * kMaxTerms + j;
    }
  }
  return -1;
}
template <int D, unsigned Ones, int S, int J>
__attribute__((always_inline)) inline sunrealtype FewTerms(const FusedPlan& fp,
                                                           const sunrealtype* v, sunrealtype acc) {
  if constexpr (J == StepTerms(D, Ones, S)) {
    return acc;
  } else {
    const sunrealtype x = v[TermRole(D, Ones, S, J)];
    const sunrealtype t = UnitTerm(D, Ones, S, J) ? x : fp.terms[S].c[J] * x;
    return FewTerms<D, Ones, S, J + 1>(fp, v, acc + t);
  }
}
template <int D, unsigned Ones, int S>
__attribute__((always_inline)) inline sunrealtype FewSums(const FusedPlan& fp, sunrealtype* v,
                                                          sunindextype i) {
  const sunrealtype r =
      FewTerms<D, Ones, S, 1>(fp, v, fp.terms[S].c[0] * v[TermRole(D, Ones, S, 0)]);
  fp.terms[S].out[i] = r;
  if constexpr (S + 1 < StepSums(D)) {
    v[OutRole(D, S)] = r;
    return FewSums<D, Ones, S + 1>(fp, v, i);
  } else {
    return r;
  }
}
template <int D, unsigned Ones, int R>
__attribute__((always_inline)) inline void FewLoads(const FusedPlan& fp, sunrealtype* v,
                                                    sunindextype i) {
  if constexpr (R <= D) {
    constexpr int kAt = FirstRead(D, Ones, R);
    if constexpr (kAt >= 0) v[R] = fp.terms[kAt / kMaxTerms].X[kAt % kMaxTerms][i];
    FewLoads<D, Ones, R + 1>(fp, v, i);
  }
}
template <int D, unsigned Ones>
sunrealtype UpdateRolesFew(const FusedPlan& fp, sunindextype n) {
  sunrealtype sum = 0;
  for (sunindextype i = 0; i < n; ++i) {
    sunrealtype v[NumRoles(D)];
    FewLoads<D, Ones, 0>(fp, v, i);
    sum += std::fabs(FewSums<D, Ones, 0>(fp, v, i));
  }
  return sum;
}
template <int D, unsigned Ones>
SerialKernelFn SmallKernel(const FusedPlan& fp, sunindextype n, bool many) {
  if (many && n < kRolesFew && RolesMatch<D, Ones>(fp)) return &UpdateRolesFew<D, Ones>;
  return &UpdateShape<D, Ones>;
}

// ---- G3_CD's kick and drift (LeapKernels) ----
// Whether fp is G3_CD's plan in the leapfrog's form (ceode_step_plans.cpp, LeapForm): v =
// (1 v_old + c a_old) + c a into the velocity's buffer, u = 1 v + c a (a work vector, which these
// kernels keep in registers), x(t + h) = 1 x(t) + h u.
bool IsLeapPlan(const FusedPlan& fp) {
  if (fp.n != 3 || fp.compensated) return false;
  const FusedTerms& tv = fp.terms[0];
  const FusedTerms& tu = fp.terms[1];
  const FusedTerms& tx = fp.terms[2];
  const bool v = tv.lead_old && tv.m == 3 && tv.form == 3 && tv.c[0] == 1 && tv.c[1] == tv.c[2];
  const bool u = !tu.lead_old && tu.m == 2 && tu.form == 2 && tu.c[0] == 1 && tu.c[1] == tv.c[1] &&
                 tu.X[0] == tv.out && tu.X[1] == tv.X[2];
  const bool x = tx.lead_old && tx.m == 2 && tx.form == 2 && tx.c[0] == 1 && tx.X[1] == tu.out;
  return v && u && x && tv.old == nullptr && tu.old == nullptr && tx.old == nullptr;
}

// The step on the entries of one vector of type V from i (TermsAt's operations in its order;
// the unit products are the values themselves, and c a, formed once, is the same product in both
// sums). kFromV: the velocity buffer holds v_old (else u = v_old + c a_old, and a_old is not
// read); kToU: u = v + c a is stored (else v). Returns x(t + h).
template <bool kFromV, bool kToU, bool kStream, typename V>
struct LeapStep {
  const sunrealtype* vin;
  const sunrealtype* aold;
  const sunrealtype* a;
  const sunrealtype* x;
  sunrealtype* vout;
  sunrealtype* xout;
  V c, w;
  __attribute__((always_inline)) explicit LeapStep(const FusedPlan& fp)
      : vin(fp.terms[0].X[0]),
        aold(fp.terms[0].X[1]),
        a(fp.terms[0].X[2]),
        x(fp.terms[2].X[0]),
        vout(fp.terms[0].out),
        xout(fp.terms[2].out),
        c(Splat(fp.terms[0].c[1], V{})),
        w(Splat(fp.terms[2].c[1], V{})) {}
  __attribute__((always_inline)) V At(sunindextype i) const {
    V u = Load(vin + i, V{});
    if constexpr (kFromV) u = u + c * Load(aold + i, V{});
    const V ca = c * Load(a + i, V{});
    const V v = u + ca;
    const V un = v + ca;
    const V xn = Load(x + i, V{}) + w * un;
    Store(vout + i, kToU ? un : v);
    if constexpr (kStream) {
      _mm_stream_pd(xout + i, xn);  // Pair only (LeapKernel streams in the SSE2 entry)
    } else {
      Store(xout + i, xn);
    }
    return xn;
  }
  __attribute__((always_inline)) sunrealtype One(sunindextype i) const {
    const sunrealtype k = c[0];
    sunrealtype u = vin[i];
    if constexpr (kFromV) u += k * aold[i];
    const sunrealtype ca = k * a[i];
    const sunrealtype v = u + ca;
    const sunrealtype un = v + ca;
    const sunrealtype xn = x[i] + w[0] * un;
    vout[i] = kToU ? un : v;
    xout[i] = xn;
    return xn;
  }
};

// Inlined into each instruction set's entry.
template <bool kFromV, bool kToU, bool kStream, typename V = Pair>
__attribute__((always_inline)) inline sunrealtype LeapPass(const FusedPlan& fp, sunindextype n) {
  const LeapStep<kFromV, kToU, kStream, V> st(fp);
  return NormPass<V, kStream>(
      st, n, [&](sunindextype i) __attribute__((always_inline)) { return st.One(i); });
}
template <bool kFromV, bool kToU, bool kStream>
sunrealtype UpdateLeap(const FusedPlan& fp, sunindextype n) {
  return LeapPass<kFromV, kToU, kStream>(fp, n);
}
#if defined(CEODE_AVX)
// Four entries at a time in AVX's three-operand encoding: the same operations per entry.
template <bool kFromV, bool kToU>
__attribute__((target("avx"))) sunrealtype UpdateLeapAvx(const FusedPlan& fp, sunindextype n) {
  return LeapPass<kFromV, kToU, false, Quad>(fp, n);
}
#endif

// Streaming the new position past the cache where it is written out of place (UpdatePairsAuto).
bool LeapStreams(const FusedPlan& fp, sunindextype n) {
  const FusedTerms& tx = fp.terms[2];
  return n >= kStreamSystem && !tx.in_place && reinterpret_cast<std::uintptr_t>(tx.out) % 16 == 0;
}
template <bool kFromV, bool kToU>
SerialKernelFn LeapKernel(const FusedPlan& fp, sunindextype n) {
  if (LeapStreams(fp, n)) return &UpdateLeap<kFromV, kToU, true>;
#if defined(CEODE_AVX)
  if (__builtin_cpu_supports("avx")) return &UpdateLeapAvx<kFromV, kToU>;
#endif
  return &UpdateLeap<kFromV, kToU, false>;
}
constexpr bool kHaveLeap = true;

template <int D, unsigned Ones>
sunrealtype UpdatePairsAuto(const FusedPlan& fp, sunindextype n) {
  // A position written over its last value stays in cache until written back, as in a hand loop:
  // streaming it (and the history beside it) measured slower at 10^6 entries (bench_step).
  const FusedTerms& last = fp.terms[StepSums(D) - 1];
  const bool stream =
      n >= kStreamSystem && !last.in_place && reinterpret_cast<std::uintptr_t>(last.out) % 16 == 0;
  return stream ? UpdatePairs<D, Ones, true>(fp, n) : UpdatePairs<D, Ones, false>(fp, n);
}
// The kernel of a plan of the shape: UpdatePairsAuto where the position may be streamed (SSE2),
// else the roles' when they match, else UpdatePairs, in the best encoding the processor runs.
template <int D, unsigned Ones>
SerialKernelFn PairKernel(const FusedPlan& fp, sunindextype n) {
  const FusedTerms& last = fp.terms[StepSums(D) - 1];
  if (n >= kStreamSystem && !last.in_place) return &UpdatePairsAuto<D, Ones>;
  if (RolesMatch<D, Ones>(fp)) return RolesKernel<D, Ones>();
#if defined(CEODE_AVX)
  if (__builtin_cpu_supports("avx")) return &UpdatePairsAvx<D, Ones>;
#endif
  return &UpdatePairs<D, Ones, false>;
}
constexpr bool kHavePairs = true;
#else
template <int D, unsigned Ones>
sunrealtype UpdatePairsAuto(const FusedPlan& fp, sunindextype n) {
  return UpdateBlocked(fp, n);
}
template <int D, unsigned Ones>
SerialKernelFn PairKernel(const FusedPlan& /*fp*/, sunindextype /*n*/) {
  return &UpdatePairsAuto<D, Ones>;
}
template <int D, unsigned Ones>
SerialKernelFn SmallKernel(const FusedPlan& /*fp*/, sunindextype /*n*/, bool /*many*/) {
  return &UpdateShape<D, Ones>;
}
constexpr bool kHavePairs = false;
bool IsLeapPlan(const FusedPlan& /*fp*/) { return false; }
template <bool kFromV, bool kToU>
SerialKernelFn LeapKernel(const FusedPlan& /*fp*/, sunindextype /*n*/) {
  return nullptr;
}
constexpr bool kHaveLeap = false;
#endif

using PairKernelFn = SerialKernelFn (*)(const FusedPlan&, sunindextype);
template <std::size_t... I>
constexpr std::array<PairKernelFn, kNumShapes> PairTable(std::index_sequence<I...> /*shapes*/) {
  return {&PairKernel<kShapes[I].d, kShapes[I].ones>...};
}
constexpr std::array<PairKernelFn, kNumShapes> kPairs =
    PairTable(std::make_index_sequence<kNumShapes>{});
using SmallKernelFn = SerialKernelFn (*)(const FusedPlan&, sunindextype, bool);
template <std::size_t... I>
constexpr std::array<SmallKernelFn, kNumShapes> SmallTable(std::index_sequence<I...> /*shapes*/) {
  return {&SmallKernel<kShapes[I].d, kShapes[I].ones>...};
}
constexpr std::array<SmallKernelFn, kNumShapes> kSmall =
    SmallTable(std::make_index_sequence<kNumShapes>{});

sunrealtype UpdateOne(const FusedPlan& fp, sunindextype /*n*/) {
  return UpdateSmall(fp, 1);  // one unknown: the entry loop folds away
}
sunrealtype UpdateFew(const FusedPlan& fp, sunindextype n) { return UpdateSmall(fp, n); }

// many: the plan runs many times (SerialKernel), so a kernel that takes a test to choose pays.
SerialKernelFn ChooseKernel(const FusedPlan& fp, sunindextype n, bool many) {
  if (fp.compensated) return &UpdateCompensated;
  if (fp.shape > 0 && n < kSmallSystem) return kSmall[fp.shape - 1](fp, n, many);
  if (kHaveLeap && n >= kSmallSystem && IsLeapPlan(fp)) return LeapKernel<true, false>(fp, n);
  if (kHavePairs && fp.shape > 0 && !fp.compensated) return kPairs[fp.shape - 1](fp, n);
  if (n == 1) return &UpdateOne;
  return n < kSmallSystem ? &UpdateFew : &UpdateBlocked;
}

}  // namespace

SerialKernelFn SerialKernel(const FusedPlan& fp, sunindextype n) {
  return ChooseKernel(fp, n, true);
}

sunrealtype UpdateSerial(const FusedPlan& fp, sunindextype n) {
  return ChooseKernel(fp, n, false)(fp, n);
}

bool LeapKernelsOf(const FusedPlan& fp, sunindextype n, LeapKernels* k) {
  if (!kHaveLeap || n < kSmallSystem || !IsLeapPlan(fp)) return false;
  k->first = LeapKernel<true, true>(fp, n);
  k->mid = LeapKernel<false, true>(fp, n);
  k->last = LeapKernel<false, false>(fp, n);
  return true;
}

// Serial vectors (their array operation is N_VGetArrayPointer_Serial, so their content is
// serial) without a call: every plan build takes a few hundred of these, and each call runs
// through the vector's operation table (unoptimised in some SUNDIALS builds). Others through
// the generic accessor.
namespace {

// 1 + the index in kShapes of the plan's shape (term counts), 0 for none.
int ShapeOf(const FusedPlan& fp) {
  for (int i = 0; i < kNumShapes; ++i) {
    bool same = StepSums(kShapes[i].d) == fp.n;
    for (int k = 0; same && k < fp.n; ++k) {
      same = fp.terms[k].form == StepTerms(kShapes[i].d, kShapes[i].ones, k);
    }
    if (same) return i + 1;
  }
  return 0;
}

}  // namespace

namespace {

// Vector types whose N_VGetArrayPointer is the (local) data in host memory, current.
bool HostData(N_Vector v) {
  const N_Vector_ID id = N_VGetVectorID(v);
  return (id == SUNDIALS_NVEC_SERIAL || id == SUNDIALS_NVEC_PARALLEL ||
          id == SUNDIALS_NVEC_OPENMP || id == SUNDIALS_NVEC_PTHREADS) &&
         N_VGetArrayPointer(v) != nullptr;
}

}  // namespace

bool CompensatedSumOnData(const Combo& cb, const Compensation& cs) {
  N_Vector all[kMaxDegree + 5];
  int m = 0;
  for (int j = 0; j < cb.m; ++j) all[m++] = cb.X[j];
  all[m++] = cs.comp[cb.level];
  all[m++] = cb.old;
  all[m++] = cs.compnew[cb.level];
  all[m++] = cb.out;
  FusedTerms tk;
  for (int j = 0; j < m; ++j) {
    if (!HostData(all[j])) return false;
  }
  tk.exact = true;
  tk.m = cb.m + 1;
  for (int j = 0; j < cb.m; ++j) {
    tk.c[j] = cb.c[j];
    tk.X[j] = N_VGetArrayPointer(cb.X[j]);
  }
  tk.c[cb.m] = -1;
  tk.X[cb.m] = N_VGetArrayPointer(cs.comp[cb.level]);
  tk.old = N_VGetArrayPointer(cb.old);
  tk.compnew = N_VGetArrayPointer(cs.compnew[cb.level]);
  tk.out = N_VGetArrayPointer(cb.out);
  N_Vector v = cb.out;
  const sunindextype n =
      v->ops->nvgetlocallength != nullptr ? v->ops->nvgetlocallength(v) : N_VGetLength(v);
  for (sunindextype i = 0; i < n; ++i) StoreCompensatedExact(tk, i);
  return true;
}

namespace {

// The weights twice (c2), which the shaped kernels read as pairs (ShapedSumPair).
void PairWeights(FusedTerms* tk) {
  for (int j = 0; j < tk->m; ++j) tk->c2[j][0] = tk->c2[j][1] = tk->c[j];
}

}  // namespace

// Each combination with its accumulated term (or, compensated, minus its compensation)
// appended, exactly as RunCombo hands it to Combine.
bool BuildFusedPlan(const UpdatePlan& plan, const Compensation& cs, FusedPlan* fp) {
  fp->n = plan.n;
  bool distinct = true;  // no sum writes a vector it reads (the kernels rely on it)
  for (int k = 0; k < plan.n; ++k) {
    const Combo& cb = plan.combos[k];
    FusedTerms& tk = fp->terms[k];
    tk.lead_old = cb.old != nullptr && !cs.on && cb.lead_old;
    const int lead = tk.lead_old ? 1 : 0;
    tk.m = cb.m + lead;
    if (tk.lead_old) {
      tk.c[0] = 1;
      tk.X[0] = SerialData(cb.old);
    }
    for (int j = 0; j < cb.m; ++j) {
      tk.c[j + lead] = cb.c[j];
      tk.X[j + lead] = SerialData(cb.X[j]);
    }
    tk.old = nullptr;
    tk.compnew = nullptr;
    if (cb.old != nullptr && !cs.on && !tk.lead_old) {
      tk.c[tk.m] = 1;
      tk.X[tk.m++] = SerialData(cb.old);
    } else if (cb.old != nullptr && cs.on) {
      tk.c[tk.m] = -1;
      tk.X[tk.m++] = SerialData(cs.comp[cb.level]);
      tk.old = SerialData(cb.old);
      tk.compnew = SerialData(cs.compnew[cb.level]);
    }
    tk.out = SerialData(cb.out);
    tk.form = FormOf(tk.m, tk.c);
    // In place: the accumulated quantity written over itself, entry by entry after it is read.
    tk.in_place = cb.old != nullptr && cb.old == cb.out && !cs.on;
    tk.exact = tk.old != nullptr && ExactIncrement(cb.level);
    const int own = !tk.in_place ? -1 : (tk.lead_old ? 0 : tk.m - 1);  // read before written
    PairWeights(&tk);
    for (int j = 0; j < tk.m; ++j) distinct &= j == own || tk.X[j] != tk.out;
    distinct = distinct && (tk.old == nullptr ||
                            (tk.old != tk.out && tk.compnew != tk.out && tk.compnew != tk.old));
  }
  fp->compensated = cs.on;
  fp->shape = distinct ? ShapeOf(*fp) : 0;
  return distinct;
}

// The terms are copied into a FusedTerms only as far as the form reads them: at n of a few the
// copy is most of the call.
void CombineSerial(sunindextype n, int m, const sunrealtype* c, const sunrealtype* const* x,
                   sunrealtype* out) {
  if (CombineEntries(n, m, c, x, out)) return;
  FusedTerms tk;
  for (int j = 0; j < m; ++j) {
    tk.c[j] = c[j];
    tk.X[j] = const_cast<sunrealtype*>(x[j]);
  }
  kBlock[FormOf(m, c)](tk, 0, n, out);
}

void CombineSerial(sunindextype n, int m, const sunrealtype* c, const N_Vector* X,
                   sunrealtype* out) {
  const sunrealtype* x[kMaxTerms];
  SerialDataOf(m, X, x);
  if (CombineEntries(n, m, c, x, out)) return;
  CombineSerial(n, m, c, x, out);
}

// Once both IDs say serial, the content is read directly (NV_DATA_S, NV_LENGTH_S): every getter
// is two calls through SUNDIALS, and these copies run twice per CE_ONE_STEP call. N_VScale(1, ...)
// elsewhere is a multiply loop with the same values.
void CopyVector(N_Vector from, N_Vector to) {
  if (N_VGetVectorID(from) == SUNDIALS_NVEC_SERIAL && N_VGetVectorID(to) == SUNDIALS_NVEC_SERIAL) {
    const sunrealtype* src = NV_DATA_S(from);
    sunrealtype* dst = NV_DATA_S(to);
    if (src != nullptr && dst != nullptr) {
      if (src != dst) std::memcpy(dst, src, sizeof(sunrealtype) * NV_LENGTH_S(from));
      return;
    }
  }
  N_VScale(1, from, to);
}

namespace {

// Whether x[0 .. n) are all finite. A NaN or an infinity makes their sum NaN or infinite, so a
// finite sum (four additions per eight entries) answers for all; only a sum that is not (a value
// that is not, or finite values overflowing together) looks at the entries one by one.
bool FiniteData(const sunrealtype* x, sunindextype n) {
  sunindextype i = 0;
  sunrealtype sum = 0;
#if defined(__SSE2__) && defined(SUNDIALS_DOUBLE_PRECISION)
  __m128d a = _mm_setzero_pd();
  __m128d b = _mm_setzero_pd();
  __m128d c = _mm_setzero_pd();
  __m128d e = _mm_setzero_pd();
  for (; i + 8 <= n; i += 8) {
    a = _mm_add_pd(a, _mm_loadu_pd(x + i));
    b = _mm_add_pd(b, _mm_loadu_pd(x + i + 2));
    c = _mm_add_pd(c, _mm_loadu_pd(x + i + 4));
    e = _mm_add_pd(e, _mm_loadu_pd(x + i + 6));
  }
  sunrealtype lanes[2];
  _mm_storeu_pd(lanes, _mm_add_pd(_mm_add_pd(a, b), _mm_add_pd(c, e)));
  sum = lanes[0] + lanes[1];
#endif
  for (; i < n; ++i) sum += x[i];
  if (std::isfinite(sum)) return true;
  for (i = 0; i < n; ++i) {
    if (!std::isfinite(x[i])) return false;
  }
  return true;
}

// to[0 .. n) = from[0 .. n) (to == from: only the test); returns whether all are finite. The
// copy and FiniteData's sum in one loop: memcpy would be a second pass, and from a few pages on it
// is a string instruction repeated per byte.
bool CopyFiniteData(const sunrealtype* from, sunrealtype* to, sunindextype n) {
  if (to == from) return FiniteData(from, n);
  sunindextype i = 0;
  sunrealtype sum = 0;
#if defined(__SSE2__) && defined(SUNDIALS_DOUBLE_PRECISION)
  __m128d a = _mm_setzero_pd();
  __m128d b = _mm_setzero_pd();
  __m128d c = _mm_setzero_pd();
  __m128d e = _mm_setzero_pd();
  for (; i + 8 <= n; i += 8) {
    const __m128d x0 = _mm_loadu_pd(from + i);
    const __m128d x1 = _mm_loadu_pd(from + i + 2);
    const __m128d x2 = _mm_loadu_pd(from + i + 4);
    const __m128d x3 = _mm_loadu_pd(from + i + 6);
    _mm_storeu_pd(to + i, x0);
    _mm_storeu_pd(to + i + 2, x1);
    _mm_storeu_pd(to + i + 4, x2);
    _mm_storeu_pd(to + i + 6, x3);
    a = _mm_add_pd(a, x0);
    b = _mm_add_pd(b, x1);
    c = _mm_add_pd(c, x2);
    e = _mm_add_pd(e, x3);
  }
  sunrealtype lanes[2];
  _mm_storeu_pd(lanes, _mm_add_pd(_mm_add_pd(a, b), _mm_add_pd(c, e)));
  sum = lanes[0] + lanes[1];
#endif
  for (; i < n; ++i) {
    to[i] = from[i];
    sum += from[i];
  }
  return std::isfinite(sum) || FiniteData(from, n);
}

// The data and length of a serial vector, or nullptr for the other kinds.
inline sunrealtype* SerialOnly(N_Vector v) {
  return v->ops->nvgetarraypointer == N_VGetArrayPointer_Serial ? NV_DATA_S(v) : nullptr;
}

}  // namespace

bool CopyFinite(N_Vector from, N_Vector to) {
  const sunrealtype* src = SerialOnly(from);
  sunrealtype* dst = SerialOnly(to);
  if (src != nullptr && dst != nullptr && NV_LENGTH_S(from) == NV_LENGTH_S(to)) {
    return CopyFiniteData(src, dst, NV_LENGTH_S(from));
  }
  N_VScale(1, from, to);
  return IsFinite(to);
}

bool CopyPairFiniteAny(N_Vector x, N_Vector v, N_Vector xout, N_Vector vout, bool serial) {
  if (!serial) return CopyFinite(x, xout) & CopyFinite(v, vout);
  const sunindextype n = NV_LENGTH_S(x);
  return CopyFiniteData(NV_DATA_S(x), NV_DATA_S(xout), n) &
         CopyFiniteData(NV_DATA_S(v), NV_DATA_S(vout), n);
}

bool CopyPairFiniteApart(N_Vector x, N_Vector v, N_Vector xout, N_Vector vout) {
  return CopyPairFinite(x, v, xout, vout);
}

bool AllFinite(N_Vector v) {
  const sunrealtype* data = SerialOnly(v);
  return data != nullptr ? FiniteData(data, NV_LENGTH_S(v)) : IsFinite(v);
}

void PreparePlan(bool serial_allowed, KernelPlan* kp) {
  kp->serial = serial_allowed && BuildFusedPlan(kp->plan, {}, &kp->fused);
}

namespace {

bool SameTerms(const UpdatePlan& a, const UpdatePlan& b) {
  if (a.n != b.n) return false;
  for (int k = 0; k < a.n; ++k) {
    const Combo& x = a.combos[k];
    const Combo& y = b.combos[k];
    if (x.m != y.m || x.old != y.old || x.out != y.out || x.level != y.level ||
        x.lead_old != y.lead_old) {
      return false;
    }
    if (!std::equal(x.X, x.X + x.m, y.X)) return false;
  }
  return true;
}

}  // namespace

bool RefreshPlanCoefficients(const UpdatePlan& plan, KernelPlan* kp) {
  if (!SameTerms(plan, kp->plan)) return false;
  bool same_forms = true;
  for (int k = 0; k < plan.n; ++k) {
    const Combo& cb = plan.combos[k];
    std::copy(cb.c, cb.c + cb.m, kp->plan.combos[k].c);
    if (!kp->serial) continue;
    FusedTerms& tk = kp->fused.terms[k];
    std::copy(cb.c, cb.c + cb.m, tk.c + (tk.lead_old ? 1 : 0));  // the accumulated term's 1 stays
    if (kp->fused.shape != 0) PairWeights(&tk);  // only the shaped kernels read the pairs
    same_forms = same_forms && FormOf(tk.m, tk.c) == tk.form;
  }
  return same_forms;
}

void RunPlan(const KernelPlan& kp, sunindextype n) {
  if (kp.serial) {
    UpdateSerial(kp.fused, n);
  } else {
    UpdateReference(kp.plan, {});
  }
}

}  // namespace ceode
