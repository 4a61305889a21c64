// A small JSON writer for summaries (`--json`, summary.json).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace carenav {

/** Streaming JSON writer with commas and escaping handled:
 *    JsonWriter j; j.beginObject(); j.key("n").value(3); j.endObject(); j.str();
 *  Non-finite numbers are written as null (JSON has no NaN/inf). */
class JsonWriter {
 public:
  explicit JsonWriter(bool pretty = true) : pretty_(pretty) {}
  JsonWriter& beginObject();
  JsonWriter& endObject();
  JsonWriter& beginArray();
  JsonWriter& endArray();
  JsonWriter& key(const std::string& k);
  JsonWriter& value(const std::string& v);
  JsonWriter& value(const char* v) { return value(std::string(v)); }
  JsonWriter& value(double v);
  JsonWriter& value(int64_t v);
  JsonWriter& value(uint64_t v);
  JsonWriter& value(int v) { return value(static_cast<int64_t>(v)); }
  JsonWriter& value(bool v);
  JsonWriter& null();
  const std::string& str() const { return out_; }

  static std::string escape(const std::string& s);

 private:
  void beforeValue();
  void newline();
  std::string out_;
  std::vector<bool> first_;  // per open container: no element yet
  bool pretty_;
  bool after_key_ = false;
};

}  // namespace carenav
