# chatterlab_add_plugin(<name> SOURCES <file>... [NO_CONFORMANCE_TEST])
#
# Builds an out-of-tree chatterlab plugin library lib<name>.so from SOURCES (one of them defines
# CHATTERLAB_PLUGIN_ENTRY, <chatterlab/plugin_api.hpp>) and registers the CTest test
# <name>.check_plugin, which runs `chatterlab check-plugin` (the conformance suite) on it.
# A study loads the library with `plugins = ["path/to/lib<name>.so"]`; list, describe, validate
# and run take `--plugin path/to/lib<name>.so`. docs/plugins.md walks through it.
#
# The library is a MODULE (only ever dlopen()ed), linked to chatterlab::chatterlab so that every
# framework symbol it uses is resolved when it is linked (--no-undefined), not first at load time.
# Only chatterlab_plugin_entry and chatterlab_plugin_build are visible (the entry macro marks
# them): nothing else of the plugin can clash with other code in the process.
function(chatterlab_add_plugin name)
  cmake_parse_arguments(PARSE_ARGV 1 arg "NO_CONFORMANCE_TEST" "" "SOURCES")
  if(NOT arg_SOURCES)
    message(FATAL_ERROR "chatterlab_add_plugin(${name}): no SOURCES given")
  endif()
  if(arg_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "chatterlab_add_plugin(${name}): unexpected arguments ${arg_UNPARSED_ARGUMENTS}")
  endif()
  add_library(${name} MODULE ${arg_SOURCES})
  target_link_libraries(${name} PRIVATE chatterlab::chatterlab)
  target_link_options(${name} PRIVATE -Wl,--no-undefined)
  set_target_properties(${name} PROPERTIES
    CXX_EXTENSIONS OFF CXX_VISIBILITY_PRESET hidden VISIBILITY_INLINES_HIDDEN ON)
  if(NOT arg_NO_CONFORMANCE_TEST)
    add_test(NAME ${name}.check_plugin COMMAND chatterlab::cli check-plugin $<TARGET_FILE:${name}>)
  endif()
endfunction()
