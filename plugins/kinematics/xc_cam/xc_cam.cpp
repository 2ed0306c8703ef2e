#include "kinematics/xc_cam/xc_cam.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include "chatterlab/param_table.hpp"
#include "chatterlab/plugin_info.hpp"

namespace chatterlab {

namespace {

struct XcCamParameters {
  double wheel_radius_mm = 0.0, c_deg_per_pulse = 0.0, x_mm_per_pulse = 0.0, max_pulse_rate_hz = 0.0;
};

const ParamTable<XcCamParameters>& parameters_table() {
  using P = XcCamParameters;
  static const ParamTable<P> table = [] {
    ParamTable<P> t;
    t.add(&P::wheel_radius_mm, "wheel_radius_mm", "mm", "grinding wheel radius R").positive().required();
    t.add(&P::c_deg_per_pulse, "c_deg_per_pulse", "deg", "C axis rotation per pulse").positive().required();
    t.add(&P::x_mm_per_pulse, "x_mm_per_pulse", "mm", "X slide travel per pulse").positive().required();
    t.add(&P::max_pulse_rate_hz, "max_pulse_rate_hz", "1/s", "largest pulse rate of each motor").positive().required();
    return t;
  }();
  return table;
}

}  // namespace

PluginInfo XcCam::info() {
  return plugin_info("xc_cam", "K2",
                     parameters_table().specs(),
                     {{"wheel_radius_mm", 200.0},
                      {"c_deg_per_pulse", 0.001},
                      {"x_mm_per_pulse", 0.0001},
                      {"max_pulse_rate_hz", 100000.0}},
                     "X-C cam grinder: C axis turns the cam so the wheel centre lies on the X slide (K2 tangent "
                     "point tracking)",
                     ThreadSafety::shareable);
}

XcCam::XcCam(const ParamValues& params) {
  const XcCamParameters p = parameters_table().read(params);
  wheel_radius_mm_ = p.wheel_radius_mm;
  c_deg_per_pulse_ = p.c_deg_per_pulse;
  x_mm_per_pulse_ = p.x_mm_per_pulse;
  max_pulse_rate_hz_ = p.max_pulse_rate_hz;
}

std::vector<MotorAxis> XcCam::motors() const {
  // mm_per_pulse of the rotary C axis is in degrees (MotorAxis: axis units per pulse).
  return {{"c_axis", c_deg_per_pulse_, max_pulse_rate_hz_, "c_axis_deg"},
          {"x_slide", x_mm_per_pulse_, max_pulse_rate_hz_, "x_slide"}};
}

void XcCam::inverse(const CurvePoint& target, const ToolContact& /*contact*/,
                    std::span<double> positions) const {
  const double length = std::hypot(target.tangent_x, target.tangent_y);
  if (!(length > 0)) throw std::domain_error("xc_cam: zero tangent");
  const double cx = target.x_mm + wheel_radius_mm_ * target.tangent_y / length;
  const double cy = target.y_mm - wheel_radius_mm_ * target.tangent_x / length;
  positions[0] = std::atan2(cy, cx) * 180.0 / std::numbers::pi;
  positions[1] = std::hypot(cx, cy);
}

ToolInPart XcCam::forward(std::span<const double> positions, const ToolContact& /*contact*/) const {
  const double theta = positions[0] * std::numbers::pi / 180.0;
  return {positions[1] * std::cos(theta), positions[1] * std::sin(theta), wheel_radius_mm_};
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_KINEMATICS(chatterlab::XcCam);
