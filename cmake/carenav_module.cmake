# carenav_add_module(<name> SOURCES ... [PUBLIC_DEPS ...] [PRIVATE_DEPS ...])
# Creates the library target carenav_<name> and its alias carenav::<name>,
# with public headers in modules/<name>/include/carenav/<name>/.
function(carenav_add_module name)
  cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(carenav_${name} ${ARG_SOURCES})
  add_library(carenav::${name} ALIAS carenav_${name})
  target_include_directories(carenav_${name} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>)
  target_link_libraries(carenav_${name} PUBLIC ${ARG_PUBLIC_DEPS}
                                        PRIVATE ${ARG_PRIVATE_DEPS})
  target_compile_options(carenav_${name} PRIVATE -Wall -Wextra -Wpedantic)
endfunction()
