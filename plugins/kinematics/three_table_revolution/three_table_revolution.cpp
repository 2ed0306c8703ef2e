#include "kinematics/three_table_revolution/three_table_revolution.hpp"

#include <cmath>
#include <stdexcept>

#include "models/model_params.hpp"

namespace chatterlab {

PluginInfo ThreeTableRevolution::info() {
  using model_params::positive;
  PluginInfo info;
  info.name = "three_table_revolution";
  info.description =
      "three-table stepper machine for solids of revolution: lower, middle table and the nut "
      "turning the upper table (P4 inverse kinematics)";
  info.models_md_ids = "P1, P2, P4";
  ParamSpec step = positive("step_angle_deg", "deg", "motor step angle per pulse");
  step.max = 360.0;
  info.params = {
      positive("pivot_to_nut_mm", "mm",
               "R: distance from the upper table's vertical axis to the lead-screw nut"),
      positive("fixture_to_pivot_mm", "mm",
               "b: distance from the fixture reference plane (generatrix x = 0) to the vertical axis"),
      positive("screw_pitch_mm", "mm", "lead-screw pitch of every table"),
      positive("gear_ratio", "1", "motor turns per screw turn (gearbox reduction, 10 for 10:1)"),
      step,
      positive("max_pulse_rate_hz", "1/s", "largest pulse rate of every motor"),
  };
  info.thread_safety = ThreadSafety::shareable;
  info.example_params = {{"pivot_to_nut_mm", 300.0},  {"fixture_to_pivot_mm", 250.0},
                         {"screw_pitch_mm", 12.0},    {"gear_ratio", 10.0},
                         {"step_angle_deg", 1.0},     {"max_pulse_rate_hz", 100.0}};
  return info;
}

ThreeTableRevolution::ThreeTableRevolution(const ParamValues& params)
    : pivot_to_nut_mm_(params.real("pivot_to_nut_mm")),
      fixture_to_pivot_mm_(params.real("fixture_to_pivot_mm")),
      mm_per_pulse_(params.real("screw_pitch_mm") * params.real("step_angle_deg") / 360.0 /
                    params.real("gear_ratio")),
      max_pulse_rate_hz_(params.real("max_pulse_rate_hz")) {}

std::vector<MotorAxis> ThreeTableRevolution::motors() const {
  return {{"lower", mm_per_pulse_, max_pulse_rate_hz_, "lower"},
          {"middle", mm_per_pulse_, max_pulse_rate_hz_, "middle"},
          {"upper", mm_per_pulse_, max_pulse_rate_hz_, "upper_nut"}};
}

void ThreeTableRevolution::inverse(const CurvePoint& target, const ToolContact& contact,
                                   std::span<double> positions_mm) const {
  if (!(target.tangent_x > 0.0))
    throw std::domain_error("three_table_revolution: the generatrix tangent must point along +x");
  // theta = atan f'(x_s) - tilt; without tilt tan theta = f'(x_s) exactly (P4).
  const double slope = contact.tilt_rad == 0.0
                           ? target.tangent_y / target.tangent_x
                           : std::tan(std::atan2(target.tangent_y, target.tangent_x) - contact.tilt_rad);
  const double c = 1.0 / std::sqrt(1.0 + slope * slope), s = slope * c;
  const double u = fixture_to_pivot_mm_ - target.x_mm, v = -target.y_mm;
  positions_mm[0] = c * u + s * v + contact.along_mm;
  positions_mm[1] = -s * u + c * v + contact.across_mm;
  positions_mm[2] = -pivot_to_nut_mm_ * slope;
}

ToolInPart ThreeTableRevolution::forward(std::span<const double> positions_mm,
                                         const ToolContact& contact) const {
  const double slope = -positions_mm[2] / pivot_to_nut_mm_;
  const double c = 1.0 / std::sqrt(1.0 + slope * slope), s = slope * c;
  // (b - x_s, -y_s) = Rot(-theta) ((x_g, y_g) - C), Rot(-theta) = [[c, -s], [s, c]].
  const double gx = positions_mm[0] - contact.along_mm, gy = positions_mm[1] - contact.across_mm;
  return {fixture_to_pivot_mm_ - (c * gx - s * gy), -(s * gx + c * gy), 0.0};
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_KINEMATICS(chatterlab::ThreeTableRevolution);
