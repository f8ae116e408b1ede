#pragma once
/* Binds a self-describing parameter struct (see core/params.hh): attributes with range checks
 * on assignment, keyword construction, and a `fields()` table for the add-on's tests. */
#include <pybind11/pybind11.h>

#include <cmath>
#include <sstream>
#include <string>
#include <type_traits>

#include "core/math.hh"
#include "core/params.hh"

namespace hairdyn::bindings {

namespace py = pybind11;

template<typename T> std::string check_range(const T value, const ParamInfo &info)
{
  const double v = double(value);
  /* The bounds as the field stores them: a float field set to its largest value (0.1 becomes
   * 0.100000001f) is inside the range it shows. */
  const auto stored = [](const double bound) {
    return std::is_floating_point_v<T> && std::isfinite(bound) ? double(T(bound)) : bound;
  };
  if (!std::isfinite(v) || v < stored(info.min) || v > stored(info.max)) {
    std::ostringstream msg;
    msg << info.name << " (" << (info.symbol[0] ? info.symbol : info.name) << ") must be";
    if (std::isfinite(info.min) && std::isfinite(info.max)) {
      msg << " between " << info.min << " and " << info.max;
    }
    else if (std::isfinite(info.min)) {
      msg << " at least " << info.min;
    }
    else if (std::isfinite(info.max)) {
      msg << " at most " << info.max;
    }
    else {
      msg << " a finite number";
    }
    if (info.unit[0]) {
      msg << " " << info.unit;
    }
    msg << ", not " << v;
    return msg.str();
  }
  return {};
}

/* Python number -> scalar or enum field value, with a ValueError that names the field. */
template<typename T> T convert_scalar(const py::handle value, const ParamInfo &info)
{
  T result{};
  try {
    if constexpr (std::is_enum_v<T>) {
      result = T(py::cast<int32_t>(value));
    }
    else {
      result = py::cast<T>(value);
    }
  }
  catch (const py::cast_error &) {
    throw py::value_error(std::string(info.name) + " must be a number, not " +
                          std::string(py::str(py::repr(value))));
  }
  if constexpr (std::is_enum_v<T>) {
    const std::string error = check_range(int32_t(result), info);
    if (!error.empty()) {
      throw py::value_error(error + " (choices: " + info.choices + ")");
    }
  }
  else if constexpr (!std::is_same_v<T, bool>) {
    const std::string error = check_range(result, info);
    if (!error.empty()) {
      throw py::value_error(error);
    }
  }
  return result;
}

/* Python value -> field value; a vec3 field takes any sequence of 3 numbers, each checked
 * against the field's range. */
template<typename T> T convert_field(const py::handle value, const ParamInfo &info)
{
  if constexpr (std::is_same_v<T, vec3>) {
    if (!py::isinstance<py::sequence>(value) || py::isinstance<py::str>(value) ||
        py::len(value) != 3) {
      throw py::value_error(std::string(info.name) + " must be a sequence of 3 numbers, not " +
                            std::string(py::str(py::repr(value))));
    }
    const py::sequence items = py::reinterpret_borrow<py::sequence>(value);
    return vec3(convert_scalar<float>(items[0], info), convert_scalar<float>(items[1], info),
                convert_scalar<float>(items[2], info));
  }
  else {
    return convert_scalar<T>(value, info);
  }
}

/* A Python value for the field `member` of `Params`, checked against that field's range: for
 * functions that take a single parameter rather than the whole struct. */
template<typename Params, typename T> T convert_param(T Params::*member, const py::handle value)
{
  T result{};
  Params::for_each_field([&](auto field, const ParamInfo &info) {
    if constexpr (std::is_same_v<decltype(field), T Params::*>) {
      if (field == member) {
        result = convert_field<T>(value, info);
      }
    }
  });
  return result;
}

/* Registers `Params` as a Python class `name` with one checked attribute per field,
 * `Params(**fields)`, `to_dict()` and the static `fields()` table (name, symbol, unit, min,
 * max, default, description, choices, display_scale, display_unit, soft_min, soft_max, label). */
template<typename Params> py::class_<Params> bind_params(py::module_ &m, const char *name,
                                                         const char *doc)
{
  py::class_<Params> cls(m, name, doc);
  Params::for_each_field([&](auto member, const ParamInfo &info) {
    using T = std::remove_reference_t<decltype(std::declval<Params &>().*member)>;
    cls.def_property(
        info.name,
        [member](const Params &self) {
          if constexpr (std::is_enum_v<T>) {
            return py::object(py::int_(int32_t(self.*member)));
          }
          else if constexpr (std::is_same_v<T, vec3>) {
            const vec3 &v = self.*member;
            return py::object(py::make_tuple(v.x, v.y, v.z));
          }
          else {
            return py::object(py::cast(self.*member));
          }
        },
        [member, info](Params &self, const py::handle value) {
          self.*member = convert_field<T>(value, info);
        },
        info.description);
  });
  cls.def(py::init([](const py::kwargs &kwargs) {
    Params params;
    py::object self = py::cast(params);
    for (const auto &item : kwargs) {
      const std::string key = py::cast<std::string>(item.first);
      if (!py::hasattr(self, key.c_str())) {
        throw py::value_error("unknown parameter '" + key + "'");
      }
      self.attr(key.c_str()) = item.second;
    }
    return self.cast<Params>();
  }));
  cls.def("to_dict", [](const py::object &self) {
    py::dict result;
    Params::for_each_field([&](auto, const ParamInfo &info) {
      result[info.name] = self.attr(info.name);
    });
    return result;
  });
  cls.def_static("fields", []() {
    py::list table;
    const py::object defaults = py::cast(Params());
    Params::for_each_field([&](auto, const ParamInfo &info) {
      py::dict row;
      row["name"] = info.name;
      row["symbol"] = info.symbol;
      row["unit"] = info.unit;
      row["min"] = info.min;
      row["max"] = info.max;
      row["default"] = defaults.attr(info.name);
      row["description"] = info.description;
      row["choices"] = info.choices;
      row["display_scale"] = info.display_scale;
      row["display_unit"] = info.display_unit;
      row["soft_min"] = info.soft_min;
      row["soft_max"] = info.soft_max;
      row["label"] = info.label;
      table.append(row);
    });
    return table;
  });
  return cls;
}

}  // namespace hairdyn::bindings
