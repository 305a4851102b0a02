# Warnings are set per target, never globally, and never -Werror for consumers.
option(PLSA_WERROR "Treat warnings as errors in plsa's own targets" OFF)

function(plsa_set_warnings target)
  if(CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
    target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic)
    # In a unity build GCC takes a source included in a unit for a header and
    # warns of every class with a member or base from that source's anonymous
    # namespace (-Wsubobject-linkage); such a class is still used in that source only.
    if(PLSA_UNITY_BUILD AND CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
      target_compile_options(${target} PRIVATE -Wno-subobject-linkage)
    endif()
    if(PLSA_WERROR)
      target_compile_options(${target} PRIVATE -Werror)
    endif()
  endif()
endfunction()
