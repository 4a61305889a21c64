// The live app's inputs: intent scripts, the keyboard/joystick/TCP sources
// and the robot bridge's message parser.
#include <carenav/common/errors.h>
#include <carenav/runtime/bridge.h>
#include <carenav/runtime/intent.h>
#include <carenav/runtime/line_socket.h>

#include <fcntl.h>
#include <gtest/gtest.h>
#include <linux/joystick.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <thread>

using namespace carenav;
using namespace carenav::navigation;

namespace {

RobotParams walker() {
  RobotParams r;
  r.v_max = 0.4;
  r.v_min = -0.2;
  r.w_max = 0.8;
  return r;
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(IntentScript, RowsHeaderAndComments) {
  const auto rows = parseIntentScript("# user\nt,v,w\n0,0.3,0\n2.5, 0.2 ,-0.1\n\n4,0,0\n", "s.csv");
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_DOUBLE_EQ(rows[1].t, 2.5);
  EXPECT_DOUBLE_EQ(rows[1].cmd.v, 0.2);
  EXPECT_DOUBLE_EQ(rows[1].cmd.w, -0.1);
  EXPECT_EQ(parseIntentScript("0,0.3,0\n", "s.csv").size(), 1u) << "the header is optional";
}

TEST(IntentScript, NavigationLogColumnsReplayTheUser) {
  const std::string log =
      "t,truth_x,truth_y,truth_yaw,est_x,est_y,est_yaw,user_v,user_w,plan_v,plan_w\n"
      "0.1,1,1,0,1,1,0,,,0,0\n"
      "0.2,1,1,0,1,1,0,0.300,0.1000,0.3,0.1\n";
  const auto rows = parseIntentScript(log, "navlog.csv");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_TRUE(rows[0].none) << "a cycle without a user command";
  EXPECT_FALSE(rows[1].none);
  EXPECT_DOUBLE_EQ(rows[1].cmd.v, 0.3);
  EXPECT_DOUBLE_EQ(rows[1].cmd.w, 0.1);
}

TEST(IntentScript, BadInputNamesFileAndLine) {
  EXPECT_NE(errorOf([] { parseIntentScript("", "e.csv"); }).find("e.csv: no commands"),
            std::string::npos);
  EXPECT_NE(errorOf([] { parseIntentScript("t,v,w\n0,0.3\n", "e.csv"); }).find("e.csv:2:"),
            std::string::npos)
      << "truncated row";
  EXPECT_NE(errorOf([] { parseIntentScript("0,0.3,0\n1,fast,0\n", "e.csv"); }).find("'fast'"),
            std::string::npos);
  EXPECT_NE(errorOf([] { parseIntentScript("2,0.3,0\n1,0.3,0\n", "e.csv"); }).find("before"),
            std::string::npos);
  EXPECT_NE(errorOf([] { parseIntentScript("a,b,c\n0,1,1\n", "e.csv"); }).find("header"),
            std::string::npos);
  EXPECT_NE(errorOf([] { parseIntentScript("0,nan,0\n", "e.csv"); }).find("e.csv:1"),
            std::string::npos);
  const auto bin = std::filesystem::temp_directory_path() / "carenav_intent_bin.csv";
  std::ofstream(bin, std::ios::binary) << std::string("0,1\0\0,2", 7);
  EXPECT_NE(errorOf([&] { readIntentScript(bin.string()); }).find("not a text file"),
            std::string::npos);
  EXPECT_NE(errorOf([] { readIntentScript("/nonexistent/i.csv"); }).find("/nonexistent/i.csv"),
            std::string::npos);
}

TEST(IntentSources, ScriptHoldsRowsThenFallsSilent) {
  const auto p = std::filesystem::temp_directory_path() / "carenav_intent.csv";
  std::ofstream(p) << "0,0.3,0\n2,0.1,0.2\n3,0,0\n";
  auto src = makeIntentSource("csv:" + p.string(), walker());
  auto a = src->poll(1.0);
  ASSERT_TRUE(a);
  EXPECT_DOUBLE_EQ(a->cmd.v, 0.3);
  EXPECT_DOUBLE_EQ(a->t, 1.0) << "a row holds (is confirmed) until the next";
  auto b = src->poll(2.5);
  EXPECT_DOUBLE_EQ(b->cmd.w, 0.2);
  auto c = src->poll(10.0);
  EXPECT_DOUBLE_EQ(c->t, 3.0) << "after the last row the user is silent: the sample ages";
  EXPECT_TRUE(src->finished(10.0));
  EXPECT_FALSE(src->finished(2.0));
}

TEST(IntentSources, UnknownSpecAndKeyboardWithoutTerminal) {
  EXPECT_NE(errorOf([] { makeIntentSource("mouse", walker()); }).find("unknown source"),
            std::string::npos);
  EXPECT_NE(errorOf([] { makeIntentSource("csv:", walker()); }).find("no file"), std::string::npos);
  EXPECT_NE(errorOf([] { makeIntentSource("tcp:notaport", walker()); }).find("notaport"),
            std::string::npos);
  EXPECT_NE(errorOf([] {
              makeIntentSource("joystick:/nonexistent/js9", walker());
            }).find("/nonexistent/js9"),
            std::string::npos);
  if (!isatty(STDIN_FILENO))
    EXPECT_NE(errorOf([] { makeIntentSource("keyboard", walker()); }).find("not a terminal"),
              std::string::npos);
}

TEST(IntentSources, JoystickAxesMapToTheRobotLimits) {
  const RobotParams r = walker();
  EXPECT_NEAR(joystickToTwist(-32767, 0, r).v, r.v_max, 1e-9) << "stick forward";
  EXPECT_NEAR(joystickToTwist(32767, 0, r).v, r.v_min, 1e-9) << "stick back: reverse limit";
  EXPECT_NEAR(joystickToTwist(0, -32767, r).w, r.w_max, 1e-9) << "stick left turns left";
  EXPECT_NEAR(joystickToTwist(0, 0, r).v, 0, 1e-12);
}

TEST(IntentSources, JoystickDeviceEventsAndUnplugging) {
  // A FIFO stands in for /dev/input/js0: the same js_event records.
  const auto fifo =
      std::filesystem::temp_directory_path() / ("carenav_js_" + std::to_string(getpid()));
  std::filesystem::remove(fifo);
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  auto src = makeIntentSource("joystick:" + fifo.string(), walker());
  const int w = open(fifo.c_str(), O_WRONLY);
  ASSERT_GE(w, 0);
  EXPECT_FALSE(src->poll(0.0)) << "nothing heard yet";
  js_event e{};
  e.type = JS_EVENT_AXIS;
  e.number = 1;
  e.value = -16384;  // half forward
  ASSERT_EQ(write(w, &e, sizeof e), static_cast<ssize_t>(sizeof e));
  auto s = src->poll(1.0);
  ASSERT_TRUE(s);
  EXPECT_NEAR(s->cmd.v, 0.2, 0.01);
  EXPECT_DOUBLE_EQ(s->t, 1.0);
  close(w);  // unplugged
  auto s2 = src->poll(2.0);
  ASSERT_TRUE(s2);
  auto s3 = src->poll(5.0);
  EXPECT_DOUBLE_EQ(s3->t, 2.0) << "a lost joystick is silent: its command goes stale";
  std::filesystem::remove(fifo);
}

TEST(IntentSources, TcpLinesAndAMalformedOne) {
  auto src = makeIntentSource("tcp:127.0.0.1:0", walker());
  const std::string d = src->describe();
  const int port = std::stoi(d.substr(d.rfind(':') + 1));
  LineSocket c = connectTcp("127.0.0.1", port, 5);
  EXPECT_FALSE(src->poll(0.0));
  c.sendLine("0.25 -0.1");
  std::optional<IntentSample> s;
  for (int i = 0; i < 50 && !s; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    s = src->poll(1.0);
  }
  ASSERT_TRUE(s);
  EXPECT_DOUBLE_EQ(s->cmd.v, 0.25);
  EXPECT_DOUBLE_EQ(s->cmd.w, -0.1);
  c.sendLine("9 0");  // beyond the robot: clamped
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_DOUBLE_EQ(src->poll(2.0)->cmd.v, 0.4);
  EXPECT_DOUBLE_EQ(src->poll(3.0)->t, 2.0) << "no new line: the command ages";
  c.sendLine("forward please");
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  const std::string err = errorOf([&] { src->poll(4.0); });
  EXPECT_NE(err.find("line 3"), std::string::npos) << err;
  EXPECT_NE(err.find("'forward please'"), std::string::npos) << err;
}

TEST(BridgeProtocol, ParsesEachMessage) {
  auto o = parseBridgeLine("odom 12.5 1.0 -2.0 0.5 0.2 -0.1");
  ASSERT_TRUE(o);
  EXPECT_EQ(o->kind, BridgeMessage::Kind::Odom);
  EXPECT_DOUBLE_EQ(o->pose.y, -2.0);
  EXPECT_DOUBLE_EQ(o->vel.w, -0.1);
  auto s = parseBridgeLine("scan 1 laser 4 1.5 0 inf nan");
  ASSERT_TRUE(s);
  EXPECT_EQ(s->label, "laser");
  ASSERT_EQ(s->ranges.size(), 4u);
  EXPECT_FLOAT_EQ(s->ranges[0], 1.5f);
  EXPECT_TRUE(std::isinf(s->ranges[2]));
  auto i = parseBridgeLine("intent 3 0.3 0.1");
  EXPECT_EQ(i->kind, BridgeMessage::Kind::Intent);
  EXPECT_EQ(parseBridgeLine("bye")->kind, BridgeMessage::Kind::Bye);
  EXPECT_FALSE(parseBridgeLine(""));
  EXPECT_FALSE(parseBridgeLine("   # a comment"));
  EXPECT_EQ(formatCommand(1.5, {0.25, -0.1}), "cmd 1.500 0.2500 -0.1000");
}

TEST(BridgeProtocol, RejectsMalformedMessages) {
  auto what = [](const std::string& l) {
    try {
      parseBridgeLine(l);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(what("odom 1 2 3").find("odom T X Y YAW V W"), std::string::npos);
  EXPECT_NE(what("odom 1 2 3 x 0 0").find("'x'"), std::string::npos);
  EXPECT_NE(what("odom 1 2 3 nan 0 0").find("'nan'"), std::string::npos);
  EXPECT_NE(what("scan 1 laser 3 1 2").find("truncated"), std::string::npos);
  EXPECT_NE(what("scan 1 laser 2 1 2 3").find("has 3"), std::string::npos);
  EXPECT_NE(what("scan 1 laser -2").find("count"), std::string::npos);
  EXPECT_NE(what("scan 1 laser 1 -0.5").find("negative"), std::string::npos);
  EXPECT_NE(what("scan 1").find("too short"), std::string::npos);
  EXPECT_NE(what("intent 1 0.3").find("intent T V W"), std::string::npos);
  EXPECT_NE(what("bye now").find("bye"), std::string::npos);
  EXPECT_NE(what("velocity 1 2").find("unknown message"), std::string::npos);
  EXPECT_NE(what(std::string("\x01\x02garbage")).find("unknown message"), std::string::npos);
}

TEST(LineSocketTest, SplitsLinesAndBoundsTheirLength) {
  TcpListener l("127.0.0.1", 0);
  LineSocket a = connectTcp("127.0.0.1", l.port(), 5);
  LineSocket b;
  for (int i = 0; i < 50 && !b.open(); ++i) b = l.accept(100);
  ASSERT_TRUE(b.open());
  a.sendLine("one\r");
  a.sendLine("two");
  std::vector<std::string> got;
  for (int i = 0; i < 50 && got.size() < 2; ++i) b.readLines(got, 20);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0], "one");
  b.max_line = 16;
  a.sendLine(std::string(100, 'x'));
  bool threw = false;
  for (int i = 0; i < 50 && !threw; ++i) {
    try {
      b.readLines(got, 20);
    } catch (const std::runtime_error&) {
      threw = true;
    }
  }
  EXPECT_TRUE(threw) << "an endless line must not grow memory without bound";
  a.close();
  std::vector<std::string> rest;
  bool alive = true;
  for (int i = 0; i < 50 && alive; ++i) alive = b.readLines(rest, 20);
  EXPECT_FALSE(alive) << "the peer closed";
}
