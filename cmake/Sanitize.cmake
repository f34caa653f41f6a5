# GLINT_SANITIZE: a comma-separated list of -fsanitize= checks (e.g.
# "address,undefined") applied to Glint's own targets only. Per target, not
# through CMAKE_CXX_FLAGS, so that third-party code found by find_package is
# untouched and a sanitized build differs from a normal one in nothing else.
#
# Any finding stops the program (-fno-sanitize-recover): a UBSan report that
# only prints would pass a test run unnoticed.

set(GLINT_SANITIZE "" CACHE STRING
    "Sanitizers for Glint's targets, e.g. address,undefined (empty: none)")

# glint_sanitize(<target>...): targets that do not exist in this configuration
# (tools or bindings switched off) are skipped.
function(glint_sanitize)
  if(GLINT_SANITIZE STREQUAL "")
    return()
  endif()
  set(flags -fsanitize=${GLINT_SANITIZE} -fno-sanitize-recover=all -fno-omit-frame-pointer)
  foreach(t IN LISTS ARGN)
    if(TARGET ${t})
      target_compile_options(${t} PRIVATE ${flags})
      target_link_options(${t} PRIVATE ${flags})
    endif()
  endforeach()
endfunction()
