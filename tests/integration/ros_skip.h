// SKIP_WITHOUT_ROS(): the first line of a test that needs the ROS part and a
// ROS master. Built without the ROS part (CARENAV_WITH_ROS=OFF), or with it
// but without `rosmaster` installed, the test is skipped with the reason.
#pragma once

#include <gtest/gtest.h>

#ifdef CARENAV_TEST_WITH_ROS
#include "ros_nodes_helpers.h"
#define SKIP_WITHOUT_ROS()                \
  if (!carenav_ros_test::haveRosmaster()) \
  GTEST_SKIP() << "no rosmaster (Debian package python3-rosmaster)"
#else
#define SKIP_WITHOUT_ROS() GTEST_SKIP() << "built without the ROS part (CARENAV_WITH_ROS=OFF)"
#endif
