// The bridge's input side: half-closed and reset connections, bounded reads,
// peer text made printable, implausible numbers refused, huge scans reduced.
#include <carenav/common/robot.h>
#include <carenav/runtime/bridge.h>
#include <carenav/runtime/intent.h>
#include <carenav/runtime/line_socket.h>

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <thread>

namespace carenav::navigation {
namespace {

std::pair<LineSocket, LineSocket> connectedPair(TcpListener& l) {
  LineSocket a = connectTcp("127.0.0.1", l.port(), 5);
  LineSocket b;
  for (int i = 0; i < 50 && !b.open(); ++i) b = l.accept(100);
  return {std::move(a), std::move(b)};
}

std::string parseError(const std::string& line) {
  try {
    parseBridgeLine(line);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(BridgeSafety, AHalfClosedPeerStillReceivesTheLastWords) {
  TcpListener l("127.0.0.1", 0);
  auto [robot, carenav] = connectedPair(l);
  ASSERT_TRUE(carenav.open());
  robot.sendLine("odom 1 0 0 0 0 0");
  robot.shutdownWrite();  // sends no more, still reads
  std::vector<std::string> got;
  bool alive = true;
  for (int i = 0; i < 100 && alive; ++i) alive = carenav.readLines(got, 20);
  EXPECT_FALSE(alive);
  EXPECT_TRUE(carenav.peerDone());
  EXPECT_FALSE(carenav.resetByPeer());
  ASSERT_EQ(got.size(), 1u) << "the line before the half-close is delivered";
  // The robot still gets the stop.
  EXPECT_TRUE(carenav.sendLine("cmd 1.000 0.0000 0.0000"));
  EXPECT_TRUE(carenav.sendLine("stop error"));
  std::vector<std::string> heard;
  for (int i = 0; i < 50 && heard.size() < 2; ++i) robot.readLines(heard, 20);
  ASSERT_EQ(heard.size(), 2u);
  EXPECT_EQ(heard[1], "stop error");
}

TEST(BridgeSafety, AResetIsToldFromAClose) {
  TcpListener l("127.0.0.1", 0);
  auto [robot, carenav] = connectedPair(l);
  ASSERT_TRUE(carenav.open());
  carenav.sendLine("hello");  // unread by the robot: its close becomes a reset
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  robot.abort();
  std::vector<std::string> got;
  bool alive = true;
  for (int i = 0; i < 100 && alive; ++i) alive = carenav.readLines(got, 20);
  EXPECT_FALSE(alive);
  EXPECT_TRUE(carenav.resetByPeer());
  EXPECT_FALSE(carenav.sendLine("stop error")) << "nobody is there";
}

TEST(BridgeSafety, ReadsAreBoundedPerCall) {
  TcpListener l("127.0.0.1", 0);
  auto [robot, carenav] = connectedPair(l);
  ASSERT_TRUE(carenav.open());
  const std::string line(1000, 'x');
  for (int i = 0; i < 200; ++i) robot.sendLine(line);  // 200 kB waiting
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  std::vector<std::string> got;
  carenav.readLines(got, 100, 10000);
  EXPECT_LE(got.size(), 10u) << "at most 10000 bytes taken in one call";
  size_t total = got.size();
  for (int i = 0; i < 500 && total < 200; ++i) {
    got.clear();
    carenav.readLines(got, 20, 10000);
    total += got.size();
  }
  EXPECT_EQ(total, 200u) << "the rest comes with the next calls";
}

TEST(BridgeSafety, APeerThatDoesNotReadCannotBlockTheSender) {
  TcpListener l("127.0.0.1", 0);
  auto [robot, carenav] = connectedPair(l);
  ASSERT_TRUE(carenav.open());
  const std::string line(60000, 'c');
  // The robot reads nothing: the socket buffers fill, then sends give up.
  int sent = 0;
  for (int i = 0; i < 2000; ++i) {
    if (!carenav.sendLine(line, 10)) break;
    ++sent;
  }
  EXPECT_LT(sent, 2000) << "buffers are not 120 MB deep: a send must have given up";
  EXPECT_TRUE(carenav.open()) << "a slow reader is not a closed one";
}

TEST(BridgeSafety, PeerTextIsPrintable) {
  EXPECT_EQ(printableText("ok"), "ok");
  EXPECT_EQ(printableText(std::string("a\x1b[31mred\x07", 10)), "a\\x1b[31mred\\x07");
  EXPECT_EQ(printableText(std::string("be\0fore", 7)), "be\\x00fore") << "no cut at NUL";
  EXPECT_EQ(printableText("back\\slash"), "back\\\\slash");
  EXPECT_EQ(printableText("\xc3\xa9"), "\\xc3\\xa9");
  EXPECT_EQ(printableText(std::string(100, 'y'), 10), "yyyyyyyyyy... (90 more bytes)");
  // Parse errors quote the peer's text made printable, past a NUL too.
  const std::string e1 = parseError(std::string("odom 1 2\x1b[2J 3 4 5 6", 20));
  EXPECT_NE(e1.find("\\x1b[2J"), std::string::npos) << e1;
  const std::string e2 = parseError(std::string("odo\0m 1", 7));
  EXPECT_NE(e2.find("odo\\x00m"), std::string::npos) << e2;
  for (const auto& e : {e1, e2})
    for (char c : e) EXPECT_GE(static_cast<unsigned char>(c), 0x20) << e;
}

TEST(BridgeSafety, ImplausibleNumbersAreRefused) {
  EXPECT_NE(parseError("odom 1 1e300 0 0 0 0").find("x '1e300' is beyond"), std::string::npos);
  EXPECT_NE(parseError("odom 1 0 -1e6 0 0 0").find("y '-1e6' is beyond"), std::string::npos);
  EXPECT_NE(parseError("odom 1 0 0 1e7 0 0").find("yaw"), std::string::npos);
  EXPECT_NE(parseError("odom 1 0 0 0 5000 0").find("v '5000'"), std::string::npos);
  EXPECT_NE(parseError("intent 1e13 0 0").find("time"), std::string::npos);
  EXPECT_NE(parseError("scan 1e300 laser 1 1").find("time"), std::string::npos);
  EXPECT_EQ(parseError("odom 1.7e9 99999 -99999 1000 2 3"), "") << "within the bounds";
}

TEST(BridgeSafety, HugeScansAreReducedKeepingTheNearestReturn) {
  const auto valid = [](float r) { return std::isfinite(r) && r >= 0.1f && r < 30.0f; };
  std::vector<float> big(100000, 5.0f);
  big[123] = 0.4f;     // something close in the first bin
  big[99999] = 0.05f;  // below range_min: not a return
  big[50000] = std::numeric_limits<float>::quiet_NaN();
  const auto r = reduceRanges(big, 1081, valid);
  ASSERT_EQ(r.size(), 1081u);
  EXPECT_FLOAT_EQ(r[1], 0.4f) << "input 123 falls in output bin 1 (92.5 inputs a bin)";
  EXPECT_FLOAT_EQ(r[0], 5.0f);
  EXPECT_FLOAT_EQ(r[1080], 5.0f);
  std::vector<float> none(5000, 0.0f);
  for (float v : reduceRanges(none, 100, valid)) EXPECT_EQ(v, 0.0f) << "no return stays none";
  const std::vector<float> small{1, 2, 3};
  EXPECT_EQ(reduceRanges(small, 1081, valid), small);
}

TEST(BridgeSafety, ADroppedTcpUserEndsTheIntentSource) {
  RobotParams r;
  r.v_max = 0.4;
  r.v_min = -0.2;
  r.w_max = 1;
  auto src = makeIntentSource("tcp:127.0.0.1:0", r);
  const std::string d = src->describe();
  const int port = std::stoi(d.substr(d.rfind(':') + 1));
  LineSocket c = connectTcp("127.0.0.1", port, 5);
  std::optional<IntentSample> s;
  c.sendLine("0.2 0");
  for (int i = 0; i < 50 && !s; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    s = src->poll(1.0);
  }
  ASSERT_TRUE(s);
  EXPECT_FALSE(src->finished(1.0));
  c.close();
  for (int i = 0; i < 50 && !src->finished(2.0); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    src->poll(2.0);
  }
  EXPECT_TRUE(src->finished(2.0)) << "the user left: the run ends and the robot stops";
}

}  // namespace
}  // namespace carenav::navigation
