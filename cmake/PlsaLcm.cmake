# LCM from pkg-config (Debian ships no CMake config for it) and a helper that
# runs lcm-gen on .lcm files into an INTERFACE target of C++ headers.
find_package(PkgConfig REQUIRED)
pkg_check_modules(LCM REQUIRED IMPORTED_TARGET lcm)
find_program(LCM_GEN_EXECUTABLE lcm-gen REQUIRED)

function(plsa_lcm_generate target)
  set(out_dir ${CMAKE_CURRENT_BINARY_DIR}/lcmtypes)
  set(headers)
  foreach(src ${ARGN})
    get_filename_component(abs ${src} ABSOLUTE)
    get_filename_component(name ${src} NAME_WE)
    set(hpp ${out_dir}/plsa_lcm/${name}.hpp)
    add_custom_command(OUTPUT ${hpp}
      COMMAND ${LCM_GEN_EXECUTABLE} --cpp --cpp-hpath ${out_dir} ${abs}
      DEPENDS ${abs}
      COMMENT "lcm-gen ${name}"
      VERBATIM)
    list(APPEND headers ${hpp})
  endforeach()
  add_custom_target(${target}_gen DEPENDS ${headers})
  add_library(${target} INTERFACE)
  add_dependencies(${target} ${target}_gen)
  set_target_properties(${target} PROPERTIES EXPORT_NAME lcmtypes)
  target_include_directories(${target} INTERFACE
    $<BUILD_INTERFACE:${out_dir}>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  install(DIRECTORY ${out_dir}/plsa_lcm DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endfunction()

# The same types as Java classes in a jar (lcm-gen -j, javac against lcm.jar)
# for lcm-spy and Java programs, when a JDK and liblcm-java are installed;
# sets PLSA_LCM_JAR to lcm.jar's path, empty without.
# (A macro: Java_JAVA_EXECUTABLE and LCM_JAR stay visible to the tests.)
macro(plsa_lcm_java target)
  find_package(Java 1.8 COMPONENTS Development Runtime QUIET)
  set(PLSA_LCM_JAR "")
  if(Java_FOUND)
    include(UseJava)
    find_jar(LCM_JAR lcm PATHS /usr/share/java)
  endif()
  if(NOT Java_FOUND OR NOT LCM_JAR)
    message(STATUS "plsa: no Java LCM types for lcm-spy (needs a JDK and liblcm-java)")
  else()
    plsa_lcm_java_jar(${target} ${ARGN})
    set(PLSA_LCM_JAR ${LCM_JAR})
  endif()
endmacro()

function(plsa_lcm_java_jar target)
  set(out_dir ${CMAKE_CURRENT_BINARY_DIR}/lcmtypes-java)
  set(sources)
  set(lcm_files)
  foreach(src ${ARGN})
    get_filename_component(abs ${src} ABSOLUTE)
    get_filename_component(name ${src} NAME_WE)
    list(APPEND sources ${out_dir}/plsa_lcm/${name}.java)
    list(APPEND lcm_files ${abs})
  endforeach()
  add_custom_command(OUTPUT ${sources}
    COMMAND ${LCM_GEN_EXECUTABLE} -j --jpath ${out_dir} ${lcm_files}
    DEPENDS ${lcm_files} COMMENT "lcm-gen: the LCM types as Java" VERBATIM)
  add_jar(${target} SOURCES ${sources} INCLUDE_JARS ${LCM_JAR} OUTPUT_NAME plsa_lcmtypes)
  install_jar(${target} DESTINATION ${CMAKE_INSTALL_DATADIR}/java)
endfunction()
