#include <carenav/common/distance_transform.h>

#include <cstddef>
#include <limits>

namespace carenav {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/** 1D squared distance transform of n samples of f (stride apart): the lower
 *  envelope of the parabolas (q - p)^2 + f(p) rooted at the finite samples;
 *  all infinite when no sample is finite. v (n) and z (n + 1) are scratch. */
void dt1d(const double* f, int n, int stride, double* out, int* v, double* z) {
  int k = -1;
  for (int q = 0; q < n; ++q) {
    const double fq = f[q * stride];
    if (fq == kInf) continue;
    if (k < 0) {
      k = 0;
      v[0] = q;
      z[0] = -kInf;
      z[1] = kInf;
      continue;
    }
    double s = 0;
    while (true) {  // z[0] is -inf, so k stays >= 0
      const int r = v[k];
      s = ((fq + double(q) * q) - (f[r * stride] + double(r) * r)) / (2.0 * (q - r));
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
    const double d = q - v[k];
    out[q * stride] = d * d + f[v[k] * stride];
  }
}

}  // namespace

std::vector<double> squaredDistanceTransform(const std::vector<uint8_t>& source, int nx, int ny) {
  std::vector<double> f(source.size()), g(source.size());
  for (std::size_t i = 0; i < source.size(); ++i) f[i] = source[i] ? kInf : 0.0;
  const int n = nx > ny ? nx : ny;
  std::vector<int> v(n + 1);
  std::vector<double> z(n + 2);
  for (int x = 0; x < nx; ++x) dt1d(&f[x], ny, nx, &g[x], v.data(), z.data());  // columns
  for (int y = 0; y < ny; ++y)
    dt1d(&g[std::size_t(y) * nx], nx, 1, &f[std::size_t(y) * nx], v.data(), z.data());  // rows
  return f;
}

}  // namespace carenav
