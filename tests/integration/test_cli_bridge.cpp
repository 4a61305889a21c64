// `carenav navigate --bridge`: the test plays a robot on the other end of the
// line-based TCP bridge (docs/navigate.md): a differential base in front of a
// wall, its user pushing towards it, and checks the commands carenav sends.
#include <carenav/runtime/line_socket.h>

#include <chrono>
#include <cmath>
#include <future>
#include <sstream>
#include <thread>

#include "cli_helpers.h"

using namespace carenav_test;
using carenav::navigation::LineSocket;
using carenav::navigation::TcpListener;

namespace {

const std::string kInterbot = kSrc + "/ini/interbot.ini";

/** A robot on the floor with a wall across its way at x = wall_x; the
 *  interbot's laser (0.15 m ahead of the axle, 270 deg, 1081 beams). */
struct FakeRobot {
  double x = 0, yaw = 0, v = 0, t = 0;
  double wall_x = 1.4;
  double max_front = 0;  ///< farthest x of the footprint's front (0.3 m ahead)
  std::vector<double> cmds_v, cmds_t;
  std::vector<std::string> received;

  std::string odom() const {
    std::ostringstream o;
    o << "odom " << t << " " << x << " 0 " << yaw << " " << v << " 0";
    return o.str();
  }
  std::string scan() const {
    std::ostringstream o;
    const int n = 1081;
    o << "scan " << t << " laser " << n;
    const double sx = x + 0.15;
    for (int i = 0; i < n; ++i) {
      const double a = -135.0 * M_PI / 180 + i * (270.0 * M_PI / 180) / (n - 1);
      const double c = std::cos(a);
      const double r = c > 1e-3 ? (wall_x - sx) / c : 0.0;
      o << " " << (r > 0 && r < 30 ? r : 0.0);
    }
    return o.str();
  }
  /** Reads carenav's lines; applies the newest command (v only: the user
   *  pushes straight). */
  void readCommands(LineSocket& s) {
    std::vector<std::string> lines;
    s.readLines(lines, 0);
    for (const auto& l : lines) {
      received.push_back(l);
      std::istringstream in(l);
      std::string k;
      double tt, vv, ww;
      if (in >> k && k == "cmd" && in >> tt >> vv >> ww) {
        v = vv;
        cmds_v.push_back(vv);
        cmds_t.push_back(tt);
      }
    }
  }
  void move(double dt) {
    x += v * dt;
    t += dt;
    max_front = std::max(max_front, x + 0.3);
  }
};

/** Starts carenav with the bridge pointing at `port`; the result arrives
 *  when it exits. */
std::future<RunResult> startCarenav(int port, const std::vector<std::string>& extra) {
  std::vector<std::string> args{"navigate",       "--bridge", "127.0.0.1:" + std::to_string(port),
                                "--profile",      kInterbot,  "--plugin",
                                "user-intent-dwa"};
  args.insert(args.end(), extra.begin(), extra.end());
  return std::async(std::launch::async, [args] { return carenav_test::carenav(args); });
}

LineSocket acceptWithin(TcpListener& l, int seconds) {
  for (int i = 0; i < seconds * 10; ++i) {
    LineSocket s = l.accept(100);
    if (s.open()) return s;
  }
  return LineSocket();
}

void sleepMs(int ms) { std::this_thread::sleep_for(std::chrono::milliseconds(ms)); }

}  // namespace

