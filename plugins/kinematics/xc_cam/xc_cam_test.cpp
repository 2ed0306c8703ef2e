// xc_cam (MODELS.md K2): on a circular cam the wheel centre lies on the radius through the contact
// at distance r + R; forward() returns that centre as a disc of radius R, tangent to the profile.
#include "kinematics/xc_cam/xc_cam.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace chatterlab {
namespace {

TEST(XcCam, CircularCamPutsTheCentreOnTheRadius) {
  const XcCam machine(ParamValues(XcCam::info().example_params));
  std::vector<double> q(2);
  for (double deg : {0.0, 37.0, 135.0, -100.0}) {
    const double a = deg * std::numbers::pi / 180;
    // Counter-clockwise circle of radius 20: tangent (-sin a, cos a).
    machine.inverse({20 * std::cos(a), 20 * std::sin(a), -std::sin(a), std::cos(a)}, {}, q);
    EXPECT_NEAR(q[0], deg, 1e-12);
    EXPECT_NEAR(q[1], 220.0, 1e-12);
    const ToolInPart wheel = machine.forward(q, {});
    EXPECT_NEAR(std::hypot(wheel.x_mm - 20 * std::cos(a), wheel.y_mm - 20 * std::sin(a)), wheel.radius_mm, 1e-12);
  }
}

}  // namespace
}  // namespace chatterlab
