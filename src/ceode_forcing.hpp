// The forcing of a problem integrated in pieces (the MRI inner stepper, ceode_stepper.cpp).
// With r(t) = sum_k tau^k F_k, tau = (t - tshift) / tscale, in halves r = [r_x; r_v], the forced
// problem x' = v + r_x, v' = g(t, x, v) + r_v is integrated in second-order form in
// u = x' = v + r_x (docs/porting.md, "The forced inner problem"):
//   x'' = g(t, x, u - r_x) + r_v + r_x',
// where g is the memory's own right-hand side (BaseRhs): the user's f, or F of the first-order
// form. The forcing enters f's output, before any mass solve; with M != I it would have to be
// multiplied by M first, so the stepper takes M = I only.
#ifndef CEODE_SRC_CEODE_FORCING_HPP_
#define CEODE_SRC_CEODE_FORCING_HPP_

#include "ceode_impl.hpp"

namespace ceode {

constexpr int kMaxForcing = 10;  // MRI forcing polynomials have (order + 1) terms at most

// What a restart of the forced problem carries over from the end of the last run, while the
// state is not changed in between (docs/porting.md, "What a restart costs"): at t, the g parts
// g[k] = D_k - (r_v + r_x')^(k-2) of the history's derivatives D_2 .. D_{d-1} (the old x' in
// them) and r_x(t).
struct ForcedEnd {
  bool valid = false;
  int degree = 0;
  sunrealtype t = 0;
  N_Vector g[kMaxDegree] = {};
  N_Vector rx = nullptr;
  N_Vector jump = nullptr;  // CarryHistory's scratch: the jump of r_x, and x plus a multiple of it
  N_Vector xp = nullptr;
};

// Adapters::forcing, owned by the stepper. Fx, Fv are views of the two halves of F_k (the
// owner's); the vectors are the forcing's own, cloned when first needed.
struct Forcing {
  int n = 0;  // terms; 0: no forcing, CEODE evaluates BaseRhs itself
  sunrealtype tshift = 0;
  sunrealtype tscale = 1;
  N_Vector Fx[kMaxForcing] = {};
  N_Vector Fv[kMaxForcing] = {};
  N_Vector vg = nullptr;  // u - r_x inside the forced right-hand side
  ForcedEnd end;
};
void FreeForcing(Forcing* fc);

// Takes n <= kMaxForcing terms, the halves Fx[k], Fv[k] of F_k, and makes CEODE evaluate the
// forced form (n = 0: the unforced one). A bad tscale is reported and leaves no forcing.
int SetForcing(CEodeMemRec* ce, Forcing* fc, sunrealtype tshift, sunrealtype tscale, int n,
               const N_Vector* Fx, const N_Vector* Fv, const char* func);
// After a run that ended on a step at tcur: strips the forcing from the history into fc->end
// (fc->end.valid: whether it could; the history must be the explicit path's consistent one).
void KeepEnd(CEodeMemRec* ce, Forcing* fc);
// Whether a start at t0 (the memory's degree and step set) can carry fc->end over.
bool CanCarry(const CEodeMemRec* ce, const Forcing& fc, sunrealtype t0);
// D_2 .. D_{d-1} at (t0, x0, v0) from fc->end and the new forcing: a ResetOptions::history.
int CarryHistory(CEodeMemRec* ce, Forcing* fc, sunrealtype t0, N_Vector x0, N_Vector v0,
                 const char* func);
// out = a * base + s * r_x(t) (base may be null).
void ForcingX(const Forcing& fc, sunrealtype t, sunrealtype a, N_Vector base, sunrealtype s,
              N_Vector out);
// out = base + s * (r_v^(m)(t) + r_x^(m+1)(t)): the forcing's part of the m-th derivative of x''.
void ForcingAccel(const Forcing& fc, sunrealtype t, int m, N_Vector base, sunrealtype s,
                  N_Vector out);

}  // namespace ceode

#endif  // CEODE_SRC_CEODE_FORCING_HPP_
