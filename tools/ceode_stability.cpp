// ceode-stability: the linear stability of a CEODE parameter set, from the
// integrator's own step map (docs/theory.md section 9), beside the classic methods
// the paper compares with.
//
//   ceode-stability --method G4_A34 [--xi 0.05] [--omega-max 5] [--points 2000] [--csv out.csv]
//   ceode-stability --degree 5 --params 0.8,1,1,1
//   ceode-stability --method RK4            (also RK3, AB4, AB5, HHT, HHT:<alpha>)
//   ceode-stability --list [--xi 0.05]      (Omega_max of every named set and comparison)
//   ceode-stability --method G3_CD --matrix 1.5   (prints A(Omega))
//   ceode-stability find --degree 7 --order 7     (the set finder, tools/ceode_find.cpp)
#include <ceode/ceode.h>
#include <ceode/ceode_stability.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "ceode_find.hpp"
#include "classic_methods.hpp"

namespace {

struct Options {
  std::string method;
  int degree = 0;
  std::vector<sunrealtype> params;
  sunrealtype xi = 0;
  sunrealtype omega_max = 0;  // 0: 1.5 * the limit (at least 1), or 4 for comparisons
  int points = 2000;
  std::string csv;
  sunrealtype matrix_at = -1;
  bool list = false;
};

void Usage(FILE* out) {
  std::fprintf(out,
               "usage: ceode-stability (--method NAME | --degree D --params p0,p1,...) [--xi XI]\n"
               "                       [--omega-max W] [--points N] [--csv FILE] [--matrix OMEGA]\n"
               "       ceode-stability --list [--xi XI]\n"
               "NAME: a CEODE set (");
  for (int i = 0; i < CEodeGetNumMethods(); ++i) {
    std::fprintf(out, "%s%s", i ? ", " : "", CEodeGetMethodName(i));
  }
  std::fprintf(
      out,
      ") or a comparison method (RK3, RK4, AB4, AB5, HHT = HHT:-0.05, HHT:<alpha>).\n"
      "Prints Omega_max = largest omega*h with spectral radius <= 1 on (0, Omega_max] for\n"
      "x'' + 2 xi omega x' + omega^2 x = 0, and writes Omega,rho rows to FILE.\n");
}

bool ParseParams(const char* text, std::vector<sunrealtype>* out) {
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (end == item.c_str() || *end != '\0') return false;
    out->push_back(v);
  }
  return !out->empty();
}

bool ParseNumber(const char* text, double* v) {
  char* end = nullptr;
  *v = std::strtod(text, &end);
  return end != text && *end == '\0' && std::isfinite(*v);
}

// One method under analysis: a CEODE set or a comparison method.
class Method {
 public:
  bool classic = false;
  std::string name;
  int degree = 0;
  sunrealtype params[8] = {};

  bool Rho(sunrealtype Omega, sunrealtype xi, sunrealtype* rho) const {
    if (!classic) return CEodeSpectralRadius(degree, params, Omega, xi, rho) == CE_SUCCESS;
    Eigen::MatrixXd A;
    if (!ceode_tools::ClassicMatrix(name, Omega, xi, &A)) return false;
    *rho = A.eigenvalues().cwiseAbs().maxCoeff();
    return std::isfinite(*rho);
  }

  // CEODE sets use the library's analysis; the comparison methods have no
  // eigenvalue pinned to the unit circle for Omega > 0, so a plain tolerance
  // and the same grid-and-bisection scan serve them.
  bool Limit(sunrealtype xi, sunrealtype* Omega_max) const {
    if (!classic) return CEodeStabilityLimit(degree, params, xi, Omega_max) == CE_SUCCESS;
    constexpr sunrealtype kTol = 1e-12;
    constexpr sunrealtype kStep = 1e-3;
    constexpr int kMax = 20000;
    auto stable = [&](sunrealtype Om) {
      sunrealtype r = 0;
      return Rho(Om, xi, &r) && r <= 1 + kTol;
    };
    int k = 1;
    while (k <= kMax && stable(k * kStep)) ++k;
    if (k == 1) {
      *Omega_max = 0;
      return true;
    }
    if (k > kMax) {
      *Omega_max = kMax * kStep;
      return true;
    }
    sunrealtype lo = (k - 1) * kStep;
    sunrealtype hi = k * kStep;
    for (int it = 0; it < 60 && hi - lo > 1e-14 * hi; ++it) {
      const sunrealtype mid = 0.5 * (lo + hi);
      (stable(mid) ? lo : hi) = mid;
    }
    *Omega_max = lo;
    return true;
  }

