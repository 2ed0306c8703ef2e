#include "analysis/embedding/embedding.hpp"

#include <gtest/gtest.h>

#include "shared/nonlinear/nonlinear_common.hpp"
#include "shared/nonlinear/test_signals.hpp"
#include "chatterlab/errors.hpp"
#include "unit/study_test_support.hpp"

namespace chatterlab {
namespace {

using test_signals::make_analysis;
using test_signals::series;

// Delay vectors are read from the series (no copy): coordinate k of vector i is x[i + k delay],
// and the k-d tree built over the view finds the nearest neighbour outside the Theiler window
// that a search over every vector finds.
TEST(Embedding, DelayVectorsAreViewsOfTheSeriesAndTheTreeFindsTheNearest) {
  const std::vector<double> x = test_signals::lorenz(3000, 0.01);
  const int dimension = 3, delay = 7;
  const std::size_t theiler = 20;
  const nonlinear::Embedding e(x, dimension, delay);
  ASSERT_EQ(e.size(), x.size() - 14);
  EXPECT_EQ(e.coordinate(100, 2), x[114]);
  EXPECT_EQ(e.kdtree_get_pt(5, 1), x[12]);
  const nonlinear::NeighbourSearch search(e);
  for (std::size_t i = 0; i < e.size(); i += 97) {
    std::size_t best = e.size();
    for (std::size_t j = 0; j < e.size(); ++j)
      if ((j > i ? j - i : i - j) > theiler && (best == e.size() || e.distance(i, j) < e.distance(i, best)))
        best = j;
    const auto nn = search.nearest(i, 1, theiler, e.size());
    ASSERT_EQ(nn.size(), 1u);
    EXPECT_EQ(nn[0].index, best) << "vector " << i;
    EXPECT_NEAR(nn[0].distance, e.distance(i, best), 1e-12 * e.distance(i, best));
  }
  EXPECT_THROW(nonlinear::Embedding(x, 65, 1), PointFailure);
}

TEST(Embedding, HenonNeedsDelayOneDimensionTwo) {
  const Json r = make_analysis("embedding")->analyse(
      series(test_signals::henon(10000), 1.0, "henon x"), Json::object());
  EXPECT_EQ(r["delay_samples"]["value"], 1);
  EXPECT_EQ(r["embedding_dimension"]["value"], 2);
  EXPECT_EQ(r["fnn_dimension"], 2);
  EXPECT_EQ(r["cao_dimension"], 2);
  EXPECT_TRUE(r["deterministic"].get<bool>());
}

TEST(Embedding, LorenzDelayAtFirstMutualInformationMinimum) {
  const Json r = make_analysis("embedding")->analyse(
      series(test_signals::lorenz(20000), 0.01, "lorenz x"), Json::object());
  // The first AMI minimum of Lorenz x at dt = 0.01 lies near 0.16 time units (Fraser & Swinney
  // style estimates give 0.15-0.18).
  EXPECT_GE(r["delay_samples"]["value"].get<int>(), 12);
  EXPECT_LE(r["delay_samples"]["value"].get<int>(), 20);
  EXPECT_EQ(r["delay_samples"]["quality"], "good");
  EXPECT_EQ(r["embedding_dimension"]["value"], 3);
}

TEST(Embedding, WhiteNoiseShowsNoDeterminism) {
  const Json r = make_analysis("embedding")->analyse(
      series(test_signals::white_noise(5000, 7), 1.0, "noise"), Json::object());
  EXPECT_FALSE(r["deterministic"].get<bool>());
}

TEST(Embedding, BadSeriesNameTheProblem) {
  auto analysis = make_analysis("embedding");
  std::vector<double> constant(500, 3.0);
  try {
    analysis->analyse(series(constant, 1.0, "signal column 'a'"), Json::object());
    FAIL() << "constant signal accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("signal column 'a': the signal is constant"),
              std::string::npos)
        << e.what();
  }
  try {
    analysis->analyse(series(std::vector<double>(50, 1.0), 1.0, "short"), Json::object());
    FAIL() << "short signal accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("at least 101 samples"), std::string::npos) << e.what();
  }
}

// Cao's E1 and E2 and the FNN fractions are sums over up to 10,000 reference vectors: summed in
// fixed blocks merged in block order, they are the same bits with one thread, with two, and from
// one run to the next (a `reduction` made E1 differ by 1e-15 between runs).
TEST(Embedding, CaoAndFnnDoNotDependOnTheThreadCount) {
  const auto x = test_signals::lorenz(20000);
  const auto [one, two, again] = testing::with_one_two_two_threads([&] {
    return choose_dimension(x, 16, 6, 100, embedding_default_distance_ratio,
                            embedding_default_fnn_threshold);
  });
  ASSERT_EQ(one.cao_e1.size(), 6u);
  EXPECT_EQ(one.cao_e1, two.cao_e1);
  EXPECT_EQ(one.cao_e2, two.cao_e2);
  EXPECT_EQ(one.fnn_fraction, two.fnn_fraction);
  EXPECT_EQ(two.cao_e1, again.cao_e1);
  EXPECT_EQ(two.cao_e2, again.cao_e2);
  EXPECT_EQ(two.fnn_fraction, again.fnn_fraction);
}

}  // namespace
}  // namespace chatterlab
