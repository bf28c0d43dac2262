// LinearStructure: M a = force(t) - K x - C v with K, C (and a sparse M) copied to CSR
// arrays at construction, so the right-hand side runs in C++; force(t, out) is the only
// Python call per evaluation, and there is none without a force.
#include <cmath>
#include <string>

#include "ceode_py.hpp"

namespace ceode_py {

namespace {

using IndexArray = py::array_t<sunindextype, py::array::c_style | py::array::forcecast>;

void CheckFinite(const std::vector<sunrealtype>& v, const char* what) {
  for (sunrealtype a : v) {
    if (!std::isfinite(a)) throw py::value_error(std::string(what) + " has a non-finite entry.");
  }
}

// scipy.sparse in canonical CSR form (a copy when the user's matrix is not).
Csr SparseToCsr(py::handle matrix, const char* what) {
  py::object csr = matrix.attr("tocsr")();
  if (!csr.attr("has_canonical_format").cast<bool>()) {
    csr = csr.attr("copy")();
    csr.attr("sum_duplicates")();
  }
  py::array data = csr.attr("data");
  if (data.dtype().kind() == 'c') throw py::type_error(std::string(what) + " is complex.");
  Csr out;
  py::tuple shape = csr.attr("shape");
  out.rows = shape[0].cast<sunindextype>();
  out.cols = shape[1].cast<sunindextype>();
  IndexArray ptr = IndexArray::ensure(csr.attr("indptr"));
  IndexArray idx = IndexArray::ensure(csr.attr("indices"));
  RealArray val = RealArray::ensure(data);
  out.ptr.assign(ptr.data(), ptr.data() + ptr.size());
  out.idx.assign(idx.data(), idx.data() + idx.size());
  out.val.assign(val.data(), val.data() + val.size());
  return out;
}

Csr DenseToCsr(py::handle matrix, const char* what) {
  py::array arr = py::array::ensure(matrix);
  if (!arr || arr.ndim() != 2 || arr.dtype().kind() == 'c' || arr.dtype().kind() == 'O') {
    throw py::type_error(std::string(what) + " must be a scipy.sparse matrix or a 2-D array.");
  }
  RealArray a = RealArray::ensure(arr);
  Csr out;
  out.rows = a.shape(0);
  out.cols = a.shape(1);
  out.ptr.push_back(0);
  for (sunindextype i = 0; i < out.rows; ++i) {
    for (sunindextype j = 0; j < out.cols; ++j) {
      const sunrealtype aij = a.at(i, j);
      if (aij == 0.0) continue;
      out.idx.push_back(j);
      out.val.push_back(aij);
    }
    out.ptr.push_back(static_cast<sunindextype>(out.idx.size()));
  }
  return out;
}

void CheckSquare(const Csr& A, sunindextype n, const char* what) {
  if (A.rows != n || A.cols != n) {
    throw py::value_error(std::string(what) + " is " + std::to_string(A.rows) + " x " +
                          std::to_string(A.cols) + "; expected " + std::to_string(n) + " x " +
                          std::to_string(n) + ".");
  }
  CheckFinite(A.val, what);
}

Csr32 Narrow(const Csr& A, const char* what) {
  if (A.val.size() > static_cast<size_t>(INT32_MAX)) {
    throw py::value_error(std::string(what) + " has more than 2^31 - 1 nonzeros.");
  }
  Csr32 out;
  out.ptr.assign(A.ptr.begin(), A.ptr.end());
  out.idx.assign(A.idx.begin(), A.idx.end());
  out.val = A.val;
  return out;
}

// sum_k A_ik x_k for row i.
inline sunrealtype RowProduct(const int32_t* ptr, const int32_t* idx, const sunrealtype* val,
                              sunindextype i, const sunrealtype* x) {
  sunrealtype s = 0.0;
  for (int32_t k = ptr[i]; k < ptr[i + 1]; ++k) s += val[k] * x[idx[k]];
  return s;
}

}  // namespace

bool IsSparse(py::handle obj) { return py::hasattr(obj, "tocsr") && py::hasattr(obj, "nnz"); }

Csr ToCsr(py::handle matrix, const char* what) {
  if (IsSparse(matrix)) return SparseToCsr(matrix, what);
  return DenseToCsr(matrix, what);
}

LinearStructure::LinearStructure(py::object M, py::object K, py::object C, py::object force)
    : force_(std::move(force)) {
  K_ = ToCsr(K, "K");
  n_ = K_.rows;
  if (n_ < 1) throw py::value_error("K is empty.");
  CheckSquare(K_, n_, "K");
  if (!IsSparse(M) && py::array::ensure(M) && py::array::ensure(M).ndim() == 1) {
    RealArray m = AsVector(M, "M (lumped masses)", n_);
    mass_.assign(m.data(), m.data() + n_);
    for (sunrealtype mi : mass_) {
      if (!(mi > 0.0) || !std::isfinite(mi)) {
        throw py::value_error("M (lumped masses) must be positive and finite.");
      }
      inv_mass_.push_back(1.0 / mi);
    }
  } else {
    sparse_mass_ = ToCsr(M, "M");
    CheckSquare(sparse_mass_, n_, "M");
  }
  if (!C.is_none()) {
    C_ = ToCsr(C, "C");
    CheckSquare(C_, n_, "C");
  }
  k32_ = Narrow(K_, "K");
  if (C_.rows > 0) c32_ = Narrow(C_, "C");
  if (!force_.is_none() && !PyCallable_Check(force_.ptr())) {
    throw py::type_error("force must be a callable force(t, out) or None.");
  }
}

void LinearStructure::Evaluate(const sunrealtype* x, const sunrealtype* v, sunrealtype* out) const {
  const int32_t *kp = k32_.ptr.data(), *ki = k32_.idx.data();
  const sunrealtype* kv = k32_.val.data();
  const int32_t *cp = c32_.ptr.data(), *ci = c32_.idx.data();
  const sunrealtype* cv = c32_.val.data();
  const sunrealtype* im = inv_mass_.data();
  const bool damped = C_.rows > 0, lumped = !inv_mass_.empty();
  for (sunindextype i = 0; i < n_; ++i) {
    sunrealtype s = out[i] - RowProduct(kp, ki, kv, i, x);
    if (damped) s -= RowProduct(cp, ci, cv, i, v);
    out[i] = lumped ? s * im[i] : s;  // a product: a division costs several
  }
}

void RegisterStructure(py::module_& m) {
  py::class_<LinearStructure, std::shared_ptr<LinearStructure>>(
      m, "LinearStructure",
      "M a = force(t) - K x - C v, evaluated in C++ on CSR copies of K, C (and M).")
      .def(py::init<py::object, py::object, py::object, py::object>(), py::arg("M"), py::arg("K"),
           py::arg("C") = py::none(), py::arg("force") = py::none())
      .def_property_readonly("n", &LinearStructure::size, "The number of degrees of freedom.")
      .def_property_readonly("lumped", &LinearStructure::lumped,
                             "True when M is a 1-D array of lumped masses.")
      .def_property_readonly("damped", &LinearStructure::damped, "True when C is given.");
}

}  // namespace ceode_py
