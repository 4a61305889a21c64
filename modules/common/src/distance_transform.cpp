#include <carenav/common/distance_transform.h>

#include <cstddef>
#include <limits>

namespace carenav {

namespace {

/** 1D squared distance transform of n samples of f (stride apart): the lower
 *  envelope of the parabolas (q - p)^2 + f(p) rooted at the finite samples;
 *  all infinite when no sample is finite. v (n) and z (n + 1) are scratch. */
template <class Real>
void dt1d(const Real* f, int n, int stride, Real* out, int* v, Real* z) {
  constexpr Real kInf = std::numeric_limits<Real>::infinity();
  int k = -1;
  for (int q = 0; q < n; ++q) {
    const Real fq = f[q * stride];
    if (fq == kInf) continue;
    if (k < 0) {
      k = 0;
      v[0] = q;
      z[0] = -kInf;
      z[1] = kInf;
      continue;
    }
    Real s = 0;
    while (true) {  // z[0] is -inf, so k stays >= 0
      const int r = v[k];
      s = ((fq + Real(q) * Real(q)) - (f[r * stride] + Real(r) * Real(r))) /
          (Real(2) * Real(q - r));
      if (s > z[k]) break;
      --k;
    }
    ++k;
    v[k] = q;
    z[k] = s;
    z[k + 1] = kInf;
  }
  if (k < 0) {
    for (int q = 0; q < n; ++q) out[q * stride] = kInf;
    return;
  }
  k = 0;
  for (int q = 0; q < n; ++q) {
    while (z[k + 1] < q) ++k;
    const Real d = Real(q - v[k]);
    out[q * stride] = d * d + f[v[k] * stride];
  }
}

}  // namespace

template <class Real>
std::vector<Real> squaredDistanceTransform(const std::vector<uint8_t>& source, int nx, int ny) {
  std::vector<Real> f(source.size()), g(source.size());
  for (std::size_t i = 0; i < source.size(); ++i)
    f[i] = source[i] ? std::numeric_limits<Real>::infinity() : Real(0);
  const int n = nx > ny ? nx : ny;
  std::vector<int> v(n + 1);
  std::vector<Real> z(n + 2);
  for (int x = 0; x < nx; ++x) dt1d(&f[x], ny, nx, &g[x], v.data(), z.data());  // columns
  for (int y = 0; y < ny; ++y)
    dt1d(&g[std::size_t(y) * nx], nx, 1, &f[std::size_t(y) * nx], v.data(), z.data());  // rows
  return f;
}

template std::vector<float> squaredDistanceTransform<float>(const std::vector<uint8_t>&, int, int);
template std::vector<double> squaredDistanceTransform<double>(const std::vector<uint8_t>&, int,
                                                              int);

}  // namespace carenav
