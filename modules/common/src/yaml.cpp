#include <carenav/common/yaml.h>

namespace carenav::yaml {

const Node* Node::find(const std::string& key) const {
  for (const auto& [k, v] : map)
    if (k == key) return &v;
  return nullptr;
}

namespace {

struct Line {
  int number = 0;  // 1-based
  int indent = 0;
  std::string text;  // without indentation and comment, right-trimmed
};

std::string rtrim(const std::string& s) {
  const size_t b = s.find_last_not_of(" \t\r");
  return b == std::string::npos ? "" : s.substr(0, b + 1);
}
std::string ltrim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t");
  return a == std::string::npos ? "" : s.substr(a);
}

class Parser {
 public:
  Parser(const std::string& text, const std::string& origin) : origin_(origin) {
    int n = 0;
    size_t pos = 0;
    while (pos <= text.size()) {
      size_t e = text.find('\n', pos);
      if (e == std::string::npos) e = text.size();
      std::string raw = text.substr(pos, e - pos);
      ++n;
      pos = e + 1;
      std::string body = rtrim(stripComment(raw, n));
      if (ltrim(body).empty()) continue;
      int indent = 0;
      while (indent < static_cast<int>(body.size()) && body[indent] == ' ') ++indent;
      if (body[indent] == '\t') fail(n, "tab in indentation (use spaces)");
      lines_.push_back({n, indent, body.substr(indent)});
      if (e == text.size()) break;
    }
    last_line_ = n;
  }

  Node document() {
    if (lines_.empty()) fail(last_line_ > 0 ? last_line_ : 1, "the file is empty");
    Node root = block(lines_[0].indent);
    if (i_ < lines_.size()) fail(lines_[i_].number, "unexpected indentation");
    return root;
  }

 private:
  [[noreturn]] void fail(int line, const std::string& what) const {
    throw InputError(origin_ + ":" + std::to_string(line) + ": " + what);
  }

  std::string stripComment(const std::string& s, int line) const {
    char q = 0;
    for (size_t k = 0; k < s.size(); ++k) {
      const char c = s[k];
      if (q) {
        if (q == '"' && c == '\\')
          ++k;
        else if (c == q)
          q = 0;
      } else if (c == '"' || c == '\'') {
        q = c;
      } else if (c == '#' && (k == 0 || s[k - 1] == ' ' || s[k - 1] == '\t')) {
        return s.substr(0, k);
      }
    }
    if (q) fail(line, "unterminated quoted string");
    return s;
  }

  static bool isSeqItem(const std::string& t) { return t == "-" || t.rfind("- ", 0) == 0; }

  // Splits "key: rest" (key plain or quoted). Returns false when no mapping colon.
  bool splitKey(const std::string& t, std::string& key, std::string& rest) const {
    size_t k = 0;
    if (!t.empty() && (t[0] == '"' || t[0] == '\'')) {
      const size_t e = t.find(t[0], 1);
      if (e == std::string::npos) return false;
      key = t.substr(1, e - 1);
      k = e + 1;
      if (k >= t.size() || t[k] != ':') return false;
    } else {
      if (!t.empty() && (t[0] == '[' || t[0] == '{')) return false;
      for (; k < t.size(); ++k)
        if (t[k] == ':' && (k + 1 == t.size() || t[k + 1] == ' ')) break;
      if (k >= t.size()) return false;
      key = rtrim(t.substr(0, k));
    }
    rest = ltrim(t.substr(k + 1));
    return true;
  }

  /** Nesting depth of the value being parsed; deeper than kMaxDepth is refused
   *  before the recursion can exhaust the stack. */
  struct Nest {
    Nest(Parser& p, int line) : p_(p) {
      if (++p_.depth_ > kMaxDepth)
        p_.fail(line, "nested deeper than " + std::to_string(kMaxDepth) + " levels");
    }
    ~Nest() { --p_.depth_; }
    Parser& p_;
  };

  Node block(int indent) {
    const Nest nest(*this, lines_[i_].number);
    const Line& first = lines_[i_];
    if (isSeqItem(first.text)) return sequence(indent);
    std::string key, rest;
    if (splitKey(first.text, key, rest)) return mapping(indent);
    // a lone scalar document or flow value
    Node n = flow(first.text, first.number);
    ++i_;
    return n;
  }

