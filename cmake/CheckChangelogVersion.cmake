# cmake -DVERSION=x.y.z -DCHANGELOG=path -P CheckChangelogVersion.cmake
# Fails unless the changelog has a release heading for the project's version
# ("## x.y.z (date)" or "## x.y.z"), so that a version bump and its release
# notes move together.
if(NOT DEFINED VERSION OR NOT DEFINED CHANGELOG)
  message(FATAL_ERROR "CheckChangelogVersion: give -DVERSION and -DCHANGELOG")
endif()
file(STRINGS "${CHANGELOG}" headings REGEX "^## ")
string(REPLACE "." "\\." escaped "${VERSION}")
set(found FALSE)
foreach(h IN LISTS headings)
  if(h MATCHES "^## ${escaped}( \\(|$)")
    set(found TRUE)
  endif()
endforeach()
if(NOT found)
  message(FATAL_ERROR "${CHANGELOG} has no '## ${VERSION}' release heading for project(plsa VERSION ${VERSION}); "
                      "add the release's notes, or set the version the changelog last released")
endif()
message(STATUS "CHANGELOG.md releases ${VERSION}")
