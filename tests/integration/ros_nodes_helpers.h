// What the tests of carenav's ROS nodes share: one rosmaster per test
// program (roscpp initialises once per process, so the program's own node
// talks to one master), a folder per test, node names of the test's own,
// the program's own node and carenav nodes started as processes. Only with
// the ROS part.
#pragma once

#include <ros/ros.h>

#include "cli_helpers.h"
#include "ros_master.h"

#include <gtest/gtest.h>

#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace carenav_ros_test {

inline bool haveRosmaster() { return std::system("command -v rosmaster >/dev/null 2>&1") == 0; }

inline RosMaster& sharedMaster() {
  static RosMaster m(carenav_test::scratch());
  return m;
}

inline fs::path testDir() {
  const auto d =
      sharedMaster().dir() / ::testing::UnitTest::GetInstance()->current_test_info()->name();
  fs::create_directories(d);
  return d;
}

/** A room or a place of apartmentWith(): name and "x0,y0,x1,y1" or "x,y,deg". */
struct Named {
  std::string name, where;
};

/** The apartment world copied into `dir` with a places file beside it
 *  (`carenav places add-room` / `add-place`); returns the world's YAML. */
inline fs::path apartmentWith(const fs::path& dir, const std::vector<Named>& rooms,
                              const std::vector<Named>& places = {}) {
  using carenav_test::carenav;
  using carenav_test::kSrc;
  for (const char* f : {"apartment.yaml", "apartment.png"})
    fs::copy_file(kSrc + "/maps/worlds/" + f, dir / f, fs::copy_options::overwrite_existing);
  const std::string file = (dir / "apartment.places.yaml").string();
  fs::remove(file);
  for (const auto& r : rooms)
    EXPECT_EQ(carenav({"-q", "places", "add-room", r.name, "--rect", r.where, "--file", file}).code,
              0)
        << r.name;
  for (const auto& p : places)
    EXPECT_EQ(
        carenav({"-q", "places", "add-place", p.name, "--pose", p.where, "--file", file}).code, 0)
        << p.name;
  return dir / "apartment.yaml";
}

/** A node name of the test's own: private parameters stay on the shared
 *  master under the node's name after it ends. */
inline std::string nodeName(const std::string& node) {
  return "__name:=" + node + "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name();
}

/** This program's own ROS node (once; never shut down before exit). */
inline void initTestNode() {
  static const bool done = [] {
    int argc = 1;
    char name[] = "test";
    char* argv[] = {name, nullptr};
    ::ros::init(argc, argv, "carenav_test", ::ros::init_options::NoSigintHandler);
    return true;
  }();
  (void)done;
}

/** `carenav -q ros NODE __name:=NAME_<test> ARGS...`, its output in DIR/NAME.log
 *  (NAME: the node's unless given). */
inline pid_t startRosNode(const fs::path& dir, const std::string& node,
                          const std::vector<std::string>& args, std::string name = "") {
  if (name.empty()) name = node;
  std::vector<std::string> argv{carenav_test::kBin, "-q", "ros", node, nodeName(name)};
  argv.insert(argv.end(), args.begin(), args.end());
  return spawn(argv, dir / (name + ".log"));
}

/** The messages of one topic as this program's node receives them, all
 *  kept (call spin() from a ros::AsyncSpinner of the test). */
template <class M>
class TopicLog {
 public:
  explicit TopicLog(const std::string& topic) {
    sub_ = nh_.subscribe<M>(topic, 50, [this](const typename M::ConstPtr& m) {
      std::lock_guard<std::mutex> l(mu_);
      all_.push_back(*m);
    });
  }
  ~TopicLog() { sub_.shutdown(); }
  size_t count() const {
    std::lock_guard<std::mutex> l(mu_);
    return all_.size();
  }
  std::optional<M> last() const {
    std::lock_guard<std::mutex> l(mu_);
    if (all_.empty()) return std::nullopt;
    return all_.back();
  }
  std::vector<M> all() const {
    std::lock_guard<std::mutex> l(mu_);
    return all_;
  }

 private:
  const bool init_ = (initTestNode(), true);  // before the node handle
  ::ros::NodeHandle nh_;
  ::ros::Subscriber sub_;
  mutable std::mutex mu_;
  std::vector<M> all_;
};

}  // namespace carenav_ros_test
