// The method: the named parameter sets (docs/theory.md section 5), the step's coefficients from
// (degree, params, h) and its update formula (section 2), the Taylor weights and finite-
// difference weights every other part of the library builds on. Pure arithmetic and N_Vector
// combinations on the history; no state of a run is kept here.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <utility>

#include "ceode_kernels.hpp"

namespace ceode {
namespace {

// Named parameter sets (docs/theory.md section 5): alpha, beta, gamma, zeta, then the stability
// limit Omega_max, the default number of PC corrections and the order in x (all derived by the
// library's own routines and checked against them by the tests). Measured properties (orders,
// stability limits) are in docs/stability.md and the tests.
const MethodSet kMethodSets[] = {
    {"G3_CD", 3, {1.0, 0.5}, 2.0, 1, 2},
    {"G3_A43", 3, {4.0 / 3.0, 0.5}, 1.5491933384830241, 1, 2},
    {"G3_A2", 3, {2.0, 0.5}, 1.1547005383792901, 1, 2},
    {"G4_A54", 4, {5.0 / 4.0, 1.0 / 3.0, 0.5}, 0.0, 2, 4},
    {"G4_A14", 4, {1.0 / 4.0, 1.0 / 3.0, 0.5}, 1.2649110640675025, 1, 3},
    {"G4_A34", 4, {3.0 / 4.0, 1.0 / 3.0, 0.5}, 1.7320508139458268, 1, 3},
    {"G5", 5, {4.0 / 5.0, 1.0, 1.0, 1.0}, 0.0, 2, 4},
    {"G5_TOP", 5, {1.62, 1.03522, 1.0291293, 1.016}, 0.068165690514902844, 2, 3},
    {"G5_ONES", 5, {1.0, 1.0, 1.0, 1.0}, 0.0, 2, 4},
    // Sets found by `ceode-stability find` (commands in docs/stability.md). G5_O4, order 4 in
    // x and x', keeps 98.5 % of central differences' interval (1.97 of 2), under damping too.
    {"G5_O4",
     5,
     {0.92577028540744155, 9.9999972798814163, 6.878731145481118, 0.63619887668052599},
     1.970651340728419,
     2,
     4},
    {"G6_O5",
     6,
     {7.8581049690442608, 3.2003060015391878, 2.306472520152492, 1.445972372099134,
      0.78920709629572905},
     0.80495242331772077,
     2,
     5},
    {"G6_O6",
     6,
     {2.438146987413893, 1.260773492352264, 1.0359340008566345, 0.84442784269433835,
      0.57681936136099354},
     0.066156247720114997,
     2,
     6},
    {"G7_O7",
     7,
     {19.362993681325158, 15.310841926671563, 8.7099568711498723, 3.9685609709725753,
      2.3539640770647496, 0.90130820250696653},
     1.0320137727279115,
     2,
     7},
    {"G8_O8",
     8,
     {399.99982239054896, 278.28678067794129, 134.15990720943549, 51.039413540261052,
      20.827940678986256, 6.8588048481939303, 2.805527440772015},
     0.98912640770612792,
     2,
     8},
};

}  // namespace

sunrealtype Factorial(int n) {
  sunrealtype r = 1;
  for (int i = 2; i <= n; ++i) r *= i;
  return r;
}

// Weights of the derivatives of orders 0..q on the nodes x[0..m-1] at 0 (Fornberg 1988): the
// recursion builds every lower order on the way, and each order's weights do not depend on
// the higher ones, so one call serves every order with the numbers of separate calls.
void FornbergTable(int q, int m, const sunrealtype* x, sunrealtype (*w)[2 * kMaxDegree + 1]) {
  sunrealtype C[2 * kMaxDegree + 1][kMaxDegree] = {};
  C[0][0] = 1;
  sunrealtype c1 = 1;
  for (int i = 1; i < m; ++i) {
    sunrealtype c2 = 1;
    const int mn = std::min(i, q);
    for (int j = 0; j < i; ++j) {
      const sunrealtype c3 = x[i] - x[j];
      c2 *= c3;
      for (int k = mn; k >= 0; --k) {
        if (j == i - 1) {
          C[i][k] = c1 / c2 * ((k > 0 ? k * C[i - 1][k - 1] : 0) - x[i - 1] * C[i - 1][k]);
        }
      }
      for (int k = mn; k >= 0; --k) {
        C[j][k] = (x[i] * C[j][k] - (k > 0 ? k * C[j][k - 1] : 0)) / c3;
      }
    }
    c1 = c2;
  }
  for (int k = 0; k <= q; ++k) {
    for (int i = 0; i < m; ++i) w[k][i] = C[i][k];
  }
}

void FornbergWeights(int q, int m, const sunrealtype* x, sunrealtype* w) {
  sunrealtype table[kMaxDegree][2 * kMaxDegree + 1];
  FornbergTable(q, m, x, table);
  std::copy(table[q], table[q] + m, w);
}

const MethodSet* FindMethodSet(const char* name) {
  if (name == nullptr) return nullptr;
  for (const MethodSet& m : kMethodSets) {
    if (std::strcmp(m.name, name) == 0) return &m;
  }
  return nullptr;
}

const MethodSet* NamedSetWithParams(int degree, const sunrealtype* params) {
  for (const MethodSet& m : kMethodSets) {
    if (m.degree == degree && std::equal(params, params + degree - 1, m.params.begin())) return &m;
  }
  return nullptr;
}

int NumMethodSets() { return static_cast<int>(sizeof(kMethodSets) / sizeof(kMethodSets[0])); }

const MethodSet& MethodSetAt(int index) { return kMethodSets[index]; }

namespace {

// The step's coefficients from its Taylor weights co->tw, for degree D (a constant, so that the
// loops unroll: the adaptive step forms them at every change of h).
template <int D>
void StepCoeffsOf(const sunrealtype* p, sunrealtype h, bool products, StepCoeffs* co) {
  sunrealtype* tw = co->tw;  // h^i / i!
  if (products) {
    tw[0] = 1;  // TaylorWeightsByProducts' values
    for (int i = 1; i < D; ++i) tw[i] = tw[i - 1] * h / i;
  } else {
    TaylorWeights(h, D, tw);
  }
  // The predictor's weights, once per h: every step reads them (PredictAccel, SolvePC).
  std::copy(tw, tw + D - 2, co->pred);
  // Lower derivatives k = 1..d-2: Taylor from t-h with the top term blended by p_k (added to
  // the entry's zero, so that a zero term keeps the sum's sign of zero).
#pragma GCC unroll 8
  for (int k = 1; k <= D - 2; ++k) {
#pragma GCC unroll 8
    for (int i = 0; i <= D - 2 - k; ++i) co->T[k][k + i] = tw[i];
    const sunrealtype top = tw[D - 1 - k];
    co->T[k][D - 1] = SUN_RCONST(0.0) + top * (1 - p[k]);
    co->c[k] = top * p[k];
  }
  if (D == 3) co->c[2] = 1;  // D_2 is the top derivative itself
  co->c[D - 1] = 1;
  co->kappa = co->c[1] / co->c[2];
  for (int j = 1; j < D; ++j) co->V0[j] = co->T[1][j] - co->kappa * co->T[2][j];
  // Position: Taylor from t with the top term blended by p_0.
  for (int i = 1; i <= D - 2; ++i) co->w[i] = tw[i];
  const sunrealtype top = tw[D - 1];
  co->wz_old = top * (1 - p[0]);
  co->wz_new = top * p[0];
  sunrealtype cx = co->wz_new;
  for (int i = 1; i <= D - 2; ++i) cx += co->w[i] * co->c[i];
  co->mu = cx / co->c[2];
}

using StepCoeffsFn = void (*)(const sunrealtype*, sunrealtype, bool, StepCoeffs*);
template <std::size_t... I>
constexpr std::array<StepCoeffsFn, sizeof...(I)> StepCoeffsTable(std::index_sequence<I...> /*d*/) {
  return {&StepCoeffsOf<static_cast<int>(I) + kMinDegree>...};
}
// By the degree d = kMinDegree .. kMaxDegree.
constexpr auto kStepCoeffsFns =
    StepCoeffsTable(std::make_index_sequence<kMaxDegree - kMinDegree + 1>{});

}  // namespace

// d = kMinDegree .. kMaxDegree (validated where the degree enters: CEodeSetMethod, the analyses).
void ComputeStepCoeffs(int d, const sunrealtype* p, sunrealtype h, StepCoeffs* co, bool products) {
  // Another h of the same degree rewrites the same entries: the zeros stay (StepCoeffs::degree).
  if (co->degree != d) {
    *co = StepCoeffs{};
    co->degree = d;
  }
  co->h = h;
  kStepCoeffsFns[d - kMinDegree](p, h, products, co);
}

// Every Taylor polynomial of the library (step coefficients, predictors, starts, dense output)
// takes its weights from here.
// The first two weights are exactly 1 and s (pow(s, 0) and pow(s, 1) are exact): no pow call.
void TaylorWeights(sunrealtype s, int m, sunrealtype* w) {
  for (int i = 0; i < m; ++i) w[i] = i == 0 ? 1 : (i == 1 ? s : std::pow(s, i) / Factorial(i));
}

void TaylorWeightsByProducts(sunrealtype s, int m, sunrealtype* w) {
  for (int i = 0; i < m; ++i) w[i] = i == 0 ? 1 : w[i - 1] * s / i;
}

void PredictAccel(const CEodeMemRec* ce, N_Vector a) {
  const int d = ce->degree;
  N_VLinearCombination(d - 2, const_cast<sunrealtype*>(ce->co.pred),
                       const_cast<N_Vector*>(ce->D + 2), a);
}

void VelocityOffset(int d, const StepCoeffs& co, N_Vector* D, N_Vector V0) {
  N_VLinearCombination(d - 1, const_cast<sunrealtype*>(co.V0 + 1), D + 1, V0);
}

// The update after the solve: z = (a - B_2)/c_2 (d = 3: z is a itself), the
// lower derivatives from the history and z, then the position increment.
void BuildUpdatePlan(int d, const StepCoeffs& co, N_Vector* D, N_Vector* Dn, N_Vector xnext,
                     N_Vector xnew, UpdatePlan* plan) {
  plan->n = 0;
  N_Vector a = Dn[2];
  N_Vector z = Dn[d - 1];
  if (d > 3) {
    Combo& cb = plan->combos[plan->n++];
    cb = Combo{};
    cb.Add(1 / co.c[2], a);
    for (int j = 2; j < d; ++j) cb.Add(-co.T[2][j] / co.c[2], D[j]);
    cb.out = z;
  }
  for (int k = 1; k <= d - 2; ++k) {
    if (k == 2) continue;  // D_2(t) = a exactly
    Combo& cb = plan->combos[plan->n++];
    cb = Combo{};
    for (int j = k + 1; j < d; ++j) cb.Add(co.T[k][j], D[j]);
    cb.Add(co.c[k], z);
    cb.old = D[k];
    cb.level = k;
    cb.out = Dn[k];
  }
  Combo& cb = plan->combos[plan->n++];
  cb = Combo{};
  for (int i = 1; i <= d - 2; ++i) cb.Add(co.w[i], Dn[i]);
  cb.Add(co.wz_old, D[d - 1]);
  cb.Add(co.wz_new, z);
  cb.old = xnext;
  cb.level = 0;
  cb.out = xnew;
}

}  // namespace ceode
