# ROS 1 as Debian 12 packages it (roscpp, rosbag, tf2_ros, message_filters and the message
# headers; scripts/setup.sh installs them). Debian ships pkg-config files for most of them but
# rosbag's needs pluginlib, whose Debian package (the ROS 2 one) has none, so the headers and
# libraries are found one by one. Defines DUET_HAVE_ROS and the INTERFACE target duet_ros_deps.
# Nothing of the core library depends on it (DESIGN.md: the core never sees ROS).
set(DUET_HAVE_ROS OFF)
if(NOT DUET_WITH_ROS)
  return()
endif()
set(_duet_ros_headers ros/ros.h rosbag/bag.h tf2_ros/transform_broadcaster.h message_filters/synchronizer.h
    sensor_msgs/Image.h nav_msgs/OccupancyGrid.h visualization_msgs/MarkerArray.h std_srvs/Trigger.h
    rosgraph_msgs/Clock.h)
set(_duet_ros_missing "")
foreach(h IN LISTS _duet_ros_headers)
  string(MAKE_C_IDENTIFIER "DUET_ROS_H_${h}" _var)
  find_path(${_var} ${h})
  if(NOT ${_var})
    list(APPEND _duet_ros_missing ${h})
  endif()
endforeach()
# rosbag/bag.h includes pluginlib's and class_loader's headers, which Debian installs one level down.
find_path(DUET_ROS_PLUGINLIB_DIR pluginlib/class_loader.hpp PATH_SUFFIXES pluginlib)
find_path(DUET_ROS_CLASS_LOADER_DIR class_loader/class_loader.hpp PATH_SUFFIXES class_loader)
find_path(DUET_ROS_RCPPUTILS_DIR rcpputils/shared_library.hpp PATH_SUFFIXES rcpputils)
find_path(DUET_ROS_RCUTILS_DIR rcutils/types.h PATH_SUFFIXES rcutils)
find_path(DUET_ROS_AMENT_DIR ament_index_cpp/get_package_prefix.hpp PATH_SUFFIXES ament_index_cpp)
foreach(d DUET_ROS_PLUGINLIB_DIR DUET_ROS_CLASS_LOADER_DIR DUET_ROS_RCPPUTILS_DIR DUET_ROS_RCUTILS_DIR DUET_ROS_AMENT_DIR)
  if(NOT ${d})
    list(APPEND _duet_ros_missing ${d})
  endif()
endforeach()
set(_duet_ros_libs roscpp rosconsole roscpp_serialization rostime xmlrpcpp cpp_common rosbag rosbag_storage
    tf2_ros tf2 message_filters console_bridge boost_system boost_thread)
set(_duet_ros_lib_paths "")
foreach(l IN LISTS _duet_ros_libs)
  find_library(DUET_ROS_LIB_${l} ${l})
  if(DUET_ROS_LIB_${l})
    list(APPEND _duet_ros_lib_paths ${DUET_ROS_LIB_${l}})
  else()
    list(APPEND _duet_ros_missing lib${l})
  endif()
endforeach()
if(_duet_ros_missing)
  message(STATUS "duet: ROS 1 not found (missing: ${_duet_ros_missing}); the ROS node, the simulator bridge "
                 "and bag replay are not built (scripts/setup.sh installs Debian's ROS packages)")
  return()
endif()
add_library(duet_ros_deps INTERFACE)
target_include_directories(duet_ros_deps SYSTEM INTERFACE ${DUET_ROS_PLUGINLIB_DIR} ${DUET_ROS_CLASS_LOADER_DIR}
  ${DUET_ROS_RCPPUTILS_DIR} ${DUET_ROS_RCUTILS_DIR} ${DUET_ROS_AMENT_DIR})
target_link_libraries(duet_ros_deps INTERFACE ${_duet_ros_lib_paths})
set(DUET_HAVE_ROS ON)
message(STATUS "duet: ROS 1 found; building duet_ros (node), duet_sim_ros (simulator bridge) and bag replay")
