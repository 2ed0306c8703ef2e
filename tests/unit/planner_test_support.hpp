#pragma once
// Shared by the planner's tests: the feed_plan study of MODELS.md P3 problem 2 on the P2 machine
// (profiled wheel, edge radius 20 mm), and a text replacement that fails the test when the text
// to replace is missing.
#include <gtest/gtest.h>

#include <string>

namespace chatterlab::planner::testing {

inline constexpr const char* problem2_study_text = R"(
[study]
kind = "feed_plan"
[machine]
type = "three_table_revolution"
pivot_to_nut_mm = 300.0
fixture_to_pivot_mm = 250.0
screw_pitch_mm = 12.0
gear_ratio = 10.0
step_angle_deg = 1.0
max_pulse_rate_hz = 100.0
max_relative_rate_change = 0.1
spindle_speed_rpm = { from = 250.0, to = 300.0 }
max_axial_advance_mm_per_100_rev = 4.0
[part]
generatrix = "30*exp(-x/400)*sin((x + 25*_pi)/100) + 130"
x_range_mm = [0.0, 600.0]
[wheel]
type = "profiled"
diameter_mm = 400.0
thickness_mm = 40.0
edge_radius_mm = 20.0
edge_angle_deg = 180.0
)";

inline std::string replace(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return at == std::string::npos ? text : text.replace(at, from.size(), to);
}

}  // namespace chatterlab::planner::testing
