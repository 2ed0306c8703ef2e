#pragma once
// Error kinds that decide the exit code of `chatterlab` (docs/studies.md, "Exit codes"):
//   InputError   -> exit 2, nothing run, nothing written. The message names file, line, key,
//                   value and limit.
//   PointFailure -> recorded in that grid point's status; the run goes on and exits 1.
//   OutputError  -> a file could not be written (disk full, I/O error): exit 3, meta.json says so.
#include <stdexcept>
#include <string>

namespace chatterlab {

// Bad user input (study file, grid, plugin library, output directory). Always thrown, never
// asserted: users must get the message in release builds too.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A numerical failure confined to one grid point (root search did not converge, integrator
// failed). The runner catches it per point, records the reason and continues.
class PointFailure : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A file of the study's output could not be written (write_file_atomically and the plot service
// throw it). Inside a grid point it fails that point; the run then ends with exit 3.
class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// An exception that left an out-of-tree plugin's constructor, whatever its type, turned into a
// message naming the plugin and its library. load_study reports it as bad input at the line of
// the table that chose the plugin; inside a grid point it fails the point.
class PluginError : public std::runtime_error {
 public:
  PluginError(const std::string& message, std::string plugin, std::string library)
      : std::runtime_error(message), plugin_(std::move(plugin)), library_(std::move(library)) {}
  const std::string& plugin() const { return plugin_; }
  const std::string& library() const { return library_; }

 private:
  std::string plugin_, library_;
};

// The exception being handled (call inside a catch block), as text: what() of a std::exception,
// otherwise "an exception of type '<demangled type>' (not derived from std::exception)".
std::string describe_current_exception();

}  // namespace chatterlab
