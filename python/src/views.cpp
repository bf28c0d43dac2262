// numpy views of CEODE's N_Vector and SUNDenseMatrix data: no copy per callback. A view is
// made once per data pointer and kept; the cache is small because CEODE hands the callbacks
// the same few vectors at every step.
#include <nvector/nvector_serial.h>

#include <string>

#include "ceode_py.hpp"

namespace ceode_py {

namespace {

constexpr size_t kMaxViews = 64;  // beyond this the cache starts again (a bound, not a size)

}  // namespace

const py::array* ViewCache::Find(const sunrealtype* data, sunindextype rows,
                                 sunindextype cols) const {
  for (const Entry& e : entries_) {
    if (e.data == data && e.rows == rows && e.cols == cols) return &e.view;
  }
  return nullptr;
}

py::array ViewCache::Add(py::array view, sunrealtype* data, sunindextype rows, sunindextype cols) {
  if (!writable_) view.attr("flags").attr("writeable") = false;  // f must not change x or v
  if (entries_.size() >= kMaxViews) entries_.clear();
  entries_.push_back(Entry{data, rows, cols, view});
  return view;
}

py::array ViewCache::Vector(sunrealtype* data, sunindextype n) {
  if (const py::array* found = Find(data, n, 0)) return *found;
  // A base object (None) makes numpy borrow the data instead of copying it.
  const std::vector<py::ssize_t> shape{static_cast<py::ssize_t>(n)};
  const std::vector<py::ssize_t> strides{static_cast<py::ssize_t>(sizeof(sunrealtype))};
  py::array view(py::dtype::of<sunrealtype>(), shape, strides, data, py::none());
  return Add(view, data, n, 0);
}

py::array ViewCache::Matrix(sunrealtype* data, sunindextype rows, sunindextype cols) {
  if (const py::array* found = Find(data, rows, cols)) return *found;
  const auto r = static_cast<py::ssize_t>(rows), c = static_cast<py::ssize_t>(cols);
  const auto item = static_cast<py::ssize_t>(sizeof(sunrealtype));
  const std::vector<py::ssize_t> shape{r, c}, strides{item, item * r};
  py::array view(py::dtype::of<sunrealtype>(), shape, strides, data, py::none());
  return Add(view, data, rows, cols);
}

py::array_t<sunrealtype> CopyVector(N_Vector v) {
  const sunindextype n = N_VGetLength(v);
  py::array_t<sunrealtype> out(static_cast<py::ssize_t>(n));
  const sunrealtype* d = N_VGetArrayPointer(v);
  std::copy(d, d + n, out.mutable_data());
  return out;
}

RealArray AsVector(py::handle obj, const char* what, sunindextype n) {
  py::array arr = py::array::ensure(obj);
  if (!arr) throw py::type_error(std::string(what) + " must be a 1-D array of floats.");
  if (arr.dtype().kind() != 'f' && arr.dtype().kind() != 'i' && arr.dtype().kind() != 'u') {
    throw py::type_error(std::string(what) + " must hold real numbers, not dtype " +
                         py::str(arr.dtype()).cast<std::string>() + ".");
  }
  if (arr.ndim() != 1) {
    throw py::value_error(std::string(what) + " must be 1-D; it has " + std::to_string(arr.ndim()) +
                          " dimensions.");
  }
  if (n >= 0 && arr.shape(0) != n) {
    throw py::value_error(std::string(what) + " has length " + std::to_string(arr.shape(0)) +
                          "; expected " + std::to_string(n) + ".");
  }
  if (arr.shape(0) < 1) throw py::value_error(std::string(what) + " is empty.");
  return RealArray::ensure(arr);
}

}  // namespace ceode_py