TEST(CliBridge, UserPushesTowardsAWallAndTheRobotStopsBeforeIt) {
  TcpListener listener("127.0.0.1", 0);
  const auto out = scratch() / "bridge_wall";
  fs::remove_all(out);
  auto done = startCarenav(listener.port(), {"--out", out.string()});
  LineSocket s = acceptWithin(listener, 30);
  ASSERT_TRUE(s.open()) << "carenav did not connect";
  FakeRobot r;
  // 12 s of robot time at 20 Hz: the user pushes at 0.25 m/s towards a wall
  // 1.1 m ahead of the front; free, that would be 3 m.
  for (int k = 0; k < 240; ++k) {
    s.sendLine(r.odom());
    if (k % 2 == 0) s.sendLine(r.scan());
    s.sendLine("intent " + std::to_string(r.t) + " 0.25 0");
    sleepMs(50);
    r.readCommands(s);
    r.move(0.05);
  }
  s.sendLine("bye");
  sleepMs(300);
  r.readCommands(s);
  const RunResult res = done.get();
  ASSERT_EQ(res.code, 0) << res.err;
  EXPECT_GT(r.x, 0.4) << "the robot should follow its user while the way is free";
  EXPECT_LT(r.max_front, r.wall_x - 0.05) << "the footprint came within 5 cm of the wall";
  ASSERT_FALSE(r.cmds_v.empty());
  EXPECT_NEAR(r.cmds_v.back(), 0.0, 1e-3) << "pushed against the wall, the robot must stand";
  EXPECT_EQ(r.received.front().rfind("hello carenav 1 interbot", 0), 0u) << r.received.front();
  EXPECT_EQ(r.received.back(), "stop robot said bye");
  EXPECT_TRUE(fs::exists(out / "run.png"));
  const std::string log = slurp(out / "navlog.csv");
  EXPECT_NE(log.find("user_v,user_w"), std::string::npos);
  EXPECT_NE(slurp(out / "summary.json").find("\"success\": true"), std::string::npos);
}

TEST(CliBridge, StopsWhenTheScansStopComing) {
  TcpListener listener("127.0.0.1", 0);
  auto done = startCarenav(listener.port(), {});
  LineSocket s = acceptWithin(listener, 30);
  ASSERT_TRUE(s.open()) << "carenav did not connect";
  FakeRobot r;
  r.wall_x = 20;  // free space ahead
  size_t moving = 0, after_silence = 0, zero_after_silence = 0;
  for (int k = 0; k < 160; ++k) {
    const bool scans = k < 60;  // the laser goes silent after 3 s
    s.sendLine(r.odom());
    if (scans && k % 2 == 0) s.sendLine(r.scan());
    s.sendLine("intent " + std::to_string(r.t) + " 0.2 0");
    sleepMs(50);
    const size_t before = r.cmds_v.size();
    r.readCommands(s);
    for (size_t i = before; i < r.cmds_v.size(); ++i) {
      if (scans) moving += r.cmds_v[i] > 0.05;
      // From 3 s after the silence on (sensor_timeout is well below that):
      if (k >= 120) {
        ++after_silence;
        zero_after_silence += std::abs(r.cmds_v[i]) < 1e-6;
      }
    }
    r.move(0.05);
  }
  s.sendLine("bye");
  const RunResult res = done.get();
  ASSERT_EQ(res.code, 0) << res.err;
  EXPECT_GT(moving, 10u) << "with fresh scans the robot follows its user";
  ASSERT_GT(after_silence, 10u);
  EXPECT_EQ(zero_after_silence, after_silence) << "stale scans must stop the robot";
}

TEST(CliBridge, MalformedMessageStopsTheRobotAndExits2) {
  TcpListener listener("127.0.0.1", 0);
  const auto out = scratch() / "bridge_bad";
  fs::remove_all(out);
  auto done = startCarenav(listener.port(), {"--out", out.string()});
  LineSocket s = acceptWithin(listener, 30);
  ASSERT_TRUE(s.open());
  FakeRobot r;
  for (int k = 0; k < 10; ++k) {
    s.sendLine(r.odom());
    s.sendLine(r.scan());
    sleepMs(50);
  }
  s.sendLine("odom 1.0 2.0");  // truncated
  const RunResult res = done.get();
  EXPECT_EQ(res.code, 2) << res.err;
  EXPECT_NE(res.err.find("line 21"), std::string::npos) << res.err;
  EXPECT_NE(res.err.find("odom T X Y YAW V W"), std::string::npos) << res.err;
  sleepMs(100);
  r.readCommands(s);
  ASSERT_GE(r.received.size(), 2u);
  EXPECT_EQ(r.received.back(), "stop error");
  EXPECT_NEAR(r.cmds_v.back(), 0.0, 1e-9);
  EXPECT_TRUE(fs::exists(out / "summary.json")) << "what was recorded is kept";
}

