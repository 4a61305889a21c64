#include <carenav/common/params.h>

#include <gtest/gtest.h>

using namespace carenav;

namespace {
struct Demo {
  double speed = 0.5;
  int count = 3;
  bool on = true;
  std::string mode = "a";
  std::vector<Point2> poly = {{0, 0}, {1, 0}, {0, 1}};
  static const ParamTable<Demo>& table() {
    static const auto t = ParamTable<Demo>()
                              .real("speed", &Demo::speed, "m/s", 0, 2, "speed")
                              .integer("count", &Demo::count, "", 1, 10, "count")
                              .flag("on", &Demo::on, "switch")
                              .choice("mode", &Demo::mode, {"a", "b"}, "mode")
                              .polygon("poly", &Demo::poly, "m", "outline")
                              .check([](const Demo& d) -> std::optional<std::string> {
                                if (d.count > 5 && d.speed > 1) return std::string("too much");
                                return std::nullopt;
                              });
    return t;
  }
};
}  // namespace

TEST(Params, DefaultsComeFromTheStruct) {
  const auto& t = Demo::table();
  EXPECT_EQ(t.find("speed")->default_text, "0.5");
  EXPECT_EQ(t.find("count")->default_text, "3");
  EXPECT_EQ(t.find("on")->default_text, "true");
  EXPECT_EQ(t.find("poly")->default_text, "0,0 1,0 0,1");
  EXPECT_EQ(t.find("nope"), nullptr);
}

TEST(Params, SetParsesAndValidates) {
  Demo d;
  const auto& t = Demo::table();
  t.set(d, "speed", " 1.25 ");
  EXPECT_DOUBLE_EQ(d.speed, 1.25);
  t.set(d, "count", "7");
  EXPECT_EQ(d.count, 7);
  t.set(d, "on", "false");
  EXPECT_FALSE(d.on);
  t.set(d, "mode", "b");
  EXPECT_EQ(d.mode, "b");
  t.set(d, "poly", "0,0 2,0 2,2 0,2");
  EXPECT_EQ(d.poly.size(), 4u);
  EXPECT_THROW(t.set(d, "speed", "2.5"), ParamValueError);
  EXPECT_THROW(t.set(d, "speed", "fast"), ParamValueError);
  EXPECT_THROW(t.set(d, "speed", "1.0m"), ParamValueError);
  EXPECT_THROW(t.set(d, "speed", "nan"), ParamValueError);
  EXPECT_THROW(t.set(d, "speed", ""), ParamValueError);
  EXPECT_THROW(t.set(d, "count", "2.5"), ParamValueError);
  EXPECT_THROW(t.set(d, "count", "0"), ParamValueError);
  EXPECT_THROW(t.set(d, "on", "maybe"), ParamValueError);
  EXPECT_THROW(t.set(d, "mode", "c"), ParamValueError);
  EXPECT_THROW(t.set(d, "poly", "0,0 1,1"), ParamValueError);
  EXPECT_THROW(t.set(d, "poly", "0,0 1,1 2,2"), ParamValueError);  // zero area
  EXPECT_THROW(t.set(d, "poly", "0,0 1;0 0,1"), ParamValueError);
  EXPECT_THROW(t.set(d, "other", "1"), ParamValueError);
  // failed sets leave the value alone
  EXPECT_DOUBLE_EQ(d.speed, 1.25);
}

TEST(Params, CrossChecks) {
  Demo d;
  EXPECT_TRUE(Demo::table().crossCheck(d).empty());
  d.count = 6;
  d.speed = 1.5;
  ASSERT_EQ(Demo::table().crossCheck(d).size(), 1u);
}

TEST(Params, AllowedTextNamesRangeAndUnit) {
  EXPECT_EQ(Demo::table().find("speed")->allowedText(), "a real number in [0, 2] m/s");
  EXPECT_EQ(Demo::table().find("mode")->allowedText(), "one of a, b");
}
