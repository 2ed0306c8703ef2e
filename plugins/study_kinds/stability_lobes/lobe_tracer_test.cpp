// The lobe tracer's two crossing finders agree (Moebius bracketing for a parameter entering G as a
// Moebius map, Newton with model builds for any other), chatter-free windows, time to chatter.
#include "study_kinds/stability_lobes/lobe_tracer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "chatterlab/kit/model.hpp"
#include "study_kinds/stability_lobes/lobe_results.hpp"
#include "study_kinds/stability_lobes/time_to_chatter.hpp"

namespace chatterlab::lobes {
namespace {

// G1 with two G8 modes (the CLI test machine), kc and the work speed varied.
std::unique_ptr<Model> g1(double kc, double work_rpm) {
  return kit::build_model({{"type", "plunge_regenerative"},
                           {"wheel_speed_rpm", 1450},
                           {"work_speed_rpm", work_rpm},
                           {"contact_stiffness_n_per_m", kc},
                           {"wheel_wear_stiffness_n_per_m", 5e9},
                           {"work_removal_stiffness_n_per_m", 5e7},
                           {"modes",
                            {{{"frequency_hz", 184.08}, {"damping_ratio", 0.05}, {"stiffness_n_per_m", 5e7}},
                             {{"frequency_hz", 305.6}, {"damping_ratio", 0.04}, {"stiffness_n_per_m", 8e7}}}},
                           {"wheel_regeneration", true},
                           {"work_regeneration", true}});
}

TraceSettings settings(double lo, double hi) {
  TraceSettings s;
  s.parameter_min = lo;
  s.parameter_max = hi;
  s.max_frequency_hz = 1222.4;
  return s;
}

// The same diagram with the parameter q = sqrt(kc): E is then quadratic in q, not a Moebius map,
// so the tracer takes its Newton path; its critical q must be the square root of the critical kc
// found by the Moebius path.
TEST(LobeTracer, NewtonPathAgreesWithTheMoebiusPath) {
  const std::vector<double> speeds{40.3, 40.9, 41.6};
  const LobeDiagram direct = trace_lobes([](double kc, double v) { return g1(kc, v); }, speeds, settings(1e5, 1e9));
  const LobeDiagram root = trace_lobes([](double q, double v) { return g1(q * q, v); }, speeds,
                                       settings(std::sqrt(1e5), std::sqrt(1e9)));
  EXPECT_TRUE(direct.parameter_enters_as_moebius_map);
  EXPECT_FALSE(root.parameter_enters_as_moebius_map);
  for (std::size_t i = 0; i < speeds.size(); ++i) {
    ASSERT_TRUE(direct.at[i].limit && root.at[i].limit) << direct.at[i].note << " / " << root.at[i].note;
    EXPECT_NEAR(root.at[i].limit->parameter * root.at[i].limit->parameter, direct.at[i].limit->parameter,
                1e-8 * direct.at[i].limit->parameter);
    EXPECT_NEAR(root.at[i].limit->omega_rad_s, direct.at[i].limit->omega_rad_s, 1e-8 * direct.at[i].limit->omega_rad_s);
  }
}

// Lobes are followed across speeds: the points of a lobe ascend in speed, and its frequency moves
// no faster than the work lattice carries it: on a lobe of the work chain w = (2 pi m + eps)/Tw,
// so df/dv = f/v at fixed eps (the wheel chain's lobes keep f nearly fixed, mixed lobes lie
// between); eps drifts along a lobe, hence the factor 2. A jump between distant crossings breaks it.
TEST(LobeTracer, LobesAreContinuousInSpeed) {
  std::vector<double> speeds;
  for (int i = 0; i <= 40; ++i) speeds.push_back(40.0 + 0.25 * i);
  const LobeDiagram d = trace_lobes([](double kc, double v) { return g1(kc, v); }, speeds, settings(1e5, 1e9));
  ASSERT_GT(d.lobes.size(), 3u);
  for (const Lobe& lobe : d.lobes)
    for (std::size_t k = 1; k < lobe.points.size(); ++k) {
      const Crossing& a = lobe.points[k - 1];
      const Crossing& b = lobe.points[k];
      EXPECT_GT(b.speed, a.speed);
      const double carried = std::max(a.omega_rad_s, b.omega_rad_s) / a.speed * (b.speed - a.speed);
      EXPECT_LT(std::abs(b.omega_rad_s - a.omega_rad_s), 2.0 * carried) << "lobe " << lobe.id << " at " << b.speed;
    }
  // The envelope is the lowest crossing at every speed.
  for (std::size_t i = 0; i < speeds.size(); ++i) {
    ASSERT_TRUE(d.at[i].limit);
    for (const Lobe& lobe : d.lobes)
      for (const Crossing& c : lobe.points) {
        if (c.speed == speeds[i]) {
          EXPECT_GE(c.parameter, d.at[i].limit->parameter);
        }
      }
  }
}

TEST(LobeWindows, IntervalsAboveTheLevelWithInterpolatedEnds) {
  LobeDiagram d;
  d.speeds = {1, 2, 3, 4, 5, 6};
  const double limits[] = {1.0, 3.0, 3.0, 1.0, NAN, 1.0};
  for (std::size_t i = 0; i < 6; ++i) {
    SpeedResult r;
    if (std::isfinite(limits[i])) {
      r.limit = Crossing{d.speeds[i], limits[i], 100.0};
      d.envelope.push_back(*r.limit);
    } else {
      r.note = "no crossing in parameter_range: stable over the whole range";
    }
    d.at.push_back(r);
  }
  const std::vector<Window> w = chatter_free_windows(d, 2.0);
  ASSERT_EQ(w.size(), 2u);
  EXPECT_DOUBLE_EQ(w[0].from, 1.5);
  EXPECT_DOUBLE_EQ(w[0].to, 3.5);
  EXPECT_DOUBLE_EQ(w[0].peak_value, 3.0);
  // Stable throughout at 5 only: the window is that speed (nothing was computed between).
  EXPECT_DOUBLE_EQ(w[1].from, 5.0);
  EXPECT_DOUBLE_EQ(w[1].to, 5.0);
  // A level above every limit: only the speed stable throughout.
  EXPECT_EQ(chatter_free_windows(d, 1e9).size(), 1u);
}

TEST(TimeToChatter, GrowthToleranceAndDressing) {
  TimeToChatterSettings s;
  s.initial_waviness_um = 0.1;
  s.tolerance_um = 1.0;
  s.part_time_s = 20.0;
  s.dressing_interval_parts = 10;
  // a0 e^{sigma t} = a_tol: t = ln(10)/sigma.
  EXPECT_DOUBLE_EQ(time_to_chatter_s(0.01, s), std::log(10.0) / 0.01);
  EXPECT_EQ(parts_before_chatter(time_to_chatter_s(0.01, s), s), 11);  // 230 s / 20 s
  EXPECT_TRUE(dressed_in_time(time_to_chatter_s(0.01, s), s));
  EXPECT_FALSE(dressed_in_time(time_to_chatter_s(0.1, s), s));  // 23 s: the second part
  EXPECT_TRUE(std::isinf(time_to_chatter_s(-0.5, s)));
  EXPECT_TRUE(dressed_in_time(time_to_chatter_s(0.0, s), s));
}

}  // namespace
}  // namespace chatterlab::lobes
