// The step's update kernel (ceode_fused.cpp), private: an UpdatePlan of linear combinations run
// by the generic N_Vector reference, or on serial vectors by the fused backend (one sweep
// through memory), with the same operations in the same order, so bit for bit equal.
#ifndef CEODE_SRC_CEODE_FUSED_HPP_
#define CEODE_SRC_CEODE_FUSED_HPP_

#include "ceode_impl.hpp"

namespace ceode {

// z = sum c_i X_i with exactly the rounding of N_VScale / N_VLinearSum / N_VLinearCombination.
void Combine(int m, const sunrealtype* c, N_Vector* X, N_Vector z);

// Compensation vectors of the accumulated quantities (index = Combo::level), and the scratch
// vector the reference needs when compensating.
struct Compensation {
  bool on = false;
  N_Vector* comp = nullptr;
  N_Vector* compnew = nullptr;
  N_Vector tmp = nullptr;
};

// The reference: every combination of the plan, one N_Vector operation per term.
void UpdateReference(const UpdatePlan& plan, const Compensation& cs);
// The serial backend on the plan's raw-pointer form (vectors of length n): one pass over the
// vectors (entry by entry for small n). Returns the L1 norm of the last combination's output
// (the new position) for the growth check, summed in four interleaved partial sums, so it may
// differ from N_VL1Norm by rounding (n * unit round-off relative); the outputs are bitwise
// those of UpdateReference.
sunrealtype UpdateSerial(const FusedPlan& fp, sunindextype n);
// The kernel UpdateSerial runs on the plan at length n, for a caller that runs it many times.
using SerialKernelFn = sunrealtype (*)(const FusedPlan&, sunindextype);
SerialKernelFn SerialKernel(const FusedPlan& fp, sunindextype n);
// The raw-pointer form of a plan (vectors that expose their data). Returns false when some
// combination writes a vector it also reads, other than its own accumulated quantity without
// compensation (an in-place plan's, read entry by entry before it is written): the serial
// backend must not run that plan.
bool BuildFusedPlan(const UpdatePlan& plan, const Compensation& cs, FusedPlan* fp);

}  // namespace ceode

#endif  // CEODE_SRC_CEODE_FUSED_HPP_
