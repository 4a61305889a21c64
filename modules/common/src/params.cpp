#include <carenav/common/params.h>
#include <carenav/common/text.h>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

namespace carenav {

std::string trim(const std::string& s) {
  const char* ws = " \t\r\n";
  const auto b = s.find_first_not_of(ws);
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(ws);
  return s.substr(b, e - b + 1);
}

std::string formatReal(double v) {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  return formatGeneral(v, 10);
}

double parseReal(const std::string& text) {
  const std::string t = trim(text);
  if (t.empty()) throw ParamValueError("empty value, expected a number");
  if (const auto v = parseNumber(t)) return *v;
  if (parseNumber(t, NonFinite::Allow)) throw ParamValueError("not a finite number");
  throw ParamValueError("not a number");
}

long parseInteger(const std::string& text) {
  const std::string t = trim(text);
  if (t.empty()) throw ParamValueError("empty value, expected a whole number");
  errno = 0;
  char* end = nullptr;
  const long v = std::strtol(t.c_str(), &end, 10);
  if (end != t.c_str() + t.size() || errno == ERANGE) throw ParamValueError("not a whole number");
  return v;
}

bool parseBool(const std::string& text) {
  const std::string t = trim(text);
  if (t == "true" || t == "1" || t == "yes" || t == "on") return true;
  if (t == "false" || t == "0" || t == "no" || t == "off") return false;
  throw ParamValueError("not a boolean");
}

std::vector<Point2> parsePolygon(const std::string& text) {
  std::vector<Point2> poly;
  std::istringstream is(text);
  std::string tok;
  while (is >> tok) {
    const auto comma = tok.find(',');
    if (comma == std::string::npos || tok.find(',', comma + 1) != std::string::npos)
      throw ParamValueError("vertex '" + tok + "' is not of the form x,y");
    Point2 p;
    try {
      p.x = parseReal(tok.substr(0, comma));
      p.y = parseReal(tok.substr(comma + 1));
    } catch (const ParamValueError&) {
      throw ParamValueError("vertex '" + tok + "' is not of the form x,y");
    }
    poly.push_back(p);
  }
  if (poly.size() < 3)
    throw ParamValueError("a polygon needs at least 3 vertices \"x1,y1 x2,y2 x3,y3\"");
  double area2 = 0;
  for (size_t i = 0; i < poly.size(); ++i) {
    const auto& a = poly[i];
    const auto& b = poly[(i + 1) % poly.size()];
    area2 += a.x * b.y - b.x * a.y;
  }
  if (std::abs(area2) < 1e-9) throw ParamValueError("the polygon has zero area");
  return poly;
}

std::string formatPolygon(const std::vector<Point2>& poly) {
  std::string s;
  for (const auto& p : poly) {
    if (!s.empty()) s += ' ';
    s += formatReal(p.x) + "," + formatReal(p.y);
  }
  return s;
}

std::string ParamSpec::typeName() const {
  switch (type) {
    case ParamType::Real:
      return "real";
    case ParamType::Integer:
      return "integer";
    case ParamType::Bool:
      return "bool";
    case ParamType::Text:
      return "text";
    case ParamType::Choice:
      return "choice";
    case ParamType::Polygon:
      return "polygon";
  }
  return "?";
}

std::string ParamSpec::allowedText() const {
  const std::string u = unit.empty() ? "" : " " + unit;
  switch (type) {
    case ParamType::Real:
      return "a real number in [" + formatReal(min) + ", " + formatReal(max) + "]" + u;
    case ParamType::Integer:
      return "a whole number in [" + formatReal(min) + ", " + formatReal(max) + "]" + u;
    case ParamType::Bool:
      return "true or false";
    case ParamType::Text:
      return "any text";
    case ParamType::Choice: {
      std::string s = "one of";
      for (size_t i = 0; i < choices.size(); ++i) s += (i ? ", " : " ") + choices[i];
      return s;
    }
    case ParamType::Polygon:
      return "a polygon \"x1,y1 x2,y2 x3,y3 ...\" (>= 3 vertices)" + u;
  }
  return "";
}

}  // namespace carenav
