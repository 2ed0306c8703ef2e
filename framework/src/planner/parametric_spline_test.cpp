// Cumulative-chord parametric cubic splines (MODELS.md K1) and the cam fit with adaptive point
// insertion (K3) on the lift table of seed 002 (tests/data/planner/cam_lift_table.csv).
#include "chatterlab/planner/parametric_spline.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>

namespace chatterlab::planner {
namespace {

constexpr double pi = std::numbers::pi;

ParametricSpline circle(int points_count) {
  std::vector<std::array<double, 2>> points;
  for (int i = 0; i < points_count; ++i) {
    const double a = 2 * pi * i / points_count;
    points.push_back({20 * std::cos(a), 20 * std::sin(a)});
  }
  return ParametricSpline(points, SplineEnds::periodic);
}

double max_radius_error(const ParametricSpline& s) {
  double worst = 0.0;
  for (double deg = 0.5; deg < 360; deg += 1.3) worst = std::max(worst, std::abs(s.polar_radius(deg * pi / 180) - 20.0));
  return worst;
}

TEST(ParametricSpline, PeriodicCircleIsRoundAndC2AcrossTheSeam) {
  const ParametricSpline s = circle(36);
  // Chord-length parameterisation: fourth order in the spacing (36 -> 72 points: ~16x smaller).
  const double coarse = max_radius_error(s), fine = max_radius_error(circle(72));
  EXPECT_LT(coarse, 1e-4);
  EXPECT_GT(coarse / fine, 12.0);
  std::array<double, 2> p{}, d1a{}, d2a{}, d1b{}, d2b{};
  s.evaluate(1e-9, p, d1a, d2a);
  s.evaluate(s.length() - 1e-9, p, d1b, d2b);
  for (int c = 0; c < 2; ++c) {
    EXPECT_NEAR(d1a[c], d1b[c], 1e-8);
    EXPECT_NEAR(d2a[c], d2b[c], 1e-8);
  }
  // Curvature of the fitted circle ~ 1/20.
  s.evaluate(0.37 * s.length(), p, d1a, d2a);
  const double speed = std::hypot(d1a[0], d1a[1]);
  EXPECT_NEAR((d1a[0] * d2a[1] - d1a[1] * d2a[0]) / (speed * speed * speed), 0.05, 5e-4);
}

TEST(ParametricSpline, NaturalReproducesALineClampedFollowsTheTangents) {
  const ParametricSpline line({{0, 0}, {1, 2}, {3, 6}, {4, 8}}, SplineEnds::natural);
  const auto q = line.position(0.5 * line.length());
  EXPECT_NEAR(q[1], 2 * q[0], 1e-12);
  // Quarter circle with its exact end tangents: clamped beats natural near the ends.
  std::vector<std::array<double, 2>> arc;
  for (int i = 0; i <= 6; ++i) arc.push_back({std::cos(i * pi / 12), std::sin(i * pi / 12)});
  const ParametricSpline clamped(arc, SplineEnds::clamped, {0, 1}, {-1, 0});
  const ParametricSpline natural(arc, SplineEnds::natural);
  auto radius_error = [](const ParametricSpline& s, double l) {
    const auto p = s.position(l);
    return std::abs(std::hypot(p[0], p[1]) - 1.0);
  };
  const double l = 0.5 * clamped.knots()[1];
  EXPECT_LT(radius_error(clamped, l), 0.1 * radius_error(natural, l));
  EXPECT_THROW(ParametricSpline({{0, 0}, {0, 0}, {1, 1}}, SplineEnds::natural), std::invalid_argument);
}

LiftTable seed_lift_table() {
  std::ifstream in(std::string(CHATTERLAB_SOURCE_DIR) + "/tests/data/planner/cam_lift_table.csv");
  LiftTable table;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line[0] == 'a') continue;
    std::stringstream row(line);
    std::string angle, radius;
    std::getline(row, angle, ',');
    std::getline(row, radius, ',');
    table.angle_deg.push_back(std::stod(angle));
    table.radius_mm.push_back(std::stod(radius));
  }
  return table;
}

// Seed 002 (K3): 27 chosen points give a max fit error of ~2e-3 mm near 50 and 300 deg; adding
// points until the max error is below 5e-4 mm.
TEST(CamFit, SeedPointsThenAdaptiveInsertion) {
  const LiftTable table = seed_lift_table();
  ASSERT_EQ(table.angle_deg.size(), 65u);
  const std::vector<double> chosen{360, 10,  21,  32,  45,  59,  90,  105, 121, 130, 141, 150, 166, 180,
                                   194, 211, 220, 230, 240, 255, 270, 300, 315, 328, 339, 350, 360};
  const CamFit seed = fit_cam(table, chosen, 0.0);
  EXPECT_GT(seed.max_radius_error_mm, 5e-4);
  EXPECT_LT(seed.max_radius_error_mm, 2e-2);
  const CamFit adaptive = fit_cam(table, chosen, 5e-4);
  EXPECT_LE(adaptive.max_radius_error_mm, 5e-4);
  EXPECT_GT(adaptive.inserted, 0u);
  EXPECT_EQ(adaptive.chosen_angles_deg.size(), 26u + adaptive.inserted);
}

}  // namespace
}  // namespace chatterlab::planner
