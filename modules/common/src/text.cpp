#include <carenav/common/text.h>

#include <cstdio>

namespace carenav {

std::string formatFixed(double v, int prec) {
  char b[48];
  std::snprintf(b, sizeof b, "%.*f", prec, v);
  return b;
}

}  // namespace carenav
