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
