// What every carenav node does at start and while it runs (node_init.cpp).
#pragma once

#include <carenav/ros/nodes.h>
#include <carenav/runtime/session.h>

#include <atomic>
#include <string>
#include <vector>

namespace carenav::ros {

/** The profile read before ROS (bad input: exit 2 before any master is
 *  needed), the node started (initRosNode), then read again with its
 *  private parameters (privateParamOverrides, but for `node_keys`; `sets`
 *  win over them). */
navigation::SessionSetup startNode(const std::string& node, const std::string& profile,
                                   const std::vector<std::string>& sets, const std::string& plugin,
                                   const std::vector<std::string>& ros_args,
                                   const std::vector<std::string>& node_keys = {});

/** Handles messages until ROS ends, `stop` is set or `duration` s (0: no
 *  limit) have passed on the wall clock. */
void spinNode(double duration, const std::atomic<bool>* stop);

}  // namespace carenav::ros
