#include <carenav/common/json.h>

#include <gtest/gtest.h>

#include <cmath>

using carenav::JsonWriter;

TEST(Json, WritesNestedStructuresCompact) {
  JsonWriter j(false);
  j.beginObject();
  j.key("a").value(1);
  j.key("b").beginArray().value("x").value(true).null().endArray();
  j.key("c").beginObject().endObject();
  j.key("d").value(std::nan(""));
  j.endObject();
  EXPECT_EQ(j.str(), R"({"a":1,"b":["x",true,null],"c":{},"d":null})");
}

TEST(Json, EscapesControlAndQuotes) {
  EXPECT_EQ(JsonWriter::escape("a\"b\\c\n\x01"), R"("a\"b\\c\n\u0001")");
}

TEST(Json, NumbersReadBackExactly) {
  JsonWriter j(false);
  j.beginArray().value(1137834225.973759).value(0.1).value(1e-300).endArray();
  EXPECT_EQ(j.str(), "[1137834225.973759,0.1,1e-300]");
}
