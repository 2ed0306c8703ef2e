#pragma once
// MODELS.md C2 (book 5.1, eqs 5-1..5-7): the 3-4-1 feed-forward network that recognises chatter
// onset from the window features of C1. Inputs (sx2, sa2, rho1) through a linear input layer
// (f(x) = x after scaling), 4 sigmoid hidden units, 1 sigmoid output f(x) = 1/(1 + e^-x) (5-7);
// thresholds zero as in the book (biases optional). Output 0 = stable, 1 = chatter onset.
// Trained by batch back-propagation on e = sum_l (y_l - yhat_l)^2 (5-6) with the decaying step
// eta = eta0 e^{-alpha t} (t = epoch), stopping at e <= 0.02.
//
// Feature scaling (the book normalises but does not say how; its raw features differ by orders of
// magnitude): z_i = (g_i(f_i) - m_i) / s_i with g = log10 for the two variances (they grow by
// decades as chatter builds up) and identity for rho1; m_i, s_i are mean and standard deviation
// over the training windows, saved with the weights.
#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "shared/monitoring/monitor_common.hpp"
#include "shared/monitoring/features.hpp"
#include "chatterlab/analysis.hpp"
#include "chatterlab/analysis_arrays.hpp"

namespace chatterlab {

using NetworkInput = Eigen::Vector3d;  // scaled (sx2, sa2, rho1)

struct FeatureScaling {
  std::array<double, 3> mean{0, 0, 0}, std{1, 1, 1};
  static FeatureScaling fit(const std::vector<WindowFeatures>& training);
  NetworkInput apply(const WindowFeatures& f) const;
};

struct TrainingOptions {
  double eta0 = 2.0;           // initial step
  double alpha = 1e-4;         // step decay per epoch
  double target_error = 0.02;  // stop when e (5-6) <= this
  std::int64_t max_epochs = 50000;
  std::uint64_t seed = 1;      // initial weights
  bool biases = false;         // book: zero thresholds
};

struct TrainingResult {
  double error = 0.0;  // e (5-6) on the training set when training stopped
  std::int64_t epochs = 0;
  bool converged = false;
};

class BackPropNetwork {
 public:
  static constexpr int hidden_units = 4;

  // Random initial weights, uniform in [-1, 1], from `seed` (same seed, same network).
  BackPropNetwork(std::uint64_t seed, bool biases);

  double output(const NetworkInput& x) const;
  // Batch back-propagation until e <= target_error or max_epochs.
  TrainingResult train(const std::vector<NetworkInput>& inputs, const std::vector<double>& targets,
                       const TrainingOptions& options);
  // e (5-6) over a data set.
  double error(const std::vector<NetworkInput>& inputs, const std::vector<double>& targets) const;

  Json to_json() const;
  // Throws InputError naming `source` when the JSON is not a 3-4-1 network.
  static BackPropNetwork from_json(const Json& j, const std::string& source);

 private:
  BackPropNetwork() = default;
  Eigen::Matrix<double, hidden_units, 3> w_hidden_ = Eigen::Matrix<double, hidden_units, 3>::Zero();
  Eigen::Matrix<double, hidden_units, 1> b_hidden_ = Eigen::Matrix<double, hidden_units, 1>::Zero();
  Eigen::Matrix<double, hidden_units, 1> w_output_ = Eigen::Matrix<double, hidden_units, 1>::Zero();
  double b_output_ = 0.0;
  bool biases_ = false;
};

// A trained monitor: network + scaling + window length, as saved in a weights file.
struct ChatterNetwork {
  BackPropNetwork network{1, false};
  FeatureScaling scaling;
  std::size_t window_samples = 10;
  Json training = Json::object();  // how it was trained (for the record)

  double output(const WindowFeatures& f) const { return network.output(scaling.apply(f)); }
  Json to_json() const;
  static ChatterNetwork from_json(const Json& j, const std::string& source);
  static ChatterNetwork load(const std::filesystem::path& file);  // InputError naming the file
};

// Labelled windows cut from one signal: non-overlapping windows of window_samples lying wholly in
// [stable_s) (label 0) or [onset_s) (label 1). Windows go to training or test by interleaving:
// window k of a class is a training window when floor((k+1) f) > floor(k f), f = train_fraction,
// so both sets span the whole labelled range (f = 2/3: 10 of 15 train, as in the book).
struct LabelledWindows {
  std::vector<WindowFeatures> train_features, test_features;
  std::vector<double> train_labels, test_labels, test_t_s;
};
LabelledWindows labelled_windows(const SampledSeries& series, std::size_t window_samples,
                                 std::array<double, 2> stable_s, std::array<double, 2> onset_s,
                                 double train_fraction);

class BpNetworkAnalysis final : public Analysis, public AnalysisWithArrays, public monitor::Detector {
 public:
  static PluginInfo info();
  explicit BpNetworkAnalysis(const ParamValues& params);

  Json analyse(const SampledSeries& series, const Json& context) const override;
  // t_s, score and alarm (one value per evaluation) as vectors.
  ResultWithArrays analyse_with_arrays(const SampledSeries& series, const Json& context) const override;
  void plot(const Json& result, const SampledSeries& series,
            const std::filesystem::path& out_dir) const override;

  void check(const SampledSeries& series) const override;
  monitor::ScoreTrack scores(const SampledSeries& series, Json& details) const override;
  std::size_t persistence() const override { return persistence_; }

 private:
  ChatterNetwork trained(const SampledSeries& series, Json& details) const;

  std::size_t window_;
  std::optional<std::array<double, 2>> stable_s_, onset_s_;
  std::optional<std::string> weights_file_;
  double train_fraction_, alarm_output_;
  TrainingOptions options_;
  std::size_t persistence_;
};

}  // namespace chatterlab
