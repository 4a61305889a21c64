// The YAML reader over yaml-cpp: nodes keep their lines, carenav's line rules
// hold, and what the library would let through silently is refused.
#include <carenav/common/yaml.h>

#include <gtest/gtest.h>

#include <string>

using namespace carenav;
using yaml::Node;

namespace {

std::string errorOf(const std::string& text, yaml::Duplicates d = yaml::Duplicates::Refuse) {
  try {
    yaml::parse(text, "t.yaml", d);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace

TEST(Yaml, NodesKeepTheirLinesAndOrder) {
  const Node n = yaml::parse(
      "# a comment\n"
      "zeta: 1\n"
      "alpha: \"two\"\n"
      "list:\n"
      "  - a: [1, [2, 3]]\n"
      "    b: 'x''y'\n"
      "empty:\n",
      "t.yaml");
  ASSERT_EQ(n.kind, Node::Kind::Map);
  ASSERT_EQ(n.map.size(), 4u);
  EXPECT_EQ(n.map[0].first, "zeta");  // file order, not sorted
  EXPECT_EQ(n.key_lines, (std::vector<int>{2, 3, 4, 7}));
  EXPECT_FALSE(n.map[0].second.quoted);
  EXPECT_TRUE(n.map[1].second.quoted);
  EXPECT_EQ(n.map[1].second.scalar, "two");
  const Node& item = n.find("list")->seq.at(0);
  EXPECT_EQ(item.line, 5);
  EXPECT_EQ(item.find("a")->seq.at(1).seq.at(1).scalar, "3");
  EXPECT_EQ(item.find("b")->scalar, "x'y");
  EXPECT_EQ(item.find("b")->line, 6);
  const Node* e = n.find("empty");
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->scalar, "");
  EXPECT_EQ(e->line, 7);  // an empty value has its key's line
}

TEST(Yaml, LibraryLeniencyIsRefused) {
  // yaml-cpp reads a last line without ':' as a key with no value.
  EXPECT_EQ(errorOf("image: a.pgm\nthis is not yaml\n"),
            "t.yaml:2: expected 'key: value', got 'this is not yaml'");
  // ... and a mapping after a top-level list as a second document.
  EXPECT_EQ(errorOf("- 1\na: 2\n").rfind("t.yaml:2: a second YAML document", 0), 0u);
  EXPECT_EQ(errorOf("a: 1\n---\nb: 2\n").rfind("t.yaml:3: a second YAML document", 0), 0u);
  EXPECT_EQ(errorOf("a: 1\n---\n"), "(no error)");
  // ... and an unclosed quote at the end of the file as a string.
  EXPECT_EQ(errorOf("a: 1\nname: \"open\n"), "t.yaml:2: name: unterminated quoted string");
}

TEST(Yaml, DuplicateKeysRefusedOrKept) {
  EXPECT_EQ(errorOf("a: 1\nb: 2\na: 3\n"), "t.yaml:3: duplicate key 'a' (first on line 1)");
  const Node n = yaml::parse("a: 1\na: 2\n", "t.yaml", yaml::Duplicates::Keep);
  ASSERT_EQ(n.map.size(), 2u);
  EXPECT_EQ(n.map[1].second.scalar, "2");
}

TEST(Yaml, LineRules) {
  EXPECT_EQ(errorOf("a: 1\n\tb: 2\n"), "t.yaml:2: tab in the indentation; use spaces");
  EXPECT_EQ(errorOf("a: 1\nrect: [1, 2\nb: 3\n"), "t.yaml:2: rect: unterminated list: missing ']'");
  EXPECT_EQ(errorOf("a: 1\n  b: 2\n").rfind("t.yaml:2: unexpected indentation", 0), 0u);
  EXPECT_EQ(errorOf(""), "t.yaml:1: the file is empty");
  EXPECT_EQ(errorOf("# only\n\n"), "t.yaml:3: the file is empty");
  EXPECT_EQ(errorOf(std::string("a: 1\nb\0c: 2\n", 12)),
            "t.yaml:2: binary data: this is not a YAML text file");
  // Quotes and '#' inside strings, apostrophes inside words, comments after values.
  const Node n = yaml::parse("a: \"x # y\" # c\nb: it's fine\nc: 'it''s'\n", "t.yaml");
  EXPECT_EQ(n.find("a")->scalar, "x # y");
  EXPECT_EQ(n.find("b")->scalar, "it's fine");
  EXPECT_EQ(n.find("c")->scalar, "it's");
  // A quote inside a plain word opens nothing.
  EXPECT_EQ(yaml::parse("a: x-'y\nb: k:'v\n", "t.yaml").find("a")->scalar, "x-'y");
}

TEST(Yaml, WhatTheLibraryAddsIsRead) {
  // Block scalars (their lines are text, not checked), flow maps, CRLF, a BOM.
  const Node n = yaml::parse(
      "\xEF\xBB\xBFnote: |\r\n  it's \"open\r\n  [ too\r\nm: {x: 1, y: [2]}\r\nz: ~\r\n", "t.yaml");
  EXPECT_EQ(n.find("note")->scalar, "it's \"open\n[ too\n");
  EXPECT_TRUE(n.find("note")->quoted);
  EXPECT_EQ(n.find("m")->find("y")->seq.at(0).scalar, "2");
  EXPECT_EQ(n.find("z")->scalar, "~");
  EXPECT_EQ(n.find("z")->line, 5);
}

TEST(Yaml, AliasesCannotExpandPastTheFile) {
  // "Billion laughs": each level doubles; the conversion stops at the file's size.
  std::string t = "a0: &a0 [x, x]\n";
  for (int i = 1; i < 40; ++i)
    t += "a" + std::to_string(i) + ": &a" + std::to_string(i) + " [*a" + std::to_string(i - 1) +
         ", *a" + std::to_string(i - 1) + "]\n";
  EXPECT_NE(errorOf(t).find("aliases expand"), std::string::npos) << errorOf(t);
  // A few aliases within the size of the file are fine.
  const Node n = yaml::parse("base: &b [1, 2]\ncopy: *b\n", "t.yaml");
  EXPECT_EQ(n.find("copy")->seq.size(), 2u);
}

TEST(Yaml, IsBlank) {
  EXPECT_TRUE(yaml::isBlank(""));
  EXPECT_TRUE(yaml::isBlank("  \n# c\n\t\n"));
  EXPECT_FALSE(yaml::isBlank("a: 1\n"));
}
