#include <carenav/common/errors.h>
#include <carenav/ros/nodes.h>

#include "node_common.h"

#include <ros/callback_queue.h>
#include <ros/master.h>
#include <ros/ros.h>

#include <xmlrpcpp/XmlRpcValue.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <sstream>
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

namespace {

std::string paramText(XmlRpc::XmlRpcValue& v) {
  switch (v.getType()) {
    case XmlRpc::XmlRpcValue::TypeBoolean:
      return static_cast<bool>(v) ? "true" : "false";
    case XmlRpc::XmlRpcValue::TypeInt:
      return std::to_string(static_cast<int>(v));
    case XmlRpc::XmlRpcValue::TypeDouble: {
      std::ostringstream o;
      o.precision(17);
      o << static_cast<double>(v);
      return o.str();
    }
    case XmlRpc::XmlRpcValue::TypeString:
      return static_cast<std::string>(v);
    default:
      throw InputError("ROS parameter of a type a profile key cannot take (lists, maps)");
  }
}

}  // namespace

std::string overrideFromParam(const std::string& relative_name, const std::string& value) {
  const size_t last = relative_name.rfind('/');
  if (last == std::string::npos || last == 0) return "";
  std::string section = relative_name.substr(0, last);
  std::replace(section.begin(), section.end(), '/', '.');
  return section + "." + relative_name.substr(last + 1) + "=" + value;
}

std::vector<std::string> privateParamOverrides(const std::vector<std::string>& node_keys) {
  std::vector<std::string> names, out;
  if (!::ros::param::getParamNames(names)) return out;
  const std::string prefix = ::ros::this_node::getName() + "/";
  std::sort(names.begin(), names.end());
  for (const auto& n : names) {
    if (n.compare(0, prefix.size(), prefix) != 0) continue;
    XmlRpc::XmlRpcValue v;
    if (!::ros::param::get(n, v)) continue;
    const std::string rel = n.substr(prefix.size());
    if (std::find(node_keys.begin(), node_keys.end(), rel) != node_keys.end()) continue;
    std::string text;
    try {
      text = paramText(v);
    } catch (const InputError& e) {
      throw InputError("~" + rel + ": " + e.what());
    }
    const std::string set = overrideFromParam(rel, text);
    if (set.empty())
      throw InputError("~" + rel +
                       ": not a profile key (give ~section/key, e.g. ~navigation/v_max)");
    out.push_back(set);
  }
  return out;
}

navigation::SessionSetup startNode(const std::string& node, const std::string& profile,
                                   const std::vector<std::string>& sets, const std::string& plugin,
                                   const std::vector<std::string>& ros_args,
                                   const std::vector<std::string>& node_keys) {
  auto setup = navigation::sessionSetup(profile, sets, plugin);
  initRosNode(node, ros_args);
  if (auto params = privateParamOverrides(node_keys); !params.empty()) {
    params.insert(params.end(), sets.begin(), sets.end());
    setup = navigation::sessionSetup(profile, params, plugin);
  }
  return setup;
}

void spinNode(double duration, const std::atomic<bool>* stop) {
  const ::ros::WallTime wall0 = ::ros::WallTime::now();
  while (::ros::ok() && !(stop && stop->load())) {
    if (duration > 0 && (::ros::WallTime::now() - wall0).toSec() >= duration) break;
    ::ros::getGlobalCallbackQueue()->callAvailable(::ros::WallDuration(0.1));
  }
}

}  // namespace carenav::ros