  Node mapping(int indent) {
    Node m;
    m.kind = Node::Kind::Map;
    m.line = lines_[i_].number;
    while (i_ < lines_.size() && lines_[i_].indent == indent) {
      const Line& l = lines_[i_];
      if (isSeqItem(l.text)) fail(l.number, "a list item where a 'key: value' was expected");
      std::string key, rest;
      if (!splitKey(l.text, key, rest))
        fail(l.number, "expected 'key: value', got '" + l.text + "'");
      if (key.empty()) fail(l.number, "empty key");
      if (m.find(key)) fail(l.number, "duplicated key '" + key + "'");
      ++i_;
      Node v;
      if (!rest.empty()) {
        v = flow(rest, l.number);
      } else if (i_ < lines_.size() && lines_[i_].indent > indent) {
        v = block(lines_[i_].indent);
      } else if (i_ < lines_.size() && lines_[i_].indent == indent && isSeqItem(lines_[i_].text)) {
        v = sequence(indent);  // "key:\n- a\n- b" at the same indentation
      } else {
        v.line = l.number;  // empty value
      }
      if (v.line == 0) v.line = l.number;
      m.map.emplace_back(key, std::move(v));
      m.key_lines.push_back(l.number);
    }
    if (i_ < lines_.size() && lines_[i_].indent > indent)
      fail(lines_[i_].number, "unexpected indentation");
    return m;
  }

  Node sequence(int indent) {
    Node s;
    s.kind = Node::Kind::Seq;
    s.line = lines_[i_].number;
    while (i_ < lines_.size() && lines_[i_].indent == indent && isSeqItem(lines_[i_].text)) {
      Line& l = lines_[i_];
      const std::string rest = ltrim(l.text.substr(1));
      if (rest.empty()) {
        ++i_;
        if (i_ < lines_.size() && lines_[i_].indent > indent)
          s.seq.push_back(block(lines_[i_].indent));
        else
          fail(l.number, "empty list item");
        continue;
      }
      std::string key, r2;
      if (splitKey(rest, key, r2)) {
        // "- key: v" opens a mapping whose keys sit at the column of `key`
        l.indent = indent + static_cast<int>(l.text.size() - rest.size());
        l.text = rest;
        s.seq.push_back(mapping(l.indent));
      } else {
        s.seq.push_back(flow(rest, l.number));
        ++i_;
      }
    }
    return s;
  }

  // flow value on one line: scalar or [ ... ]
  Node flow(const std::string& t, int line) {
    size_t k = 0;
    Node n = flowValue(t, k, line);
    while (k < t.size() && t[k] == ' ') ++k;
    if (k != t.size()) fail(line, "unexpected text after the value: '" + t.substr(k) + "'");
    return n;
  }

  Node flowValue(const std::string& t, size_t& k, int line) {
    const Nest nest(*this, line);
    while (k < t.size() && t[k] == ' ') ++k;
    Node n;
    n.line = line;
    if (k >= t.size()) fail(line, "missing value");
    if (t[k] == '{') fail(line, "flow mappings {...} are not supported; use indented keys");
    if (t[k] == '[') {
      n.kind = Node::Kind::Seq;
      ++k;
      while (true) {
        while (k < t.size() && t[k] == ' ') ++k;
        if (k >= t.size()) fail(line, "unterminated list: missing ']'");
        if (t[k] == ']') {
          if (!n.seq.empty()) fail(line, "missing value after ','");
          ++k;
          return n;
        }
        n.seq.push_back(flowValue(t, k, line));
        while (k < t.size() && t[k] == ' ') ++k;
        if (k >= t.size()) fail(line, "unterminated list: missing ']'");
        if (t[k] == ',') {
          ++k;
          while (k < t.size() && t[k] == ' ') ++k;
          if (k < t.size() && t[k] == ']') fail(line, "missing value after ','");
          continue;
        }
        if (t[k] == ']') {
          ++k;
          return n;
        }
        fail(line, "expected ',' or ']' in a list");
      }
    }
    if (t[k] == '"' || t[k] == '\'') {
      const char q = t[k++];
      while (k < t.size() && t[k] != q) {
        if (q == '"' && t[k] == '\\' && k + 1 < t.size()) ++k;
        n.scalar += t[k++];
      }
      if (k >= t.size()) fail(line, "unterminated quoted string");
      ++k;
      n.quoted = true;
      return n;
    }
    const size_t a = k;
    while (k < t.size() && t[k] != ',' && t[k] != ']' && t[k] != '[') ++k;
    n.scalar = rtrim(t.substr(a, k - a));
    if (n.scalar.empty()) fail(line, "missing value");
    return n;
  }

  std::string origin_;
  std::vector<Line> lines_;
  size_t i_ = 0;
  int last_line_ = 0;
  int depth_ = 0;
};

}  // namespace

Node parse(const std::string& text, const std::string& origin) {
  Parser p(text, origin);
  return p.document();
}

}  // namespace carenav::yaml
