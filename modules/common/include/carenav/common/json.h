// JSON through nlohmann-json: summaries (`--json`, summary.json) are written
// and results passed between processes are read back with it.
#pragma once

#include <carenav/common/json_fwd.h>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace carenav {

/** The text of `j`: pretty (two-space indent) or compact. Non-finite numbers
 *  are written as null (JSON has no NaN/inf); bytes that are not UTF-8 are
 *  replaced (U+FFFD) instead of failing. */
std::string dumpJson(const Json& j, bool pretty = true);

/** Parses `text`; throws InputError "ORIGIN: not JSON (...)" when it is not. */
Json parseJson(const std::string& text, const std::string& origin);

/** A streaming front end over Json for summaries written field by field:
 *    JsonWriter j; j.beginObject(); j.key("n").value(3); j.endObject(); j.str(); */
class JsonWriter {
 public:
  explicit JsonWriter(bool pretty = true) : pretty_(pretty) {}
  JsonWriter& beginObject() { return open(Json::object()); }
  JsonWriter& endObject() { return close(); }
  JsonWriter& beginArray() { return open(Json::array()); }
  JsonWriter& endArray() { return close(); }
  JsonWriter& key(const std::string& k);
  JsonWriter& value(const std::string& v) { return put(v); }
  JsonWriter& value(const char* v) { return put(std::string(v)); }
  JsonWriter& value(double v) { return put(v); }
  JsonWriter& value(int64_t v) { return put(v); }
  JsonWriter& value(uint64_t v) { return put(v); }
  JsonWriter& value(int v) { return put(static_cast<int64_t>(v)); }
  JsonWriter& value(bool v) { return put(v); }
  JsonWriter& null() { return put(nullptr); }
  /** Inserts a whole value built elsewhere. */
  JsonWriter& value(const Json& v) { return put(v); }
  const Json& json() const { return root_; }
  /** The text written so far. */
  const std::string& str() const;

  /** `s` as a JSON string literal, quotes included. */
  static std::string escape(const std::string& s);

 private:
  Json* place(Json v);
  JsonWriter& put(Json v) {
    place(std::move(v));
    return *this;
  }
  JsonWriter& open(Json v);
  JsonWriter& close();
  Json root_;
  std::vector<Json*> open_;  // the containers being filled, innermost last
  std::string key_;
  bool pretty_;
  mutable std::string text_;
};

}  // namespace carenav
