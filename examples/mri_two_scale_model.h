/* -----------------------------------------------------------------------------
 * The two-scale model of examples/mri_two_scale.c, shared with
 * bench/sundials_interop/mri_inner_cost.c (one copy of the model and of its closed form):
 *     q'' = -omega^2 (q - s)            fast (the inner stepper)
 *     s'  = -lambda s + cos t           slow (MRIStep's explicit part)
 * First-order state y = (q, s, p, w), x = (q, s), v = (p, w); w = 0 throughout
 * (s moves only through the MRI forcing of the x-part).
 * Closed form, with a = lambda/(1+lambda^2), b = 1/(1+lambda^2), C = s0 - a:
 *     s(t) = C e^{-lambda t} + a cos t + b sin t,
 *     q(t) = K e^{-lambda t} + M cos t + N sin t + A cos(omega t),
 * K = omega^2 C/(omega^2 + lambda^2), M = omega^2 a/(omega^2 - 1),
 * N = omega^2 b/(omega^2 - 1). A is the amplitude of the fast oscillation
 * present from the start (A = 0: the start lies on the slow manifold and the
 * fast mode is excited only by integration errors).
 * ---------------------------------------------------------------------------*/
#ifndef CEODE_EXAMPLES_MRI_TWO_SCALE_MODEL_H
#define CEODE_EXAMPLES_MRI_TWO_SCALE_MODEL_H

#include <arkode/arkode_butcher.h>
#include <math.h>
#include <nvector/nvector_serial.h>

#define TWO_SCALE_LAMBDA 2.0
#define TWO_SCALE_S0 1.0

/* The model's parameters and the fast f counter (the user data of the fast part). */
typedef struct {
  double omega;
  double amp;
  long nfast;
} TwoScale;

/* Closed-form solution: q, s and p = q' at t. */
static inline void two_scale_exact(const TwoScale* m, double t, double* q, double* s, double* p) {
  const double lam = TWO_SCALE_LAMBDA, w = m->omega, w2 = w * w;
  const double a = lam / (1 + lam * lam), b = 1 / (1 + lam * lam), C = TWO_SCALE_S0 - a;
  const double K = w2 * C / (w2 + lam * lam), M = w2 * a / (w2 - 1), N = w2 * b / (w2 - 1);
  const double e = exp(-lam * t);
  *s = C * e + a * cos(t) + b * sin(t);
  *q = K * e + M * cos(t) + N * sin(t) + m->amp * cos(w * t);
  *p = -lam * K * e - M * sin(t) + N * cos(t) - m->amp * w * sin(w * t);
}

/* y = (q, s, p, w) at t from the closed form. */
static inline void two_scale_state(const TwoScale* m, double t, N_Vector y) {
  two_scale_exact(m, t, &NV_Ith_S(y, 0), &NV_Ith_S(y, 1), &NV_Ith_S(y, 2));
  NV_Ith_S(y, 3) = 0;
}

/* Max error of y at t: q, s, and p scaled by 1/omega (the size of q's fast part). */
static inline double two_scale_error(const TwoScale* m, double t, N_Vector y) {
  double q, s, p;
  two_scale_exact(m, t, &q, &s, &p);
  const double e = fmax(fabs(NV_Ith_S(y, 0) - q), fabs(NV_Ith_S(y, 1) - s));
  return fmax(e, fabs(NV_Ith_S(y, 2) - p) / m->omega);
}

/* Fast acceleration for CEODE: x = (q, s); data is the TwoScale. */
static inline int two_scale_fast_accel(sunrealtype t, N_Vector x, N_Vector v, N_Vector f,
                                       void* data) {
  TwoScale* m = (TwoScale*)data;
  (void)t;
  (void)v;
  ++m->nfast;
  NV_Ith_S(f, 0) = -m->omega * m->omega * (NV_Ith_S(x, 0) - NV_Ith_S(x, 1));
  NV_Ith_S(f, 1) = 0;
  return 0;
}

/* The same fast part in first-order form (ARKStep): y = (q, s, p, w). */
static inline int two_scale_fast_first_order(sunrealtype t, N_Vector y, N_Vector ydot, void* data) {
  TwoScale* m = (TwoScale*)data;
  (void)t;
  ++m->nfast;
  NV_Ith_S(ydot, 0) = NV_Ith_S(y, 2);
  NV_Ith_S(ydot, 1) = NV_Ith_S(y, 3);
  NV_Ith_S(ydot, 2) = -m->omega * m->omega * (NV_Ith_S(y, 0) - NV_Ith_S(y, 1));
  NV_Ith_S(ydot, 3) = 0;
  return 0;
}

/* Slow part of y' for MRIStep. */
static inline int two_scale_slow_rhs(sunrealtype t, N_Vector y, N_Vector ydot, void* data) {
  (void)data;
  N_VConst(0, ydot);
  NV_Ith_S(ydot, 1) = -TWO_SCALE_LAMBDA * NV_Ith_S(y, 1) + cos(t);
  return 0;
}

/* Classic RK4 (ARKODE has no such built-in table): the ARKStep inner stepper compared. */
static inline ARKodeButcherTable two_scale_rk4_table(void) {
  const sunrealtype c[4] = {0, 0.5, 0.5, 1};
  const sunrealtype A[16] = {0, 0, 0, 0, 0.5, 0, 0, 0, 0, 0.5, 0, 0, 0, 0, 1, 0};
  const sunrealtype b[4] = {1.0 / 6, 1.0 / 3, 1.0 / 3, 1.0 / 6};
  return ARKodeButcherTable_Create(4, 4, 0, (sunrealtype*)c, (sunrealtype*)A, (sunrealtype*)b,
                                   NULL);
}

#endif
