// The right-hand side trampolines CEODE calls: a Python f(t, x, v, out) on views of CEODE's
// own vectors, or a LinearStructure in C++ (with force(t, out) its only Python call), and
// the structure's velocity Jacobian -C. A Python exception is stashed (CallbackData::Guard)
// and the failing return stops CEODE; the Integrator raises it again.
#include <sunmatrix/sunmatrix_dense.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <algorithm>

#include "ceode_py.hpp"

namespace ceode_py {

namespace {

int StructureRhs(CallbackData* cb, sunrealtype t, N_Vector x, N_Vector v, N_Vector f) {
  const LinearStructure& s = *cb->structure;
  sunrealtype* out = N_VGetArrayPointer(f);
  std::fill(out, out + cb->n, 0.0);  // force writes only the loaded entries
  if (s.has_force()) {
    const int r = cb->Guard([&] {
      ++cb->python_calls;
      s.force()(t, cb->out.Vector(out, cb->n));
    });
    if (r != 0) return r;
  }
  s.Evaluate(N_VGetArrayPointer(x), N_VGetArrayPointer(v), out);
  return 0;
}

// -C, or -M^{-1} C when f returns accelerations (lumped masses m, empty otherwise).
inline sunrealtype MinusC(const Csr& C, const std::vector<sunrealtype>& m, sunindextype i,
                          sunindextype k) {
  return m.empty() ? -C.val[k] : -C.val[k] / m[i];
}

int DenseMinusC(const Csr& C, const std::vector<sunrealtype>& m, SUNMatrix J) {
  for (sunindextype i = 0; i < C.rows; ++i) {
    for (sunindextype k = C.ptr[i]; k < C.ptr[i + 1]; ++k) {
      SM_ELEMENT_D(J, i, C.idx[k]) = MinusC(C, m, i, k);
    }
  }
  return 0;
}

int SparseMinusC(const Csr& C, const std::vector<sunrealtype>& m, SUNMatrix J) {
  if (SUNSparseMatrix_SparseType(J) != CSR_MAT) return -1;
  const auto nnz = static_cast<sunindextype>(C.val.size());
  if (SUNSparseMatrix_NNZ(J) < nnz && SUNSparseMatrix_Reallocate(J, nnz) != 0) return -1;
  sunindextype* ptr = SUNSparseMatrix_IndexPointers(J);
  sunindextype* idx = SUNSparseMatrix_IndexValues(J);
  sunrealtype* val = SUNSparseMatrix_Data(J);
  std::copy(C.ptr.begin(), C.ptr.end(), ptr);
  // J may be larger than n x n (the saddle-point kind): its extra rows stay empty.
  for (sunindextype i = C.rows + 1; i <= SUNSparseMatrix_Rows(J); ++i) ptr[i] = nnz;
  std::copy(C.idx.begin(), C.idx.end(), idx);
  for (sunindextype i = 0; i < C.rows; ++i) {
    for (sunindextype k = C.ptr[i]; k < C.ptr[i + 1]; ++k) val[k] = MinusC(C, m, i, k);
  }
  return 0;
}

}  // namespace

int RhsFn(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, void* user_data) {
  auto* cb = static_cast<CallbackData*>(user_data);
  if (cb->structure) return StructureRhs(cb, t, x, v, f);
  return cb->Guard([&] {
    ++cb->python_calls;
    cb->rhs(t, cb->in.Vector(N_VGetArrayPointer(x), cb->n),
            cb->in.Vector(N_VGetArrayPointer(v), cb->n),
            cb->out.Vector(N_VGetArrayPointer(f), cb->n));
  });
}

int StructureVelJac(sunrealtype t, N_Vector x, N_Vector v, N_Vector f, SUNMatrix J, void* user_data,
                    N_Vector t1, N_Vector t2, N_Vector t3) {
  (void)t, (void)x, (void)v, (void)f, (void)t1, (void)t2, (void)t3;
  const auto* cb = static_cast<CallbackData*>(user_data);
  const Csr& C = cb->structure->damping();
  const std::vector<sunrealtype>& m = cb->structure->lumped_mass();
  if (SUNMatGetID(J) == SUNMATRIX_DENSE) return DenseMinusC(C, m, J);
  if (SUNMatGetID(J) == SUNMATRIX_SPARSE) return SparseMinusC(C, m, J);
  return -1;
}

}  // namespace ceode_py
