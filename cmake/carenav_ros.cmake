# The optional ROS 1 part (modules/ros: `.bag` input, `carenav import rosbag`,
# `carenav ros <node>`; docs/ros.md), from Debian's ROS 1 packages
# (scripts/setup.sh). CARENAV_WITH_ROS: AUTO (default: on when the packages
# are found), ON (they must be) or OFF. Sets CARENAV_ROS (bool).
set(CARENAV_WITH_ROS AUTO CACHE STRING "Build the ROS 1 part: AUTO (when found), ON or OFF")
set_property(CACHE CARENAV_WITH_ROS PROPERTY STRINGS AUTO ON OFF)

set(CARENAV_ROS OFF)
if(NOT CARENAV_WITH_ROS STREQUAL "OFF")
  # Libraries found directly: the catkin configs of Debian's packages pull
  # in pluginlib and ament, whose CMake code runs Python modules a build
  # machine need not have.
  set(_missing "")
  set(CARENAV_ROS_LIBRARIES "")
  foreach(_l roscpp roscpp_serialization rostime cpp_common rosconsole rosbag_storage roslz4
             console_bridge xmlrpcpp)
    find_library(CARENAV_ROS_LIB_${_l} ${_l})
    mark_as_advanced(CARENAV_ROS_LIB_${_l})
    if(CARENAV_ROS_LIB_${_l})
      list(APPEND CARENAV_ROS_LIBRARIES ${CARENAV_ROS_LIB_${_l}})
    else()
      list(APPEND _missing lib${_l})
    endif()
  endforeach()
  # bz2-compressed chunks of bags
  find_package(BZip2 QUIET)
  if(NOT BZIP2_FOUND)
    list(APPEND _missing libbz2-dev)
  endif()
  # Message packages are headers only.
  foreach(_h ros/ros.h rosbag/bag.h sensor_msgs/LaserScan.h nav_msgs/Odometry.h nav_msgs/Path.h geometry_msgs/Twist.h
             tf2_msgs/TFMessage.h rosgraph_msgs/Clock.h std_msgs/String.h roslz4/lz4s.h)
    string(MAKE_C_IDENTIFIER "CARENAV_ROS_HDR_${_h}" _var)
    find_path(${_var} ${_h})
    mark_as_advanced(${_var})
    if(NOT ${_var})
      list(APPEND _missing ${_h})
    endif()
  endforeach()
  # rosbag/bag.h includes pluginlib's and class_loader's headers, installed
  # one folder down (ROS 2 style).
  set(CARENAV_ROS_INCLUDE_DIRS "")
  foreach(_p pluginlib/class_loader.hpp:pluginlib class_loader/class_loader.hpp:class_loader
             rcutils/types.h:rcutils rcpputils/filesystem_helper.hpp:rcpputils
             ament_index_cpp/get_resource.hpp:ament_index_cpp)
    string(REPLACE ":" ";" _p "${_p}")
    list(GET _p 0 _h)
    list(GET _p 1 _sub)
    string(MAKE_C_IDENTIFIER "CARENAV_ROS_HDR_${_h}" _var)
    find_path(${_var} ${_h} PATH_SUFFIXES ${_sub})
    mark_as_advanced(${_var})
    if(${_var})
      list(APPEND CARENAV_ROS_INCLUDE_DIRS ${${_var}})
    else()
      list(APPEND _missing ${_h})
    endif()
  endforeach()
  if(_missing STREQUAL "")
    set(CARENAV_ROS ON)
  elseif(CARENAV_WITH_ROS STREQUAL "ON")
    message(FATAL_ERROR "CARENAV_WITH_ROS=ON, but missing: ${_missing} (bash scripts/setup.sh)")
  else()
    message(STATUS "carenav: no ROS part (missing: ${_missing})")
  endif()
endif()
if(CARENAV_ROS)
  message(STATUS "carenav: with the ROS part (ROS 1: roscpp, rosbag storage)")
endif()
