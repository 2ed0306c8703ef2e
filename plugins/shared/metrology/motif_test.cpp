#include "shared/metrology/motif.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace chatterlab::surface {
namespace {

// Hand-worked profile (spacing 0.1 mm): y = 0, -2, 3, -1, 1, -3, 4.
// Peaks (boundaries): x = 0 (end), 0.2 (3), 0.4 (1), 0.6 (end, 4). Motifs and depths:
//   [0, 0.2] valley -2: H = 2, 5, T = 2;  [0.2, 0.4] valley -1: H = 4, 2, T = 2;
//   [0.4, 0.6] valley -3: H = 4, 7, T = 4.
// Common peak 3 at 0.2 is above both neighbours' peaks (0 and 1): C1 fails.
// Common peak 1 at 0.4: C1 1 <= max(3, 4); C2 0.4 <= A = 0.5; joined T = min(3, 4) - (-3) = 6
// >= max(2, 4) (C3); min(2, 4) = 2 < 0.6 * 6 (C4) -> combined into [0.2, 0.6], valley -3.
// Then at 0.2: C1 holds now (3 <= 4) but the width 0.6 > 0.5: final motifs [0, 0.2], [0.2, 0.6]
// with depths 2, 5, 6, 7: R = 5, AR = 0.3, Rx = 7.
TEST(Motif, HandWorkedRoughnessMotifs) {
  const std::vector<double> y{0, -2, 3, -1, 1, -3, 4};
  const MotifParameters p = motif_parameters(y, 0.1, 0.5, 2.5);
  EXPECT_EQ(p.roughness_motifs, 2u);
  EXPECT_DOUBLE_EQ(p.R, 5.0);
  EXPECT_NEAR(p.AR, 0.3, 1e-12);
  EXPECT_DOUBLE_EQ(p.Rx, 7.0);
  // Envelope points (0, 0), (0.2, 3), (0.6, 4): one waviness motif [0, 0.6] (no interior
  // peak), valley 0: depths 0 and 4 -> W = 2, Wx = 4, AW = 0.6; Wte = 4 - 0.
  EXPECT_EQ(p.waviness_motifs, 1u);
  EXPECT_DOUBLE_EQ(p.W, 2.0);
  EXPECT_DOUBLE_EQ(p.Wx, 4.0);
  EXPECT_NEAR(p.AW, 0.6, 1e-12);
  EXPECT_DOUBLE_EQ(p.Wte, 4.0);
}

TEST(Motif, WiderLimitStillBlockedByEnlargement) {
  // Same profile with A = 1: at 0.2 the joined motif [0, 0.6] would have T = min(0, 4) - (-3)
  // = 3 < max(2, 6): C3 blocks it.
  const std::vector<double> y{0, -2, 3, -1, 1, -3, 4};
  const MotifParameters p = motif_parameters(y, 0.1, 1.0, 2.5);
  EXPECT_EQ(p.roughness_motifs, 2u);
  EXPECT_DOUBLE_EQ(p.R, 5.0);
}

TEST(Motif, RelativeDepthConditionKeepsEqualWavesApart) {
  // A pure sine: neighbouring motifs are equally deep, so C4 (min T < 0.6 joined T) fails and
  // every wave stays one motif of depth 2a and length lambda.
  std::vector<double> y(2001);
  for (std::size_t i = 0; i < y.size(); ++i)
    y[i] = std::cos(2 * std::numbers::pi * static_cast<double>(i) / 100.0);
  const MotifParameters p = motif_parameters(y, 0.001, 0.5, 2.5);  // lambda = 0.1 mm
  EXPECT_EQ(p.roughness_motifs, 20u);
  EXPECT_NEAR(p.R, 2.0, 1e-9);
  EXPECT_NEAR(p.AR, 0.1, 1e-9);
  EXPECT_NEAR(p.Wte, 0.0, 1e-9);  // the envelope through the crests is flat
}

TEST(Motif, WavinessOfTwoScales) {
  // Roughness 0.05 mm waves of amplitude 0.3 on a waviness of 1 mm and amplitude 3: the upper
  // envelope follows the waviness, whose motifs are 1 mm long and about 6 deep.
  const double spacing = 0.001;
  std::vector<double> y(8001);
  for (std::size_t i = 0; i < y.size(); ++i) {
    const double x = static_cast<double>(i) * spacing;
    y[i] = 3 * std::cos(2 * std::numbers::pi * x) + 0.3 * std::cos(2 * std::numbers::pi * x / 0.05);
  }
  const MotifParameters p = motif_parameters(y, spacing);
  EXPECT_NEAR(p.AW, 1.0, 0.05);
  EXPECT_NEAR(p.W, 6.0, 0.3);
  EXPECT_NEAR(p.Wte, 6.0, 0.1);  // crest 3 + 0.3 down to trough -3 + 0.3
  EXPECT_GT(p.roughness_motifs, 100u);
}

}  // namespace
}  // namespace chatterlab::surface
