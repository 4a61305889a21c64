#include <carenav/common/text.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace carenav {

std::string formatFixed(double v, int prec) {
  char b[48];
  std::snprintf(b, sizeof b, "%.*f", prec, v);
  return b;
}

std::string formatGeneral(double v, int significant) {
  char b[48];
  std::snprintf(b, sizeof b, "%.*g", significant, v);
  return b;
}

std::optional<double> parseNumber(const std::string& text, NonFinite non_finite) {
  if (text.empty()) return std::nullopt;
  const char* b = text.c_str();
  char* e = nullptr;
  errno = 0;
  const double v = std::strtod(b, &e);
  if (e == b || e != b + text.size()) return std::nullopt;
  if (errno == ERANGE && non_finite != NonFinite::Saturate) return std::nullopt;
  if (non_finite == NonFinite::Refuse && !std::isfinite(v)) return std::nullopt;
  return v;
}

}  // namespace carenav
