// Numbers as text: the project's one strict number parser and one
// fixed-point formatter.
#pragma once

#include <optional>
#include <string>

namespace carenav {

/** `v` with `prec` digits after the point ("%.*f"); "nan", "inf" as printf writes them. */
std::string formatFixed(double v, int prec = 3);

/** `v` with at most `significant` significant digits, the shorter of fixed
 *  and exponent notation ("%.*g"). */
std::string formatGeneral(double v, int significant = 6);

/** What parseNumber takes besides finite numbers in range. */
enum class NonFinite {
  Refuse,   ///< nothing else
  Allow,    ///< "inf" and "nan" as written; out of range is still refused
  Saturate  ///< also out of range, as strtod saturates it (1e400: inf, 1e-400: 0)
};

/** The number that is the whole of `text` (strtod's syntax in the C locale:
 *  leading blanks are skipped, nothing may follow), or nothing when the text
 *  is empty, has anything after the number, is out of the range of a double
 *  (1e400, 1e-400) or is inf or nan, unless `non_finite` says otherwise. Callers word their own
 *  messages. */
std::optional<double> parseNumber(const std::string& text,
                                  NonFinite non_finite = NonFinite::Refuse);

}  // namespace carenav
