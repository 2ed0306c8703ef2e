// A shared library that is not a chatterlab plugin: it exports a function, but not
// chatterlab_plugin_entry (as if CHATTERLAB_PLUGIN_ENTRY had been forgotten).
extern "C" __attribute__((visibility("default"))) int example_not_a_plugin() { return 42; }