TEST(CliBridge, ConnectionLostWithoutByeExits2) {
  TcpListener listener("127.0.0.1", 0);
  auto done = startCarenav(listener.port(), {});
  {
    LineSocket s = acceptWithin(listener, 30);
    ASSERT_TRUE(s.open());
    FakeRobot r;
    s.sendLine(r.odom());
    sleepMs(200);
  }  // the robot goes away without 'bye'
  const RunResult res = done.get();
  EXPECT_EQ(res.code, 2) << res.err;
  EXPECT_NE(res.err.find("closed the connection without 'bye'"), std::string::npos) << res.err;
}

TEST(CliBridge, UnreachableRobotExits2) {
  // A port nobody listens on: bind one, learn its number, close it.
  int port;
  {
    TcpListener l("127.0.0.1", 0);
    port = l.port();
  }
  const RunResult res = carenav_test::carenav(
      {"navigate", "--bridge", "127.0.0.1:" + std::to_string(port), "--profile", kInterbot,
       "--plugin", "user-intent-dwa", "--connect-timeout", "0.5"});
  EXPECT_EQ(res.code, 2);
  EXPECT_NE(res.err.find("cannot connect"), std::string::npos) << res.err;
}

// ------------------------------------------------------------ every way a connection ends

namespace {

/** Waits for carenav's next command (it sends one per control cycle);
 *  false when none came within `ms` (or the connection ended). */
bool awaitCommand(LineSocket& s, FakeRobot& r, int ms = 5000) {
  const size_t before = r.cmds_v.size();
  for (int waited = 0; waited < ms && r.cmds_v.size() == before; waited += 20) {
    std::vector<std::string> lines;
    const bool alive = s.readLines(lines, 20);
    for (const auto& l : lines) {
      r.received.push_back(l);
      std::istringstream in(l);
      std::string k;
      double tt, vv, ww;
      if (in >> k && k == "cmd" && in >> tt >> vv >> ww) {
        r.v = vv;
        r.cmds_v.push_back(vv);
        r.cmds_t.push_back(tt);
      }
    }
    if (!alive) break;
  }
  return r.cmds_v.size() > before;
}

/** Reads whatever carenav still sends until it closes (at most `ms`). */
void drain(LineSocket& s, FakeRobot& r, int ms = 10000) {
  for (int waited = 0; waited < ms; waited += 20) {
    std::vector<std::string> lines;
    const bool alive = s.readLines(lines, 20);
    for (const auto& l : lines) {
      r.received.push_back(l);
      std::istringstream in(l);
      std::string k;
      double tt, vv, ww;
      if (in >> k && k == "cmd" && in >> tt >> vv >> ww) {
        r.v = vv;
        r.cmds_v.push_back(vv);
        r.cmds_t.push_back(tt);
      }
    }
    if (!alive) return;
  }
}

/** Drives in lock-step with carenav (one message batch per command) for
 *  `cycles` cycles: odometry, the user pushing at 0.2 m/s, and scans of a
 *  free way ahead while `scans(k)`. */
template <class F>
void lockStep(LineSocket& s, FakeRobot& r, int cycles, F scans) {
  for (int k = 0; k < cycles; ++k) {
    if (scans(k)) s.sendLine(r.scan());
    s.sendLine(r.odom());
    s.sendLine("intent " + std::to_string(r.t) + " 0.2 0");
    if (!awaitCommand(s, r)) return;
    r.move(0.1);
  }
}

}  // namespace

