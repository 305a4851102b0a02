# Installs the build tree into a scratch prefix and builds/runs the consumer.
file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)

# Runs one step (the command after `what`); stops with `what` named if it fails.
function(consumer_step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc)
  if(rc)
    message(FATAL_ERROR "${what} failed (${rc})")
  endif()
endfunction()

consumer_step("install" ${CMAKE_COMMAND} --install ${PLSA_BUILD_DIR} --prefix ${prefix})
# Components predict and io need Eigen alone: NLopt and pkg-config (LCM) are hidden from it.
consumer_step("configuring the consumer against ${prefix}"
  ${CMAKE_COMMAND} -S ${CONSUMER_SOURCE_DIR} -B ${WORK_DIR}/build -G ${GENERATOR} -DCMAKE_PREFIX_PATH=${prefix}
  -DCMAKE_DISABLE_FIND_PACKAGE_NLopt=TRUE -DCMAKE_DISABLE_FIND_PACKAGE_PkgConfig=TRUE)
consumer_step("building the consumer" ${CMAKE_COMMAND} --build ${WORK_DIR}/build)
consumer_step("the consumer" ${WORK_DIR}/build/consumer)

# No components: every one this install has, each target defined.
file(WRITE ${WORK_DIR}/all/CMakeLists.txt "cmake_minimum_required(VERSION 3.16)
project(plsa_all LANGUAGES CXX)
find_package(plsa 0.2 REQUIRED)
foreach(t core predict io model eval identify sim can can_sim diagnose report)
  if(NOT TARGET plsa::\${t})
    message(FATAL_ERROR \"plsa::\${t} missing\")
  endif()
endforeach()
")
consumer_step("find_package(plsa) with every component"
  ${CMAKE_COMMAND} -S ${WORK_DIR}/all -B ${WORK_DIR}/all/build -G ${GENERATOR} -DCMAKE_PREFIX_PATH=${prefix})

# The examples, built on their own against the installed package (the
# project's own build runs them).
consumer_step("configuring examples/ against ${prefix}"
  ${CMAKE_COMMAND} -S ${EXAMPLES_SOURCE_DIR} -B ${WORK_DIR}/examples -G ${GENERATOR} -DCMAKE_PREFIX_PATH=${prefix})
consumer_step("building examples/ against ${prefix}" ${CMAKE_COMMAND} --build ${WORK_DIR}/examples)

# The same program without CMake, through pkg-config (predict, model, io).
find_program(PKG_CONFIG pkg-config)
if(NOT PKG_CONFIG)
  message(STATUS "pkg-config not found: the pkg-config build is skipped")
  return()
endif()
set(ENV{PKG_CONFIG_PATH} ${prefix}/lib/pkgconfig)
execute_process(COMMAND ${PKG_CONFIG} --cflags --libs plsa OUTPUT_VARIABLE flags RESULT_VARIABLE rc
                OUTPUT_STRIP_TRAILING_WHITESPACE)
if(rc)
  message(FATAL_ERROR "pkg-config knows no plsa under ${prefix}/lib/pkgconfig (${rc})")
endif()
separate_arguments(flags UNIX_COMMAND "${flags}")
consumer_step("building the consumer with pkg-config's flags (${flags})"
  c++ -std=c++17 ${CONSUMER_SOURCE_DIR}/main.cpp ${flags} -o ${WORK_DIR}/consumer_pc)
consumer_step("the pkg-config consumer" ${WORK_DIR}/consumer_pc)