  int RhsEvals() const { return classic ? ceode_tools::ClassicRhsEvals(name) : 1; }

  bool Matrix(sunrealtype Omega, sunrealtype xi, Eigen::MatrixXd* A) const {
    if (classic) return ceode_tools::ClassicMatrix(name, Omega, xi, A);
    std::vector<sunrealtype> a(degree * degree);
    if (CEodeAmplificationMatrix(degree, params, Omega, xi, a.data()) != CE_SUCCESS) return false;
    A->resize(degree, degree);
    for (int i = 0; i < degree; ++i) {
      for (int j = 0; j < degree; ++j) (*A)(i, j) = a[i * degree + j];
    }
    return true;
  }
};

bool MakeMethod(const std::string& name, Method* m) {
  m->name = name;
  Eigen::MatrixXd probe;
  if (ceode_tools::ClassicMatrix(name, 0.1, 0, &probe)) {
    m->classic = true;
    return true;
  }
  return CEodeGetMethodParams(name.c_str(), &m->degree, m->params, 8) == CE_SUCCESS;
}

void PrintLimit(const Method& m, sunrealtype xi) {
  sunrealtype lim = 0;
  if (!m.Limit(xi, &lim)) {
    std::printf("%-12s  analysis failed\n", m.name.c_str());
    return;
  }
  std::printf("%-12s %9.6f", m.name.c_str(), static_cast<double>(lim));
  if (lim >= 20) std::printf("  (stable on the whole scanned range, Omega <= 20)");
  if (lim == 0) {
    sunrealtype r1 = 0;
    m.Rho(0.1, xi, &r1);
    std::printf("  rho > 1 as Omega -> 0 (no stable (0, Omega]); rho(0.1) = %.9f",
                static_cast<double>(r1));
  }
  if (m.RhsEvals() > 1) {
    std::printf("  (%d f evaluations per step: %.4f per evaluation)", m.RhsEvals(),
                static_cast<double>(lim / m.RhsEvals()));
  }
  std::printf("\n");
}

