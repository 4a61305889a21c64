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
