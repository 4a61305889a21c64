// Numbers as text: the one fixed-point formatter of the project.
#pragma once

#include <string>

namespace carenav {

/** `v` with `prec` digits after the point ("%.*f"); "nan", "inf" as printf writes them. */
std::string formatFixed(double v, int prec = 3);

}  // namespace carenav
