// YAML documents read through yaml-cpp, with the line of every node kept for
// error messages. Used by the simulator's world files, the navigation
// scenarios, the places files and ROS map_server YAML.
//
// carenav's YAML files are YAML 1.2 with three rules on top, checked line by
// line before the library sees the text (so that an error names the line the
// author got wrong, and the library's recursion is bounded by construction):
// spaces, not tabs, in the indentation; quoted strings and flow lists
// ([a, b]) close on the line they open; at most kMaxDepth levels of nesting.
// One document per file.
#pragma once

#include <carenav/common/errors.h>

#include <string>
#include <utility>
#include <vector>

namespace carenav::yaml {

struct Node {
  enum class Kind { Scalar, Map, Seq };
  Kind kind = Kind::Scalar;
  /** A scalar's text; "" for an empty value ("key:" with nothing after it). */
  std::string scalar;
  /** The scalar was written quoted (or as a | or > block): a string, never a number. */
  bool quoted = false;
  /** A map's entries in the order of the file (with Duplicates::Keep, repeated keys too). */
  std::vector<std::pair<std::string, Node>> map;
  /** The line of each key of `map`. */
  std::vector<int> key_lines;
  std::vector<Node> seq;
  /** 1-based line of the value (of its key when the value is empty). */
  int line = 0;
  const Node* find(const std::string& key) const;
};

/** Deepest nesting of maps, lists and flow lists accepted (world and
 *  scenario files use 4); deeper input is refused, never a stack overflow. */
inline constexpr int kMaxDepth = 64;

/** What parse does with a key given twice in one mapping. */
enum class Duplicates {
  Refuse,  ///< InputError "origin:line: duplicate key 'k' (first on line N)"
  Keep     ///< both entries are kept, for readers with their own message
};

/** Parses `text`; errors are InputError "origin:line: what". An empty file
 *  (only blanks and comments) is "origin:N: the file is empty". */
Node parse(const std::string& text, const std::string& origin,
           Duplicates duplicates = Duplicates::Refuse);

/** True when `text` holds nothing but blanks and comments. */
bool isBlank(const std::string& text);

}  // namespace carenav::yaml
