// The alarm persistence rule and the synthetic transition signal shared by the monitors.
#include "shared/monitoring/monitor_common.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <string>

#include "unit/study_test_support.hpp"

namespace chatterlab::monitor {
namespace {

ScoreTrack track_of(const std::vector<double>& scores) {
  ScoreTrack t{"test", "score", {}, scores, 0.5};
  for (std::size_t k = 0; k < scores.size(); ++k) t.t_s.push_back(0.1 * static_cast<double>(k));
  return t;
}

TEST(AlarmPersistence, RaisesAndClearsAfterRuns) {
  //                         0  1  2  3  4  5  6  7  8  9  10 11
  const auto t = track_of({0, 1, 0, 1, 1, 1, 1, 0, 1, 0, 0, 0});
  const AlarmReport r = track_alarms(t, 3, 2.0);
  // Single flag at 1 ignored; run 3..5 raises at 5; the 0 at 7 does not clear; 9..11 clears at 11.
  ASSERT_EQ(r.intervals.size(), 1u);
  EXPECT_DOUBLE_EQ(r.intervals[0].start_s, 0.5);
  EXPECT_DOUBLE_EQ(r.intervals[0].end_s, 0.1 * 11);
  EXPECT_FALSE(r.intervals[0].open);
  EXPECT_DOUBLE_EQ(*r.first_alarm_s, 0.5);
  EXPECT_DOUBLE_EQ(*r.first_flag_s, 0.1);
  const std::vector<bool> expected{false, false, false, false, false, true,
                                   true,  true,  true,  true,  true,  false};
  EXPECT_EQ(r.alarm, expected);

  // Persistence 1: every flagged evaluation is an alarm of its own.
  const AlarmReport raw = track_alarms(t, 1, 2.0);
  EXPECT_EQ(raw.intervals.size(), 3u);
  EXPECT_DOUBLE_EQ(*raw.first_alarm_s, 0.1);

  // Still on at the end: open, ending at the signal's end.
  const AlarmReport open = track_alarms(track_of({0, 1, 1, 1}), 2, 7.0);
  ASSERT_EQ(open.intervals.size(), 1u);
  EXPECT_TRUE(open.intervals[0].open);
  EXPECT_DOUBLE_EQ(open.intervals[0].end_s, 7.0);
  EXPECT_EQ(alarm_json(open).at("alarm_open_at_end"), true);
  EXPECT_TRUE(track_alarms(track_of({0, 0.49, 0}), 1, 1.0).intervals.empty());  // below threshold
}

// A plot's shading bucket is shaded when the alarm is on anywhere in it: an alarm between two
// shading lines (on from 2.04 s to 2.06 s, evaluations every 0.01 s) is found in the bucket
// [1.6, 2.4] s although it is off at both ends and at the bucket's centre.
TEST(AlarmWithin, AnAlarmShorterThanTheBucketIsFound) {
  DetectorTrack track;
  for (int k = 0; k <= 400; ++k) {
    track.t_s.push_back(0.01 * k);
    track.alarm.push_back(k >= 204 && k < 206 ? 1.0 : 0.0);
  }
  EXPECT_TRUE(alarm_within(track, 1.6, 2.4));
  EXPECT_TRUE(alarm_within(track, 2.045, 2.3));  // on at the bucket's start
  EXPECT_FALSE(alarm_within(track, 1.6, 2.035)); // ends before the alarm starts
  EXPECT_FALSE(alarm_within(track, 2.065, 3.0)); // starts after it ended
  EXPECT_FALSE(alarm_within(track, -1.0, -0.5)); // before the first evaluation
}

TEST(TransitionSignal, AmplitudeLawAndNoiseLevel) {
  TransitionSignal spec;
  EXPECT_EQ(spec.amplitude(spec.onset_s - 1e-9), 0.0);
  EXPECT_DOUBLE_EQ(spec.amplitude(spec.onset_s), spec.initial_amplitude);
  EXPECT_NEAR(spec.amplitude(spec.time_of_amplitude(2.0)), 2.0, 1e-12);
  EXPECT_NEAR(spec.amplitude(100.0), spec.saturation_amplitude, 1e-9);
  // Early growth is exponential at growth_per_s.
  EXPECT_NEAR(std::log(spec.amplitude(spec.onset_s + 0.04) / spec.amplitude(spec.onset_s)) / 0.04,
              spec.growth_per_s, 0.5);
  const std::vector<double> x = spec.samples();
  ASSERT_EQ(x.size(), 8000u);
  double sum_sq = 0;
  for (std::size_t i = 0; i < 4000; ++i) sum_sq += x[i] * x[i];
  EXPECT_NEAR(std::sqrt(sum_sq / 4000), spec.noise_rms, 0.05);  // se ~ 0.011
  EXPECT_EQ(spec.samples(), x);  // same seed, same signal
}

// A 10^7-sample signal gives 10^6 windows: the score plot must stay bounded and still show the one
// spike and the alarm.
TEST(ScorePlot, LongTracksAreDrawnBoundedWithTheirExtremes) {
  constexpr std::size_t n = 1000000;
  std::vector<double> t(n), score(n, 0.25);
  std::vector<bool> alarm(n, false);
  for (std::size_t k = 0; k < n; ++k) t[k] = 1e-3 * static_cast<double>(k);
  score[654321] = 7.5;
  alarm[654321] = true;
  const Json result{{"t_s", t}, {"score", score}, {"alarm", alarm}, {"persistence_windows", 1}, {"threshold", 0.5}};
  testing::TempDir dir;
  plot_scores(result, "scores", "score", dir.path(), "scores_test");
  std::ifstream in(dir.path() / "scores_test.dat");
  const std::string data{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  EXPECT_LT(std::count(data.begin(), data.end(), '\n'), 20000);
  EXPECT_NE(data.find("7.5"), std::string::npos);
  EXPECT_NE(data.find("654.321"), std::string::npos);  // the spike's time, kept with it
}

}  // namespace
}  // namespace chatterlab::monitor
