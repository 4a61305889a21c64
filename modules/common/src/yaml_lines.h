// The line rules carenav adds on top of YAML (see carenav/common/yaml.h),
// checked before the text reaches the library.
#pragma once

#include <string>

namespace carenav::yaml::detail {

/** What the line check found. */
struct LineSummary {
  int lines = 1;             ///< number of lines, counting a last one without '\n'
  bool has_content = false;  ///< a line other than blanks and comments
};

/** Checks every line of `text` (tabs in the indentation, quotes and flow
 *  lists closed on their line, nesting depth, NUL bytes); throws InputError
 *  "origin:line: what" at the first line that breaks a rule. */
LineSummary checkLines(const std::string& text, const std::string& origin);

/** Line count and content as checkLines reports them, without the checks. */
LineSummary summarise(const std::string& text);

}  // namespace carenav::yaml::detail
