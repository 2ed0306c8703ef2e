#pragma once
// Three-table stepper machine for solids of revolution (MODELS.md P1, P2, P4; seed 000 eq 5.12).
// Lower table x_g along the base rails (parallel to the wheel axis), middle table y_g across it,
// upper table turned by theta about the middle table's vertical axis through a lead-screw nut at
// distance R from the axis (nut travel z_g = -R tan theta). The fixture reference plane (x = 0 of
// the generatrix) is at distance b from the vertical axis. With the wheel contact point fixed in
// the base frame (origin) and the wheel tangent parallel to the rails (P4):
//
//   tan theta = f'(x_s),   z_g = -R f'(x_s),
//   (x_g, y_g) = [[cos th, sin th], [-sin th, cos th]] (b - x_s, -y_s)
//
// Wear spreading (P6) moves the contact on the wheel to C = (along, across) with the wheel's
// tangent tilted by phi there (ToolContact): then theta = atan f'(x_s) - phi and
// (x_g, y_g) = C + Rot(theta) (b - x_s, -y_s). Docs: docs/kinematics/three_table_revolution.md.
#include <span>
#include <vector>

#include "chatterlab/kinematics.hpp"
#include "chatterlab/params.hpp"

namespace chatterlab {

class ThreeTableRevolution final : public Kinematics {
 public:
  static PluginInfo info();
  explicit ThreeTableRevolution(const ParamValues& params);

  std::vector<MotorAxis> motors() const override;
  void inverse(const CurvePoint& target, const ToolContact& contact,
               std::span<double> positions_mm) const override;
  ToolInPart forward(std::span<const double> positions_mm,
                     const ToolContact& contact) const override;

  double mm_per_pulse() const { return mm_per_pulse_; }

 private:
  double pivot_to_nut_mm_;      // R
  double fixture_to_pivot_mm_;  // b
  double mm_per_pulse_;         // screw pitch * step angle / 360 / gear ratio
  double max_pulse_rate_hz_;
};

}  // namespace chatterlab
