#include <carenav/common/errors.h>
#include <carenav/ros/nodes.h>

#include <ros/master.h>
#include <ros/ros.h>

#include <chrono>
#include <cstdlib>
#include <thread>

namespace carenav::ros {

void initRosNode(const std::string& name, const std::vector<std::string>& ros_args, double wait_s) {
  std::vector<std::string> args{"carenav"};
  args.insert(args.end(), ros_args.begin(), ros_args.end());
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  int argc = static_cast<int>(argv.size());
  // carenav handles SIGINT itself (the robot stops, outputs are written).
  ::ros::init(argc, argv.data(), name, ::ros::init_options::NoSigintHandler);
  for (int i = 1; i < argc; ++i)
    throw InputError(std::string("unknown argument '") + argv[i] +
                     "' (ROS arguments: from:=to, _param:=value, __name:=node)");
  const auto t0 = std::chrono::steady_clock::now();
  while (!::ros::master::check()) {
    if (std::chrono::steady_clock::now() - t0 > std::chrono::duration<double>(wait_s)) {
      const char* uri = std::getenv("ROS_MASTER_URI");
      throw InputError(std::string("no ROS master at ") + (uri ? uri : "(ROS_MASTER_URI unset)") +
                       " after " + std::to_string(static_cast<int>(wait_s)) + " s");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
}

}  // namespace carenav::ros
