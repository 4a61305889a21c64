#include <carenav/common/errors.h>
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

TEST(Json, PrettyOutputKeepsTheKeyOrderAndReadsBack) {
  JsonWriter j;
  j.beginObject();
  j.key("z").value(1.5);
  j.key("a").beginArray().value(uint64_t{7}).endArray();
  j.endObject();
  EXPECT_EQ(j.str(), "{\n  \"z\": 1.5,\n  \"a\": [\n    7\n  ]\n}");
  const carenav::Json back = carenav::parseJson(j.str(), "test");
  EXPECT_EQ(back.at("z").get<double>(), 1.5);
  EXPECT_EQ(back.at("a").at(0).get<uint64_t>(), 7u);
}

TEST(Json, BytesThatAreNotUtf8AreReplacedNotThrown) {
  EXPECT_EQ(carenav::dumpJson(carenav::Json("a\xff"), false), "\"a\xef\xbf\xbd\"");
}

TEST(Json, TextThatIsNotJsonIsBadInputNamingItsOrigin) {
  try {
    carenav::parseJson("{\"a\": ", "child 12");
    FAIL() << "no error";
  } catch (const carenav::InputError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("child 12: not JSON", 0), 0u) << e.what();
  }
}
