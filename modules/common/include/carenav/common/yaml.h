// A small YAML subset with line numbers (mrpt::containers::yaml keeps none),
// used by the simulator's world files and the navigation scenarios:
// block maps, block sequences, flow sequences [a, b, [c, d]], plain and
// quoted scalars, '#' comments. Enough for world files; anything else is an
// error naming the file and line.
#pragma once

#include <carenav/common/errors.h>

#include <string>
#include <utility>
#include <vector>

namespace carenav::yaml {

struct Node {
  enum class Kind { Scalar, Map, Seq };
  Kind kind = Kind::Scalar;
  std::string scalar;
  bool quoted = false;
  std::vector<std::pair<std::string, Node>> map;
  std::vector<int> key_lines;
  std::vector<Node> seq;
  int line = 0;
  const Node* find(const std::string& key) const;
};

/** Deepest nesting of maps, lists and flow lists accepted (world and
 *  scenario files use 4); deeper input is refused, never a stack overflow. */
inline constexpr int kMaxDepth = 64;

/** Parses `text`; errors are InputError "origin:line: what". */
Node parse(const std::string& text, const std::string& origin);

}  // namespace carenav::yaml
