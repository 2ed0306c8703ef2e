#include "convert.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <memory>

namespace chatterlab::python {

Json to_json(py::handle object, const std::string& where) {
  if (object.is_none()) return Json();
  if (py::isinstance<py::bool_>(object)) return object.cast<bool>();
  if (py::isinstance<py::int_>(object)) return object.cast<std::int64_t>();
  if (py::isinstance<py::float_>(object)) return object.cast<double>();
  if (py::isinstance<py::str>(object)) return object.cast<std::string>();
  if (py::isinstance<py::dict>(object)) {
    Json out = Json::object();
    for (auto [key, value] : object.cast<py::dict>()) {
      if (!py::isinstance<py::str>(key))
        throw py::type_error(where + ": table keys must be strings, not " + std::string(py::repr(key)));
      const std::string name = key.cast<std::string>();
      out[name] = to_json(value, where + "." + name);
    }
    return out;
  }
  if (py::isinstance<py::list>(object) || py::isinstance<py::tuple>(object)) {
    Json out = Json::array();
    std::size_t i = 0;
    for (auto item : object) out.push_back(to_json(item, where + "." + std::to_string(i++)));
    return out;
  }
  // numpy arrays and scalars (np.int64, np.bool_ ...) become their Python equivalents.
  if (py::hasattr(object, "tolist")) return to_json(object.attr("tolist")(), where);
  if (py::hasattr(object, "__fspath__")) return object.attr("__fspath__")().cast<std::string>();
  throw py::type_error(where + ": cannot use a " + std::string(py::str(object.get_type().attr("__name__"))) +
                       " here (expected a dict, list, number, bool, str or None)");
}

py::object to_python(const Json& value) {
  switch (value.type()) {
    case Json::value_t::null:
      return py::none();
    case Json::value_t::boolean:
      return py::bool_(value.get<bool>());
    case Json::value_t::number_integer:
      return py::int_(value.get<std::int64_t>());
    case Json::value_t::number_unsigned:
      return py::int_(value.get<std::uint64_t>());
    case Json::value_t::number_float:
      return py::float_(value.get<double>());
    case Json::value_t::string:
      return py::str(value.get_ref<const std::string&>());
    case Json::value_t::array: {
      py::list out;
      for (const Json& item : value) out.append(to_python(item));
      return out;
    }
    case Json::value_t::object: {
      py::dict out;
      for (const auto& [key, item] : value.items()) out[py::str(key)] = to_python(item);
      return out;
    }
    default:
      return py::none();  // binary and discarded values do not occur in chatterlab's documents
  }
}

namespace {

bool is_numeric_array(const Json& value) {
  return value.is_array() && !value.empty() &&
         std::all_of(value.begin(), value.end(), [](const Json& item) { return item.is_number(); });
}

}  // namespace

py::object to_python_with_arrays(const Json& value) {
  if (is_numeric_array(value)) {
    std::vector<double> numbers;
    numbers.reserve(value.size());
    for (const Json& item : value) numbers.push_back(item.get<double>());
    return to_numpy(std::move(numbers));
  }
  if (value.is_array()) {
    py::list out;
    for (const Json& item : value) out.append(to_python_with_arrays(item));
    return out;
  }
  if (value.is_object()) {
    py::dict out;
    for (const auto& [key, item] : value.items()) out[py::str(key)] = to_python_with_arrays(item);
    return out;
  }
  return to_python(value);
}

py::array_t<double, py::array::c_style | py::array::forcecast> as_series(py::handle values, const std::string& where) {
  auto array = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(values);
  if (!array) throw py::type_error(where + ": expected a sequence of numbers (a numpy array)");
  if (array.ndim() != 1)
    throw py::value_error(where + ": expected a one-dimensional array, not one of " +
                          std::to_string(array.ndim()) + " dimensions");
  return array;
}

py::array_t<double> to_numpy(std::vector<double>&& values) {
  auto owner = std::make_unique<std::vector<double>>(std::move(values));
  const auto size = static_cast<py::ssize_t>(owner->size());
  double* data = owner->data();
  py::capsule free_when_done(owner.get(), [](void* p) { delete static_cast<std::vector<double>*>(p); });
  owner.release();
  return py::array_t<double>({size}, {static_cast<py::ssize_t>(sizeof(double))}, data, free_when_done);
}

}  // namespace chatterlab::python
