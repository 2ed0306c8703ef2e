// describe_current_exception (chatterlab/errors.hpp).
#include "chatterlab/errors.hpp"

#include <cxxabi.h>

#include <cstdlib>
#include <exception>
#include <memory>
#include <typeinfo>

namespace chatterlab {

std::string describe_current_exception() {
  try {
    throw;
  } catch (const std::exception& e) {
    return e.what();
  } catch (...) {
    // Plugins may throw anything (an int, a string literal, their own class): name its type, so
    // the message says what happened instead of "unknown exception".
    const std::type_info* type = abi::__cxa_current_exception_type();
    if (type == nullptr) return "an exception of unknown type (not derived from std::exception)";
    int status = 0;
    std::unique_ptr<char, void (*)(void*)> name(
        abi::__cxa_demangle(type->name(), nullptr, nullptr, &status), std::free);
    return std::string("an exception of type '") + (status == 0 ? name.get() : type->name()) +
           "' (not derived from std::exception)";
  }
}

}  // namespace chatterlab
