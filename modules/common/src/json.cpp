#include <carenav/common/errors.h>
#include <carenav/common/json.h>

namespace carenav {

std::string dumpJson(const Json& j, bool pretty) {
  return j.dump(pretty ? 2 : -1, ' ', false, Json::error_handler_t::replace);
}

Json parseJson(const std::string& text, const std::string& origin) {
  try {
    return Json::parse(text);
  } catch (const Json::parse_error& e) {
    throw InputError(origin + ": not JSON (" + e.what() + ")");
  }
}

std::string JsonWriter::escape(const std::string& s) { return dumpJson(Json(s), false); }

JsonWriter& JsonWriter::key(const std::string& k) {
  key_ = k;
  return *this;
}

// While a container is open only it grows, never its parent, so the
// pointers in open_ stay valid.
Json* JsonWriter::place(Json v) {
  if (open_.empty()) {
    root_ = std::move(v);
    return &root_;
  }
  Json& c = *open_.back();
  if (c.is_array()) {
    c.push_back(std::move(v));
    return &c.back();
  }
  Json& slot = c[key_];
  slot = std::move(v);
  return &slot;
}

JsonWriter& JsonWriter::open(Json v) {
  open_.push_back(place(std::move(v)));
  return *this;
}

JsonWriter& JsonWriter::close() {
  open_.pop_back();
  return *this;
}

const std::string& JsonWriter::str() const {
  text_ = dumpJson(root_, pretty_);
  return text_;
}

}  // namespace carenav
