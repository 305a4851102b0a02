# Warnings are set per target, never globally, and never -Werror for consumers.
option(PLSA_WERROR "Treat warnings as errors in plsa's own targets" OFF)

function(plsa_set_warnings target)
  if(CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
    target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic)
    if(PLSA_WERROR)
      target_compile_options(${target} PRIVATE -Werror)
    endif()
  endif()
endfunction()
