// YAML through yaml-cpp: the library parses, this file checks carenav's line
// rules first (yaml_lines.cpp) and turns the library's nodes into Nodes that
// keep their line, refusing what the library lets through silently (a line
// without ':' taken as a key, a second document, duplicate keys, aliases
// that expand past the size of the file).
#include <carenav/common/yaml.h>

#include <yaml-cpp/yaml.h>

#include <string>

#include "yaml_lines.h"

namespace carenav::yaml {

const Node* Node::find(const std::string& key) const {
  for (const auto& [k, v] : map)
    if (k == key) return &v;
  return nullptr;
}

namespace {

/** The library's message in words closer to the file's author. */
std::string explain(const std::string& msg) {
  if (msg == YAML::ErrorMsg::END_OF_MAP || msg == YAML::ErrorMsg::MAP_VALUE)
    return "unexpected indentation, or a line that is not 'key: value' (" + msg + ")";
  if (msg == YAML::ErrorMsg::END_OF_SEQ || msg == YAML::ErrorMsg::BLOCK_ENTRY)
    return "a list item ('- ') out of line with the list (" + msg + ")";
  return msg;
}

/** The line of `text` holding `pos`, without its indentation. */
std::string lineAt(const std::string& text, size_t pos) {
  const size_t a = pos == 0 ? 0 : text.rfind('\n', pos - 1) + 1;  // npos + 1 == 0
  const size_t b = text.find('\n', pos);
  const std::string l = text.substr(a, b == std::string::npos ? std::string::npos : b - a);
  const size_t f = l.find_first_not_of(' '), e = l.find_last_not_of(" \r");
  return f == std::string::npos ? "" : l.substr(f, e - f + 1);
}

class Converter {
 public:
  Converter(const std::string& text, const std::string& origin, Duplicates dup)
      : text_(text),
        origin_(origin),
        dup_(dup),
        budget_(text.size() + 64),
        bom_(text.compare(0, 3, "\xEF\xBB\xBF") == 0 ? 3 : 0) {}

  Node node(const YAML::Node& y, int depth, int parent_line) {
    const int line = y.Mark().is_null() ? parent_line : y.Mark().line + 1;
    if (depth > kMaxDepth)
      fail(line, "nested deeper than " + std::to_string(kMaxDepth) + " levels");
    if (--budget_ < 0) fail(line, "aliases expand to more values than the file holds");
    if (y.IsMap()) return mapping(y, depth, line);
    Node n;
    n.line = line;
    if (y.IsSequence()) {
      n.kind = Node::Kind::Seq;
      for (const auto& item : y) n.seq.push_back(node(item, depth + 1, line));
    } else if (y.IsScalar()) {
      n.scalar = y.Scalar();
      n.quoted = y.Tag() == "!";
    } else {
      n.scalar = nullWord(y);
      if (n.scalar.empty()) n.line = parent_line;  // "key:" with nothing after it
    }
    return n;
  }

  [[noreturn]] void fail(int line, const std::string& what) const {
    throw InputError(origin_ + ":" + std::to_string(line) + ": " + what);
  }

 private:
  Node mapping(const YAML::Node& y, int depth, int line) {
    Node m;
    m.kind = Node::Kind::Map;
    m.line = line;
    for (auto it = y.begin(); it != y.end(); ++it) {
      const int key_line = it->first.Mark().is_null() ? line : it->first.Mark().line + 1;
      const std::string key = keyOf(it->first, key_line);
      if (dup_ == Duplicates::Refuse)
        for (size_t i = 0; i < m.map.size(); ++i)
          if (m.map[i].first == key)
            fail(key_line, "duplicate key '" + key + "' (first on line " +
                               std::to_string(m.key_lines[i]) + ")");
      m.map.emplace_back(key, node(it->second, depth + 1, key_line));
      m.key_lines.push_back(key_line);
    }
    return m;
  }

  /** A key is a scalar followed by ':' (the library takes a lone line at the
   *  end of a mapping as a key with no value). */
  std::string keyOf(const YAML::Node& k, int line) const {
    if (!k.IsScalar() || k.Mark().is_null())
      fail(line, "a key must be a word or a quoted string, not a list or mapping");
    const size_t at = static_cast<size_t>(k.Mark().pos) + bom_;
    if (k.Tag() != "!" && text_.compare(at, k.Scalar().size(), k.Scalar()) == 0) {
      size_t p = at + k.Scalar().size();
      while (p < text_.size() && (text_[p] == ' ' || text_[p] == '\t')) ++p;
      if (p >= text_.size() || text_[p] != ':')
        fail(line, "expected 'key: value', got '" + lineAt(text_, at) + "'");
    }
    return k.Scalar();
  }

  /** "~" or "null" as written (a string to the readers, as before); "" for nothing. */
  std::string nullWord(const YAML::Node& y) const {
    if (y.Mark().is_null()) return "";
    const size_t at = static_cast<size_t>(y.Mark().pos) + bom_;
    for (const char* w : {"~", "null", "Null", "NULL"}) {
      const size_t n = std::char_traits<char>::length(w);
      if (text_.compare(at, n, w) == 0 &&
          (at + n >= text_.size() ||
           std::string(" \t\r\n,]}#").find(text_[at + n]) != std::string::npos))
        return w;
    }
    return "";
  }

  const std::string& text_;
  const std::string& origin_;
  Duplicates dup_;
  long long budget_;  // values left before aliases count as an expansion attack
  size_t bom_;        // the library's positions do not count a UTF-8 byte order mark
};

}  // namespace

bool isBlank(const std::string& text) { return !detail::summarise(text).has_content; }

Node parse(const std::string& text, const std::string& origin, Duplicates duplicates) {
  const detail::LineSummary lines = detail::checkLines(text, origin);
  Converter conv(text, origin, duplicates);
  if (!lines.has_content) conv.fail(lines.lines, "the file is empty");
  std::vector<YAML::Node> docs;
  try {
    docs = YAML::LoadAll(text);
  } catch (const YAML::Exception& e) {
    conv.fail(e.mark.is_null() ? lines.lines : e.mark.line + 1, explain(e.msg));
  }
  if (docs.empty()) conv.fail(lines.lines, "the file is empty");
  for (size_t i = 1; i < docs.size(); ++i)
    if (!docs[i].IsNull())
      conv.fail(docs[i].Mark().is_null() ? lines.lines : docs[i].Mark().line + 1,
                "a second YAML document starts here (one per file; is a line out of place?)");
  Node root = conv.node(docs[0], 1, 1);
  if (root.kind == Node::Kind::Scalar && root.scalar.empty() && !root.quoted)
    conv.fail(lines.lines, "the file is empty");
  return root;
}

}  // namespace carenav::yaml
