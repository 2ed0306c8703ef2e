#pragma once
// X-C cam grinder (MODELS.md K2, seed 002): the cam turns on the C axis, the wheel (radius R) sits
// on the X slide. For the tangent point H = (x, y) of the cam profile with tangent (x', y') (cam
// frame, profile run counter-clockwise), the wheel centre is H + R n with the outward normal
// n = (y', -x') / |r'|; the machine turns the cam by theta so that this centre lies on the X axis,
// (cos theta, sin theta) = (X, Y) / sqrt(X^2 + Y^2), and sets the slide to sqrt(X^2 + Y^2).
// Axis positions: C angle theta in degrees (in (-180, 180]; a plan unwraps it), X slide in mm.
// Docs: docs/kinematics/xc_cam.md.
#include <span>
#include <vector>

#include "chatterlab/kinematics.hpp"
#include "chatterlab/params.hpp"

namespace chatterlab {

class XcCam final : public Kinematics, public CamGrindingMachine {
 public:
  static PluginInfo info();
  explicit XcCam(const ParamValues& params);

  std::vector<MotorAxis> motors() const override;
  // The wheel is a disc: the contact on it does not change the geometry (ignored).
  void inverse(const CurvePoint& target, const ToolContact& contact,
               std::span<double> positions) const override;
  ToolInPart forward(std::span<const double> positions, const ToolContact& contact) const override;

  const CamGrindingMachine* cam_grinding() const override { return this; }
  double wheel_radius_mm() const override { return wheel_radius_mm_; }

 private:
  double wheel_radius_mm_;
  double c_deg_per_pulse_, x_mm_per_pulse_, max_pulse_rate_hz_;
};

}  // namespace chatterlab
