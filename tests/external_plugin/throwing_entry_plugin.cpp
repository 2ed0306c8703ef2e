// A plugin library whose entry point throws something that is not a std::exception: loading it
// must be bad input (exit 2) naming the library, never "terminate called".
#include <chatterlab/plugin_api.hpp>

CHATTERLAB_PLUGIN_ENTRY(registries) {
  (void)registries;
  throw 42;
}
