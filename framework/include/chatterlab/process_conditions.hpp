#pragma once
// Capability of a model: its parameters follow the grinding process conditions. A feed plan
// changes the work radius, the work surface speed, the engaged width of the wheel and the spindle
// speed segment by segment (feed_risk); a variable-speed or variable-feed strategy changes a
// speed or the depth of cut over time (suppression_map, MODELS.md S1-S3). Study kinds reach any
// model that implements this interface through Model::process_conditions(), never through its
// parameter names, so a new model that declares the capability works with them unchanged.
#include <bit>
#include <cstdint>
#include <algorithm>
#include <string>
#include <vector>

#include "chatterlab/params.hpp"

namespace chatterlab {

// The process conditions at the wheel-work contact.
struct ProcessConditions {
  double wheel_speed_rpm = 0.0;
  double work_speed_rpm = 0.0;
  double contact_width_mm = 0.0;    // engaged width of cut b (along the wheel axis)
  double work_radius_mm = 0.0;      // radius of the part under the wheel
  double wheel_diameter_mm = 0.0;
  double depth_of_cut_ratio = 1.0;  // depth of cut per work revolution over the reference's
};

// How the process stiffnesses follow the conditions: study settings, the same for every model.
struct ProcessScaling {
  // MODELS.md G4: the removal stiffness grows with Kv/(1 + Kv) and the wear stiffness falls as
  // 1/(1 + Kv), Kv = v_work / v_wheel; false: only the width scales them.
  bool speed_dependent_stiffness = true;
  // MODELS.md S1 (5-29): contact and wear stiffness k = k0 (1 - eps/2 da/a) with the relative
  // depth-of-cut change da/a = depth_of_cut_ratio - 1; 0 leaves them alone.
  double thickness_exponent = 0.0;
};

class ProcessConditionsModel {
 public:
  virtual ~ProcessConditionsModel() = default;

  // What a NaN in parameter_values_at's vector carries: a container's size, a text's length, or
  // six bytes of a text (payload below 2^48).
  enum class Structure : std::uint64_t { container_size = 1, text_length = 2, text_bytes = 3 };
  static double structure_value(Structure what, std::uint64_t payload) {
    return std::bit_cast<double>(0x7ff8000000000000ULL | (static_cast<std::uint64_t>(what) << 48) |
                                 (payload & 0xffffffffffffULL));
  }

  // The speeds the model's own parameters describe (width, radii and depth ratio are not model
  // parameters: a study gives them as the reference, see parameters_at).
  virtual ProcessConditions nominal_conditions() const = 0;

  // The model's parameter table (validated form, without `type`) at `conditions`, given that its
  // own parameters hold at `reference`. A condition of 0 in both means "not given": the model
  // keeps what depends on it unchanged.
  virtual Json parameters_at(const ProcessConditions& reference, const ProcessConditions& conditions,
                             const ProcessScaling& scaling) const = 0;

  // The leaves of parameters_at's table as numbers, in a fixed order, without building the table: a
  // study comparing the parameters of 10^5 conditions (feed_risk's grouping) spent a fifth of its
  // time building and freeing those tables. A model overrides it with its typed parameters; two
  // conditions give bitwise equal vectors exactly when their tables are equal. Default: the
  // table's leaves (booleans 0/1), each array and object preceded by its size, each text by its
  // length and then its bytes six to a value, so that no two different tables give the same
  // vector. Sizes, lengths and text bytes travel as NaNs carrying them in their payload
  // (structure_value): a study compares NaNs by their bits, never within a tolerance.
  virtual void parameter_values_at(const ProcessConditions& reference, const ProcessConditions& conditions,
                                   const ProcessScaling& scaling, std::vector<double>& values) const {
    values.clear();
    auto leaves = [&values](const Json& v, const auto& self) -> void {
      if (v.is_object() || v.is_array()) {
        values.push_back(structure_value(Structure::container_size, v.size()));
        for (const Json& e : v) self(e, self);
      } else if (v.is_number()) {
        values.push_back(v.get<double>());
      } else if (v.is_boolean()) {
        values.push_back(v.get<bool>() ? 1.0 : 0.0);
      } else {
        const std::string text = v.dump();
        values.push_back(structure_value(Structure::text_length, text.size()));
        for (std::size_t i = 0; i < text.size(); i += 6) {
          std::uint64_t chunk = 0;
          for (std::size_t j = i; j < std::min(i + 6, text.size()); ++j)
            chunk = (chunk << 8) | static_cast<unsigned char>(text[j]);
          values.push_back(structure_value(Structure::text_bytes, chunk));
        }
      }
    };
    leaves(parameters_at(reference, conditions, scaling), leaves);
  }
};

}  // namespace chatterlab
