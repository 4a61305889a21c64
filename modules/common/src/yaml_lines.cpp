#include "yaml_lines.h"

#include <carenav/common/errors.h>
#include <carenav/common/yaml.h>

#include <vector>

namespace carenav::yaml::detail {

namespace {

/** One line after its indentation: where a comment starts, whether a quote
 *  or a flow list is left open, and how deep its brackets go. */
struct Scan {
  size_t end = 0;  // the content ends here (a comment or the end of the line)
  char open_quote = 0;
  int open_brackets = 0;
  int max_brackets = 0;
};

Scan scanLine(const std::string& s, size_t from) {
  Scan r;
  r.end = s.size();
  char q = 0;
  int depth = 0;
  for (size_t k = from; k < s.size(); ++k) {
    const char c = s[k];
    if (q) {
      if (q == '"' && c == '\\')
        ++k;
      else if (c == q && q == '\'' && k + 1 < s.size() && s[k + 1] == '\'')
        ++k;  // '' inside '...' is a quote
      else if (c == q)
        q = 0;
    } else if ((c == '"' || c == '\'') &&
               (k == from || std::string(" \t[{,").find(s[k - 1]) != std::string::npos)) {
      q = c;  // a quote opens a scalar only at its start (it's text inside it's)
    } else if (c == '#' && (k == from || s[k - 1] == ' ' || s[k - 1] == '\t')) {
      r.end = k;
      break;
    } else if (c == '[' || c == '{') {
      r.max_brackets = std::max(r.max_brackets, ++depth);
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
  }
  r.open_quote = q;
  r.open_brackets = depth;
  return r;
}

/** "key: " for messages about a "key: value" line (after any "- "), else "". */
std::string keyPrefix(const std::string& s, size_t from) {
  while (from + 1 < s.size() && (s[from] == '-' || s[from] == '?') && s[from + 1] == ' ')
    from = s.find_first_not_of(' ', from + 1);
  if (from >= s.size() || std::string("\"'[{#").find(s[from]) != std::string::npos) return "";
  const size_t colon = s.find(": ", from);
  if (colon == std::string::npos || colon == from) return "";
  const std::string key = s.substr(from, colon - from);
  return key.find_first_of("[]{}\"'#") == std::string::npos ? key + ": " : "";
}

/** "- " and "? " indicators at the start of a line each open a level. */
int leadingIndicators(const std::string& s, size_t from) {
  int n = 0;
  while (from < s.size() && (s[from] == '-' || s[from] == '?') &&
         (from + 1 == s.size() || s[from + 1] == ' ')) {
    ++n;
    from = s.find_first_not_of(' ', from + 1);
    if (from == std::string::npos) break;
  }
  return n;
}

/** A value that starts a | or > block: the lines indented below it are text. */
bool opensBlockScalar(const std::string& s, size_t end) {
  size_t e = end;
  while (e > 0 && (s[e - 1] == ' ' || s[e - 1] == '\t')) --e;
  size_t b = e;
  while (b > 0 && std::string("|>+-0123456789").find(s[b - 1]) != std::string::npos) --b;
  if (b == e || (s[b] != '|' && s[b] != '>')) return false;
  return b == 0 || s[b - 1] == ' ';
}

class LineChecker {
 public:
  LineChecker(const std::string& origin, bool check) : origin_(origin), check_(check) {}

  void line(std::string s, int number) {
    if (number == 1 && s.compare(0, 3, "\xEF\xBB\xBF") == 0) s.erase(0, 3);  // UTF-8 BOM
    if (!s.empty() && s.back() == '\r') s.pop_back();
    if (check_ && s.find('\0') != std::string::npos)
      fail(number, "binary data: this is not a YAML text file");
    const size_t first = s.find_first_not_of(" \t");
    const int indent = static_cast<int>(
        s.find_first_not_of(' ') == std::string::npos ? s.size() : s.find_first_not_of(' '));
    if (block_indent_ >= 0 && (first == std::string::npos || indent > block_indent_)) return;
    block_indent_ = -1;
    if (first == std::string::npos || s[first] == '#') return;
    summary_.has_content = true;
    if (!check_) return;
    if (s.find('\t') < first) fail(number, "tab in the indentation; use spaces");
    checkContent(s, first, indent, number);
  }

  LineSummary summary(int lines) {
    summary_.lines = lines;
    return summary_;
  }

 private:
  void checkContent(const std::string& s, size_t first, int indent, int number) {
    const Scan sc = scanLine(s, first);
    if (sc.open_quote) fail(number, keyPrefix(s, first) + "unterminated quoted string");
    while (!indents_.empty() && indents_.back() >= indent) indents_.pop_back();
    indents_.push_back(indent);
    const int depth =
        static_cast<int>(indents_.size()) + leadingIndicators(s, first) + sc.max_brackets;
    if (depth > kMaxDepth)
      fail(number, "nested deeper than " + std::to_string(kMaxDepth) + " levels");
    if (sc.open_brackets > 0) fail(number, keyPrefix(s, first) + "unterminated list: missing ']'");
    if (opensBlockScalar(s, sc.end)) block_indent_ = indent;
  }

  [[noreturn]] void fail(int line, const std::string& what) const {
    throw InputError(origin_ + ":" + std::to_string(line) + ": " + what);
  }

  std::string origin_;
  bool check_;
  std::vector<int> indents_;  // indentation of the enclosing lines, outermost first
  int block_indent_ = -1;     // inside a | or > block opened at this indentation
  LineSummary summary_;
};

LineSummary run(const std::string& text, const std::string& origin, bool check) {
  LineChecker c(origin, check);
  int n = 0;
  size_t pos = 0;
  while (true) {
    const size_t e = text.find('\n', pos);
    c.line(text.substr(pos, e == std::string::npos ? std::string::npos : e - pos), ++n);
    if (e == std::string::npos) break;
    pos = e + 1;
  }
  return c.summary(n);
}

}  // namespace

LineSummary checkLines(const std::string& text, const std::string& origin) {
  return run(text, origin, true);
}

LineSummary summarise(const std::string& text) { return run(text, "", false); }

}  // namespace carenav::yaml::detail