int List(sunrealtype xi) {
  std::printf("Omega_max (largest omega*h with rho <= 1 on (0, Omega_max]), xi = %g\n",
              static_cast<double>(xi));
  for (int i = 0; i < CEodeGetNumMethods(); ++i) {
    Method m;
    if (!MakeMethod(CEodeGetMethodName(i), &m)) return 1;
    PrintLimit(m, xi);
  }
  for (const char* name : {"RK3", "RK4", "AB4", "AB5", "HHT"}) {
    Method m;
    MakeMethod(name, &m);
    PrintLimit(m, xi);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc > 1 && std::strcmp(argv[1], "find") == 0)
    return ceode_tools::FindMain(argc - 1, argv + 1);
  Options opt;
  for (int i = 1; i < argc; ++i) {
    const char* a = argv[i];
    const bool has_value = i + 1 < argc;
    double v = 0;
    if (std::strcmp(a, "--help") == 0 || std::strcmp(a, "-h") == 0) {
      Usage(stdout);
      return 0;
    } else if (std::strcmp(a, "--list") == 0) {
      opt.list = true;
    } else if (std::strcmp(a, "--method") == 0 && has_value) {
      opt.method = argv[++i];
    } else if (std::strcmp(a, "--degree") == 0 && has_value) {
      opt.degree = std::atoi(argv[++i]);
    } else if (std::strcmp(a, "--params") == 0 && has_value) {
      if (!ParseParams(argv[++i], &opt.params)) {
        std::fprintf(stderr, "ceode-stability: --params wants comma-separated numbers\n");
        return 2;
      }
    } else if (std::strcmp(a, "--xi") == 0 && has_value && ParseNumber(argv[i + 1], &v) && v >= 0) {
      opt.xi = v;
      ++i;
    } else if (std::strcmp(a, "--omega-max") == 0 && has_value && ParseNumber(argv[i + 1], &v) &&
               v > 0) {
      opt.omega_max = v;
      ++i;
    } else if (std::strcmp(a, "--points") == 0 && has_value) {
      opt.points = std::atoi(argv[++i]);
    } else if (std::strcmp(a, "--csv") == 0 && has_value) {
      opt.csv = argv[++i];
    } else if (std::strcmp(a, "--matrix") == 0 && has_value && ParseNumber(argv[i + 1], &v) &&
               v >= 0) {
      opt.matrix_at = v;
      ++i;
    } else {
      std::fprintf(stderr, "ceode-stability: bad or incomplete argument '%s'\n", a);
      Usage(stderr);
      return 2;
    }
  }
  if (opt.list) return List(opt.xi);

  Method m;
  if (!opt.method.empty()) {
    if (!MakeMethod(opt.method, &m)) {
      std::fprintf(stderr, "ceode-stability: unknown method '%s'\n", opt.method.c_str());
      Usage(stderr);
      return 2;
    }
  } else if (opt.degree > 0) {
    if (static_cast<int>(opt.params.size()) != opt.degree - 1 || opt.degree > 8) {
      std::fprintf(stderr, "ceode-stability: degree %d needs %d parameters (3 <= degree <= 8)\n",
                   opt.degree, opt.degree - 1);
      return 2;
    }
    m.name = "G" + std::to_string(opt.degree) + " custom";
    m.degree = opt.degree;
    for (int i = 0; i < opt.degree - 1; ++i) m.params[i] = opt.params[i];
  } else {
    Usage(stderr);
    return 2;
  }
  if (opt.points < 2) opt.points = 2;

  std::printf("method    %s", m.name.c_str());
  if (!m.classic) {
    std::printf("  (degree %d, params", m.degree);
    for (int i = 0; i < m.degree - 1; ++i) std::printf(" %.9g", static_cast<double>(m.params[i]));
    std::printf(")");
  }
  std::printf("\nxi        %g\n", static_cast<double>(opt.xi));
  int order_x = 0;
  int order_v = 0;
  if (!m.classic && CEodeMethodOrder(m.degree, m.params, &order_x, &order_v) == CE_SUCCESS) {
    std::printf("order     x %d, x' %d (CEodeMethodOrder)\n", order_x, order_v);
  }
  sunrealtype lim = 0;
  if (!m.Limit(opt.xi, &lim)) {
    std::fprintf(stderr, "ceode-stability: the analysis failed (bad parameters?)\n");
    return 1;
  }
  std::printf("Omega_max %.10g%s\n", static_cast<double>(lim),
              lim >= 20  ? "  (stable on the whole scanned range Omega <= 20)"
              : lim == 0 ? "  (rho > 1 arbitrarily close to Omega = 0: no stable interval)"
                         : "");
  for (sunrealtype Om : {0.1, 0.01, 0.001}) {
    sunrealtype r = 0;
    if (m.Rho(Om, opt.xi, &r)) {
      std::printf("rho(%g) = %.12f\n", static_cast<double>(Om), static_cast<double>(r));
    }
  }
  if (opt.matrix_at >= 0) {
    Eigen::MatrixXd A;
    if (!m.Matrix(opt.matrix_at, opt.xi, &A)) return 1;
    std::printf("A(%g) =\n", static_cast<double>(opt.matrix_at));
    for (int i = 0; i < A.rows(); ++i) {
      for (int j = 0; j < A.cols(); ++j) std::printf(" %22.15e", A(i, j));
      std::printf("\n");
    }
    const Eigen::VectorXcd ev = A.eigenvalues();
    std::printf("eigenvalues:");
    for (int i = 0; i < ev.size(); ++i) {
      std::printf(" (%.12g %+.12gi)", ev(i).real(), ev(i).imag());
    }
    std::printf("\n");
  }
  if (!opt.csv.empty()) {
    sunrealtype wmax = opt.omega_max;
    if (wmax <= 0)
      wmax = m.classic ? 4 : std::max<sunrealtype>(1, std::min<sunrealtype>(20, 1.5 * lim));
    FILE* f = std::fopen(opt.csv.c_str(), "w");
    if (f == nullptr) {
      std::fprintf(stderr, "ceode-stability: cannot write %s\n", opt.csv.c_str());
      return 1;
    }
    std::fprintf(f, "# %s, xi = %g, Omega_max = %.10g\nOmega,rho\n", m.name.c_str(),
                 static_cast<double>(opt.xi), static_cast<double>(lim));
    for (int i = 1; i <= opt.points; ++i) {
      const sunrealtype Om = wmax * i / opt.points;
      sunrealtype r = 0;
      if (!m.Rho(Om, opt.xi, &r)) {
        std::fclose(f);
        return 1;
      }
      std::fprintf(f, "%.8g,%.15g\n", static_cast<double>(Om), static_cast<double>(r));
    }
    std::fclose(f);
    std::printf("wrote %d points, Omega in (0, %g], to %s\n", opt.points, static_cast<double>(wmax),
                opt.csv.c_str());
  }
  return 0;
}
