# write_if_changed(FILE TEXT): writes FILE only when its content differs, so that a generated
# source that did not change does not make the build recompile anything.
function(write_if_changed file text)
  set(old "")
  if(EXISTS "${file}")
    file(READ "${file}" old)
  endif()
  if(NOT old STREQUAL text)
    file(WRITE "${file}" "${text}")
  endif()
endfunction()
