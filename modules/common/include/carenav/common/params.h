// Declarative parameter tables: every module parameter struct lists its keys
// with type, unit, default and meaning, so profiles can be validated and
// documented (`carenav profile show`) from one place.
#pragma once

#include <functional>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace carenav {

enum class ParamType { Real, Integer, Bool, Text, Choice, Polygon };

struct Point2 {
  double x = 0, y = 0;
  bool operator==(const Point2& o) const { return x == o.x && y == o.y; }
};

/** Thrown by the value parsers; carries only what is wrong with the value.
 *  Profile adds file, line, section and key. */
class ParamValueError : public std::runtime_error {
 public:
  explicit ParamValueError(const std::string& what) : std::runtime_error(what) {}
};

/** Description of one key of a section. */
struct ParamSpec {
  std::string key;
  ParamType type = ParamType::Real;
  std::string unit;          ///< "" when dimensionless
  std::string default_text;  ///< default value as it would be written in the INI
  std::string meaning;
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  std::vector<std::string> choices;  ///< for ParamType::Choice

  std::string typeName() const;
  /** Human text of what is allowed, e.g. "a real number in [0, 3] m/s". */
  std::string allowedText() const;
};

// Value parsers (strict: the whole text must be consumed). Throw ParamValueError.
double parseReal(const std::string& text);
long parseInteger(const std::string& text);
bool parseBool(const std::string& text);
/** "x1,y1 x2,y2 x3,y3 ..." (at least 3 vertices, non-zero area). */
std::vector<Point2> parsePolygon(const std::string& text);
std::string formatReal(double v);
std::string formatPolygon(const std::vector<Point2>& poly);
std::string trim(const std::string& s);

/** Table of the keys of a parameter struct T. T must be default-constructible:
 *  the defaults shown to users are those of T{}.
 *
 *  Usage, in the struct:
 *    static const ParamTable<MyParams>& table() {
 *      static const auto t = ParamTable<MyParams>()
 *          .real("v_max", &MyParams::v_max, "m/s", 0, 3, "top forward speed");
 *      return t;
 *    }
 */
template <class T>
class ParamTable {
 public:
  using Check = std::function<std::optional<std::string>(const T&)>;

  ParamTable& real(const char* key, double T::*m, const char* unit, double lo, double hi,
                   const char* meaning) {
    ParamSpec s = make(key, ParamType::Real, unit, meaning);
    s.min = lo;
    s.max = hi;
    return add(
        std::move(s),
        [m, lo, hi](T& o, const std::string& v) {
          double x = parseReal(v);
          inRange(x, lo, hi);
          o.*m = x;
        },
        [m](const T& o) { return formatReal(o.*m); });
  }
  ParamTable& integer(const char* key, int T::*m, const char* unit, int lo, int hi,
                      const char* meaning) {
    ParamSpec s = make(key, ParamType::Integer, unit, meaning);
    s.min = lo;
    s.max = hi;
    return add(
        std::move(s),
        [m, lo, hi](T& o, const std::string& v) {
          long x = parseInteger(v);
          inRange(static_cast<double>(x), lo, hi);
          o.*m = static_cast<int>(x);
        },
        [m](const T& o) { return std::to_string(o.*m); });
  }
  ParamTable& flag(const char* key, bool T::*m, const char* meaning) {
    return add(
        make(key, ParamType::Bool, "", meaning),
        [m](T& o, const std::string& v) { o.*m = parseBool(v); },
        [m](const T& o) { return std::string(o.*m ? "true" : "false"); });
  }
  ParamTable& text(const char* key, std::string T::*m, const char* meaning) {
    return add(
        make(key, ParamType::Text, "", meaning), [m](T& o, const std::string& v) { o.*m = v; },
        [m](const T& o) { return o.*m; });
  }
  ParamTable& choice(const char* key, std::string T::*m, std::vector<std::string> choices,
                     const char* meaning) {
    ParamSpec s = make(key, ParamType::Choice, "", meaning);
    s.choices = choices;
    return add(
        std::move(s),
        [m, choices](T& o, const std::string& v) {
          for (const auto& c : choices)
            if (c == v) {
              o.*m = v;
              return;
            }
          throw ParamValueError("not an allowed value");
        },
        [m](const T& o) { return o.*m; });
  }
  ParamTable& polygon(const char* key, std::vector<Point2> T::*m, const char* unit,
                      const char* meaning) {
    return add(
        make(key, ParamType::Polygon, unit, meaning),
        [m](T& o, const std::string& v) { o.*m = parsePolygon(v); },
        [m](const T& o) { return formatPolygon(o.*m); });
  }
  /** A rule over several keys (e.g. range_min < range_max); returns the
   *  problem, or nothing when the struct is consistent. */
  ParamTable& check(Check c) {
    checks_.push_back(std::move(c));
    return *this;
  }

  const std::vector<ParamSpec>& specs() const { return specs_; }
  const ParamSpec* find(const std::string& key) const {
    for (const auto& s : specs_)
      if (s.key == key) return &s;
    return nullptr;
  }
  /** Parses and assigns; throws ParamValueError. Unknown keys throw too. */
  void set(T& obj, const std::string& key, const std::string& value) const {
    for (size_t i = 0; i < specs_.size(); ++i)
      if (specs_[i].key == key) return setters_[i](obj, trim(value));
    throw ParamValueError("unknown key '" + key + "'");
  }
  std::string get(const T& obj, const std::string& key) const {
    for (size_t i = 0; i < specs_.size(); ++i)
      if (specs_[i].key == key) return getters_[i](obj);
    throw ParamValueError("unknown key '" + key + "'");
  }
  /** Problems found by the cross-key rules. */
  std::vector<std::string> crossCheck(const T& obj) const {
    std::vector<std::string> out;
    for (const auto& c : checks_)
      if (auto p = c(obj)) out.push_back(*p);
    return out;
  }

 private:
  using Setter = std::function<void(T&, const std::string&)>;
  using Getter = std::function<std::string(const T&)>;

  static ParamSpec make(const char* key, ParamType type, const char* unit, const char* meaning) {
    ParamSpec s;
    s.key = key;
    s.type = type;
    s.unit = unit;
    s.meaning = meaning;
    return s;
  }
  static void inRange(double x, double lo, double hi) {
    if (!(x >= lo && x <= hi)) throw ParamValueError("out of range");
  }
  ParamTable& add(ParamSpec s, Setter set, Getter get) {
    s.default_text = get(T{});
    specs_.push_back(std::move(s));
    setters_.push_back(std::move(set));
    getters_.push_back(std::move(get));
    return *this;
  }

  std::vector<ParamSpec> specs_;
  std::vector<Setter> setters_;
  std::vector<Getter> getters_;
  std::vector<Check> checks_;
};

}  // namespace carenav