TEST(CliBridge, HalfClosedConnectionGetsZeroVelocityAndStop) {
  TcpListener listener("127.0.0.1", 0);
  const auto out = scratch() / "bridge_halfclose";
  fs::remove_all(out);
  auto done = startCarenav(listener.port(), {"--out", out.string()});
  LineSocket s = acceptWithin(listener, 30);
  ASSERT_TRUE(s.open());
  FakeRobot r;
  r.wall_x = 20;
  lockStep(s, r, 30, [](int) { return true; });
  ASSERT_GT(r.cmds_v.size(), 20u);
  EXPECT_GT(r.cmds_v.back(), 0.05) << "the user was being followed";
  s.shutdownWrite();  // the robot sends no more but still listens
  drain(s, r);
  const RunResult res = done.get();
  EXPECT_EQ(res.code, 2) << res.err;
  EXPECT_NE(res.err.find("closed the connection without 'bye'"), std::string::npos) << res.err;
  ASSERT_GE(r.received.size(), 2u);
  EXPECT_EQ(r.received.back(), "stop error");
  EXPECT_NEAR(r.cmds_v.back(), 0.0, 1e-9) << "the last command stands the robot still";
  EXPECT_TRUE(fs::exists(out / "summary.json"));
}

TEST(CliBridge, ResetConnectionExits2AndKeepsTheOutputs) {
  TcpListener listener("127.0.0.1", 0);
  const auto out = scratch() / "bridge_reset";
  fs::remove_all(out);
  auto done = startCarenav(listener.port(), {"--out", out.string()});
  LineSocket s = acceptWithin(listener, 30);
  ASSERT_TRUE(s.open());
  FakeRobot r;
  r.wall_x = 20;
  lockStep(s, r, 10, [](int) { return true; });
  s.sendLine(r.odom());
  s.abort();  // RST: the robot's side is gone at once
  const RunResult res = done.get();
  EXPECT_EQ(res.code, 2) << res.err;
  EXPECT_TRUE(res.err.find("reset") != std::string::npos ||
              res.err.find("without 'bye'") != std::string::npos)
      << res.err;
  EXPECT_TRUE(fs::exists(out / "summary.json"));
}

TEST(CliBridge, SilentRobotIsStoppedThenTheRunEnds) {
  TcpListener listener("127.0.0.1", 0);
  auto done = startCarenav(listener.port(), {"--silence-timeout", "1.5"});
  LineSocket s = acceptWithin(listener, 30);
  ASSERT_TRUE(s.open());
  FakeRobot r;
  r.wall_x = 20;
  lockStep(s, r, 20, [](int) { return true; });
  const size_t before = r.cmds_v.size();
  drain(s, r, 30000);  // connected, reading, silent
  const RunResult res = done.get();
  EXPECT_EQ(res.code, 2) << res.err;
  EXPECT_NE(res.err.find("sent nothing for 1.5 s"), std::string::npos) << res.err;
  ASSERT_GE(r.received.size(), 2u);
  EXPECT_EQ(r.received.back(), "stop error");
  ASSERT_GT(r.cmds_v.size(), before + 5) << "commands went on while it was silent";
  EXPECT_NEAR(r.cmds_v.back(), 0.0, 1e-9);
  // Cycles 0.1 s apart at least 0.09 s: within the 1.5 s, at most 6 (0.5 s
  // sensor_timeout / 0.09 s) moved on the last scan; the rest stood still.
  size_t moving = 0;
  for (size_t i = before; i < r.cmds_v.size(); ++i) moving += r.cmds_v[i] > 1e-6;
  EXPECT_LE(moving, 6u);
}

TEST(CliBridge, StaleScansStopTheRobotWithinSensorTimeoutPlusOnePeriod) {
  // Lock-step at carenav's rate (10 Hz, sensor_timeout 0.5 s): after the
  // last scan, commands computed on it (those whose robot time is at least
  // the scan's) may move for at most 0.5 s: 6 cycles (cycles are at least
  // 0.9 periods apart). The robot obeys each for one period: the stale-data
  // bound is sensor_timeout + one period (docs/navigate.md).
  TcpListener listener("127.0.0.1", 0);
  auto done = startCarenav(listener.port(), {});
  LineSocket s = acceptWithin(listener, 30);
  ASSERT_TRUE(s.open());
  FakeRobot r;
  r.wall_x = 20;
  const int last_scan = 30;
  double t_last = 0;
  lockStep(s, r, 80, [&](int k) {
    if (k == last_scan) t_last = r.t;
    return k <= last_scan;
  });
  s.sendLine("bye");
  drain(s, r);
  const RunResult res = done.get();
  ASSERT_EQ(res.code, 0) << res.err;
  size_t before = 0, moving_after = 0, after = 0;
  for (size_t i = 0; i < r.cmds_v.size(); ++i) {
    if (r.cmds_t[i] < t_last - 1e-6) {
      before += r.cmds_v[i] > 0.05;
      continue;
    }
    ++after;
    moving_after += r.cmds_v[i] > 1e-6;
  }
  EXPECT_GT(before, 10u) << "with fresh scans the robot follows its user";
  EXPECT_GT(after, 30u);
  EXPECT_GE(moving_after, 1u) << "a fresh scan is used at once";
  EXPECT_LE(moving_after, 6u) << "moving commands on a scan older than sensor_timeout";
  EXPECT_NEAR(r.cmds_v.back(), 0.0, 1e-9);
}

TEST(CliBridge, HugeScanLinesAreUsedAndDoNotStallTheLoop) {
  // 100,000-beam scans (about 400 kB a line) with a wall 0.3 m ahead of the
  // laser (0.15 m ahead of the footprint, safe_distance 0.2 m): they are reduced to the profile's
  // 1081 beams (the nearest return of each share), so the wall is seen and the user's push is
  // refused, and carenav answers every batch with a command (lock-step).
  TcpListener listener("127.0.0.1", 0);
  auto done = startCarenav(listener.port(), {});
  LineSocket s = acceptWithin(listener, 30);
  ASSERT_TRUE(s.open());
  FakeRobot r;
  const int n = 100000;
  auto hugeScan = [&] {
    std::ostringstream o;
    o << "scan " << r.t << " laser " << n;
    for (int i = 0; i < n; ++i) {
      const double a = -135.0 * M_PI / 180 + i * (270.0 * M_PI / 180) / (n - 1);
      const double c = std::cos(a);
      const double d = c > 1e-3 ? 0.3 / c : 0.0;
      o << " " << (d > 0 && d < 30 ? d : 0.0);
    }
    return o.str();
  };
  int answered = 0;
  for (int k = 0; k < 15; ++k) {
    s.sendLine(hugeScan());
    s.sendLine(r.odom());
    s.sendLine("intent " + std::to_string(r.t) + " 0.3 0");
    answered += awaitCommand(s, r, 20000);
    r.t += 0.1;
  }
  s.sendLine("bye");
  drain(s, r);
  const RunResult res = done.get();
  ASSERT_EQ(res.code, 0) << res.err;
  EXPECT_EQ(answered, 15);
  ASSERT_FALSE(r.cmds_v.empty());
  size_t moving = 0;
  for (double v : r.cmds_v) moving += v > 1e-6;
  EXPECT_EQ(moving, 0u) << "the wall 0.15 m ahead of the footprint must hold the robot";
}

TEST(CliBridge, ImplausibleOdometryAndRawBytesAreRefusedPrintably) {
  for (const std::string bad :
       {std::string("odom 1 1e300 0 0 0 0"), std::string("odom 1 \x1b[2J\x07 0 0 0 0"),
        std::string("odo\0m 1 2 3", 11)}) {
    TcpListener listener("127.0.0.1", 0);
    auto done = startCarenav(listener.port(), {});
    LineSocket s = acceptWithin(listener, 30);
    ASSERT_TRUE(s.open());
    FakeRobot r;
    s.sendLine(r.odom());
    s.sendLine(bad);
    drain(s, r);
    const RunResult res = done.get();
    EXPECT_EQ(res.code, 2) << res.err;
    EXPECT_NE(res.err.find("line 2"), std::string::npos) << res.err;
    for (char c : res.err)
      if (c != '\n') EXPECT_GE(static_cast<unsigned char>(c), 0x20) << res.err;
    EXPECT_TRUE(res.err.find("beyond") != std::string::npos ||
                res.err.find("\\x1b[2J\\x07") != std::string::npos ||
                res.err.find("odo\\x00m") != std::string::npos)
        << res.err;
    ASSERT_FALSE(r.received.empty());
    EXPECT_EQ(r.received.back(), "stop error");
  }
}
