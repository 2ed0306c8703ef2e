#include "analysis/bp_network/bp_network.hpp"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "chatterlab/errors.hpp"
#include "chatterlab/input_files.hpp"
#include "chatterlab/plot.hpp"
#include "chatterlab/plugin_info.hpp"

namespace chatterlab {

namespace {

constexpr const char* weights_format = "chatterlab bp_network 3-4-1";
constexpr std::array<const char*, 3> feature_names{"variance", "residual_variance", "rho1"};

double sigmoid(double x) { return 1.0 / (1.0 + std::exp(-x)); }

// Features in network input order (sx2, sa2, rho1) with the variances on a log10 scale.
std::array<double, 3> transformed(const WindowFeatures& f) {
  constexpr double floor = 1e-300;  // an all-zero window: far below anything measured
  return {std::log10(std::max(f.variance, floor)), std::log10(std::max(f.residual_variance, floor)),
          f.rho1};
}

std::array<double, 2> range_param(const ParamValues& params, const char* key) {
  auto v = params.reals(key);
  if (v.size() != 2)
    throw InputError(fmt::format("bp_network.{}: expected [from, to] (2 times in s), got {} values",
                                 key, v.size()));
  return {v[0], v[1]};
}

}  // namespace

// ------------------------------------------------------------------ scaling
FeatureScaling FeatureScaling::fit(const std::vector<WindowFeatures>& training) {
  FeatureScaling s;
  const double n = static_cast<double>(training.size());
  for (std::size_t i = 0; i < 3; ++i) {
    double sum = 0.0, sum_sq = 0.0;
    for (const auto& f : training) sum += transformed(f)[i];
    s.mean[i] = sum / n;
    for (const auto& f : training) sum_sq += std::pow(transformed(f)[i] - s.mean[i], 2);
    const double sd = std::sqrt(sum_sq / n);
    s.std[i] = sd > 0.0 ? sd : 1.0;  // a feature constant over training carries no information
  }
  return s;
}

NetworkInput FeatureScaling::apply(const WindowFeatures& f) const {
  const auto g = transformed(f);
  return {(g[0] - mean[0]) / std[0], (g[1] - mean[1]) / std[1], (g[2] - mean[2]) / std[2]};
}

// ------------------------------------------------------------------ network
BackPropNetwork::BackPropNetwork(std::uint64_t seed, bool biases) : biases_(biases) {
  monitor::SplitMix64 rng(seed);
  auto uniform_pm1 = [&rng] { return 2.0 * rng.uniform01() - 1.0; };
  for (int i = 0; i < hidden_units; ++i)
    for (int j = 0; j < 3; ++j) w_hidden_(i, j) = uniform_pm1();
  for (int i = 0; i < hidden_units; ++i) w_output_(i) = uniform_pm1();
  if (biases_) {
    for (int i = 0; i < hidden_units; ++i) b_hidden_(i) = uniform_pm1();
    b_output_ = uniform_pm1();
  }
}

double BackPropNetwork::output(const NetworkInput& x) const {
  const Eigen::Matrix<double, hidden_units, 1> h = (w_hidden_ * x + b_hidden_).unaryExpr(&sigmoid);
  return sigmoid(w_output_.dot(h) + b_output_);
}

double BackPropNetwork::error(const std::vector<NetworkInput>& inputs,
                              const std::vector<double>& targets) const {
  double e = 0.0;
  for (std::size_t l = 0; l < inputs.size(); ++l) e += std::pow(output(inputs[l]) - targets[l], 2);
  return e;
}

TrainingResult BackPropNetwork::train(const std::vector<NetworkInput>& inputs,
                                      const std::vector<double>& targets,
                                      const TrainingOptions& options) {
  using Hidden = Eigen::Matrix<double, hidden_units, 1>;
  TrainingResult result;
  for (std::int64_t epoch = 0;; ++epoch) {
    // Batch gradient of e/2 (5-3..5-5: the weight change sums the error terms over all samples).
    Eigen::Matrix<double, hidden_units, 3> grad_w_hidden = Eigen::Matrix<double, hidden_units, 3>::Zero();
    Hidden grad_b_hidden = Hidden::Zero(), grad_w_output = Hidden::Zero();
    double grad_b_output = 0.0, e = 0.0;
    for (std::size_t l = 0; l < inputs.size(); ++l) {
      const Hidden h = (w_hidden_ * inputs[l] + b_hidden_).unaryExpr(&sigmoid);
      const double y = sigmoid(w_output_.dot(h) + b_output_);
      const double diff = y - targets[l];
      e += diff * diff;
      const double delta_out = diff * y * (1.0 - y);                 // (5-4)
      const Hidden delta_hidden =                                     // (5-5)
          (delta_out * w_output_).cwiseProduct(h.cwiseProduct(Hidden::Ones() - h));
      grad_w_output += delta_out * h;
      grad_b_output += delta_out;
      grad_w_hidden += delta_hidden * inputs[l].transpose();
      grad_b_hidden += delta_hidden;
    }
    result.error = e;
    result.epochs = epoch;
    if (e <= options.target_error) {
      result.converged = true;
      return result;
    }
    if (epoch >= options.max_epochs || !std::isfinite(e)) return result;
    const double eta = options.eta0 * std::exp(-options.alpha * static_cast<double>(epoch));
    w_output_ -= eta * grad_w_output;
    w_hidden_ -= eta * grad_w_hidden;
    if (biases_) {
      b_output_ -= eta * grad_b_output;
      b_hidden_ -= eta * grad_b_hidden;
    }
  }
}

Json BackPropNetwork::to_json() const {
  Json hidden = Json::array();
  for (int i = 0; i < hidden_units; ++i)
    hidden.push_back({w_hidden_(i, 0), w_hidden_(i, 1), w_hidden_(i, 2)});
  Json out = Json::array(), b_hidden = Json::array();
  for (int i = 0; i < hidden_units; ++i) {
    out.push_back(w_output_(i));
    b_hidden.push_back(b_hidden_(i));
  }
  return {{"biases", biases_},
          {"hidden_weights", std::move(hidden)},
          {"hidden_biases", std::move(b_hidden)},
          {"output_weights", std::move(out)},
          {"output_bias", b_output_}};
}

BackPropNetwork BackPropNetwork::from_json(const Json& j, const std::string& source) {
  auto bad = [&](const std::string& what) {
    return InputError(fmt::format("{}: not a 3-4-1 bp_network weights file: {}", source, what));
  };
  auto number = [&](const Json& v, const std::string& where) {
    if (!v.is_number() || !std::isfinite(v.get<double>()))
      throw bad(fmt::format("{} is not a finite number", where));
    return v.get<double>();
  };
  auto array_of = [&](const char* key, std::size_t size) -> const Json& {
    if (!j.contains(key) || !j[key].is_array() || j[key].size() != size)
      throw bad(fmt::format("'{}' must be an array of {} entries", key, size));
    return j[key];
  };
  BackPropNetwork net;
  if (!j.is_object() || !j.contains("biases") || !j["biases"].is_boolean())
    throw bad("missing boolean 'biases'");
  net.biases_ = j["biases"].get<bool>();
  const Json& hidden = array_of("hidden_weights", hidden_units);
  const Json& b_hidden = array_of("hidden_biases", hidden_units);
  const Json& out = array_of("output_weights", hidden_units);
  for (int i = 0; i < hidden_units; ++i) {
    const auto ui = static_cast<std::size_t>(i);
    if (!hidden[ui].is_array() || hidden[ui].size() != 3)
      throw bad(fmt::format("hidden_weights[{}] must have 3 entries", i));
    for (std::size_t k = 0; k < 3; ++k)
      net.w_hidden_(i, static_cast<int>(k)) =
          number(hidden[ui][k], fmt::format("hidden_weights[{}][{}]", i, k));
    net.b_hidden_(i) = number(b_hidden[ui], fmt::format("hidden_biases[{}]", i));
    net.w_output_(i) = number(out[ui], fmt::format("output_weights[{}]", i));
  }
  if (!j.contains("output_bias")) throw bad("missing 'output_bias'");
  net.b_output_ = number(j["output_bias"], "output_bias");
  return net;
}

Json ChatterNetwork::to_json() const {
  Json features = Json::array();
  for (const char* name : feature_names) features.push_back(name);
  return {{"format", weights_format},
          {"window_samples", window_samples},
          {"feature_scaling",
           {{"features", std::move(features)},
            {"transform", {"log10", "log10", "identity"}},
            {"mean", scaling.mean},
            {"std", scaling.std}}},
          {"network", network.to_json()},
          {"training", training}};
}

ChatterNetwork ChatterNetwork::from_json(const Json& j, const std::string& source) {
  auto bad = [&](const std::string& what) {
    return InputError(fmt::format("{}: not a bp_network weights file: {}", source, what));
  };
  if (!j.is_object() || j.value("format", "") != weights_format)
    throw bad(fmt::format("\"format\" must be \"{}\"", weights_format));
  ChatterNetwork c;
  if (!j.contains("window_samples") || !j["window_samples"].is_number_unsigned() ||
      j["window_samples"].get<std::size_t>() < 3)
    throw bad("\"window_samples\" must be an integer >= 3");
  c.window_samples = j["window_samples"].get<std::size_t>();
  const Json scaling = j.value("feature_scaling", Json::object());
  for (const char* key : {"mean", "std"}) {
    if (!scaling.contains(key) || !scaling[key].is_array() || scaling[key].size() != 3)
      throw bad(fmt::format("feature_scaling.{} must be an array of 3 numbers", key));
    for (std::size_t i = 0; i < 3; ++i) {
      const Json& v = scaling[key][i];
      if (!v.is_number() || !std::isfinite(v.get<double>()) ||
          (std::string(key) == "std" && v.get<double>() <= 0.0))
        throw bad(fmt::format("feature_scaling.{}[{}] must be a finite number{}", key, i,
                              std::string(key) == "std" ? " > 0" : ""));
      (std::string(key) == "mean" ? c.scaling.mean : c.scaling.std)[i] = v.get<double>();
    }
  }
  c.network = BackPropNetwork::from_json(j.value("network", Json()), source);
  c.training = j.value("training", Json::object());
  return c;
}

ChatterNetwork ChatterNetwork::load(const std::filesystem::path& file) {
  InputFileStream in(file);  // the run's snapshot (chatterlab/input_files.hpp)
  if (!in) throw InputError(fmt::format("{}: cannot open the weights file", file.string()));
  std::stringstream text;
  text << in.rdbuf();
  Json j = Json::parse(text.str(), nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) throw InputError(fmt::format("{}: not valid JSON", file.string()));
  return from_json(j, file.string());
}

// ------------------------------------------------------------------ labelled windows
LabelledWindows labelled_windows(const SampledSeries& series, std::size_t window_samples,
                                 std::array<double, 2> stable_s, std::array<double, 2> onset_s,
                                 double train_fraction) {
  LabelledWindows out;
  const double half_sample = 0.5 * series.sample_interval;
  for (int label = 0; label < 2; ++label) {
    const auto range = label == 0 ? stable_s : onset_s;
    std::size_t k = 0;  // window index within this class
    // Every window of the signal is visited (not stored: 10^6 of them for 10^7 samples).
    for_each_window(series.values, window_samples, window_samples, series.sample_interval,
                    [&](std::size_t first, double t_s, const WindowFeatures& f) {
                      const double start = static_cast<double>(first) * series.sample_interval;
                      if (start < range[0] - half_sample || t_s > range[1] + half_sample) return;
                      const double kf = static_cast<double>(k);
                      const bool train =
                          std::floor((kf + 1.0) * train_fraction) > std::floor(kf * train_fraction);
                      (train ? out.train_features : out.test_features).push_back(f);
                      (train ? out.train_labels : out.test_labels).push_back(label);
                      if (!train) out.test_t_s.push_back(t_s);
                      ++k;
                    });
  }
  return out;
}

// ------------------------------------------------------------------ plugin
PluginInfo BpNetworkAnalysis::info() {
  const TrainingOptions defaults;
  const ParamSpec window =
      monitor::count_spec("window_samples", "samples per feature window (book: 10)", 10, 3);
  auto range = [](const char* key, const char* what) {
    ParamSpec s = param_spec(key, ValueKind::real_list, "s",
                             fmt::format("[from, to]: signal time range labelled {}", what));
    s.optional = true;
    s.min = 0.0;
    s.min_items = 2;
    return s;
  };
  ParamSpec weights = param_spec("weights_file", ValueKind::string, "",
                                 "saved network (JSON) to use instead of training");
  weights.optional = true;
  ParamSpec fraction = param_spec("train_fraction", ValueKind::real, "1",
                                  "share of the labelled windows used for training, the rest "
                                  "test (book: 10 of 15)");
  fraction.default_value = 2.0 / 3.0;
  fraction.min = 0.0;
  fraction.min_exclusive = true;
  fraction.max = 1.0;
  ParamSpec eta0 = param_spec("eta0", ValueKind::real, "1", "initial back-propagation step");
  eta0.default_value = defaults.eta0;
  eta0.min = 0.0;
  eta0.min_exclusive = true;
  eta0.max = 100.0;
  ParamSpec alpha = param_spec("alpha", ValueKind::real, "1",
                               "step decay per epoch: eta = eta0 exp(-alpha t)");
  alpha.default_value = defaults.alpha;
  alpha.min = 0.0;
  alpha.max = 1.0;
  ParamSpec target = param_spec("target_error", ValueKind::real, "1",
                                "training stops when sum (y - yhat)^2 over the training windows "
                                "is at most this (book: 0.02)");
  target.default_value = defaults.target_error;
  target.min = 0.0;
  target.min_exclusive = true;
  ParamSpec epochs = param_spec("max_epochs", ValueKind::integer, "1",
                                "training gives up (not converged) after this many epochs");
  epochs.default_value = defaults.max_epochs;
  epochs.min = 1;
  epochs.max = 10'000'000;
  ParamSpec seed = param_spec("seed", ValueKind::integer, "1", "seed of the initial weights");
  seed.default_value = 1;
  seed.min = 0;
  ParamSpec biases = param_spec("biases", ValueKind::boolean, "",
                                "train thresholds (biases) too; the book keeps them at zero");
  biases.default_value = false;
  ParamSpec alarm = param_spec("alarm_output", ValueKind::real, "1",
                               "a window flags chatter when the network output is at least this");
  alarm.default_value = 0.5;
  alarm.min = 0.0;
  alarm.max = 1.0;
  alarm.min_exclusive = true;
  alarm.max_exclusive = true;
  return plugin_info("bp_network", "C1, C2",
                     {window, range("stable_s", "stable (target 0)"),
                      range("onset_s", "chatter onset (target 1)"), weights, fraction, eta0, alpha,
                      target, epochs, seed, biases, alarm, monitor::persistence_spec(5)},
                     {{"stable_s", {0.0, 0.15}}, {"onset_s", {0.2, 0.35}}},
                     "3-4-1 back-propagation network on window features: chatter-onset score per window, "
                     "trained from labelled time ranges or loaded from a weights file",
                     ThreadSafety::shareable);
}

BpNetworkAnalysis::BpNetworkAnalysis(const ParamValues& params)
    : window_(static_cast<std::size_t>(params.integer("window_samples"))),
      train_fraction_(params.real("train_fraction")),
      alarm_output_(params.real("alarm_output")),
      persistence_(static_cast<std::size_t>(params.integer("persistence_windows"))) {
  if (params.has("stable_s")) stable_s_ = range_param(params, "stable_s");
  if (params.has("onset_s")) onset_s_ = range_param(params, "onset_s");
  if (params.has("weights_file")) weights_file_ = params.string("weights_file");
  options_.eta0 = params.real("eta0");
  options_.alpha = params.real("alpha");
  options_.target_error = params.real("target_error");
  options_.max_epochs = params.integer("max_epochs");
  options_.seed = static_cast<std::uint64_t>(params.integer("seed"));
  options_.biases = params.boolean("biases");
}

void BpNetworkAnalysis::check(const SampledSeries& series) const {
  monitor::require_samples(series, window_, fmt::format("bp_network.window_samples = {}", window_));
  if (weights_file_) {
    const ChatterNetwork net = ChatterNetwork::load(*weights_file_);
    if (net.window_samples != window_)
      throw InputError(fmt::format(
          "bp_network.weights_file = \"{}\": trained on windows of {} samples, but "
          "bp_network.window_samples = {} (features depend on the window length)",
          *weights_file_, net.window_samples, window_));
  } else if (!stable_s_ || !onset_s_) {
    throw InputError(
        "bp_network: give either weights_file (a saved network) or both stable_s and onset_s "
        "(time ranges [from, to] in s labelling stable and chatter-onset parts of the signal)");
  }
  if (stable_s_.has_value() != onset_s_.has_value())
    throw InputError("bp_network: stable_s and onset_s go together (labels of both classes)");
  if (!stable_s_) return;
  const double end = monitor::end_time_s(series);
  const std::size_t min_windows = 2;
  for (const auto& [key, range] : {std::pair{"stable_s", *stable_s_}, std::pair{"onset_s", *onset_s_}}) {
    if (!(range[0] < range[1]))
      throw InputError(fmt::format("bp_network.{} = [{}, {}]: 'from' must be below 'to'", key,
                                   range[0], range[1]));
    if (range[1] > end + 0.5 * series.sample_interval)
      throw InputError(fmt::format(
          "bp_network.{} = [{}, {}]: outside the signal, which ends at t = {:.6g} s", key, range[0],
          range[1], end));
  }
  const LabelledWindows lw = labelled_windows(series, window_, *stable_s_, *onset_s_, train_fraction_);
  for (int label = 0; label < 2; ++label) {
    std::size_t n = 0;
    for (double l : lw.train_labels) n += l == label ? 1 : 0;
    for (double l : lw.test_labels) n += l == label ? 1 : 0;
    if (n < min_windows)
      throw InputError(fmt::format(
          "bp_network.{}: the range holds {} whole window(s) of {} samples, fewer than the {} "
          "needed (at least one to train and one to test)",
          label == 0 ? "stable_s" : "onset_s", n, window_, min_windows));
  }
}

ChatterNetwork BpNetworkAnalysis::trained(const SampledSeries& series, Json& details) const {
  LabelledWindows lw;
  if (stable_s_) lw = labelled_windows(series, window_, *stable_s_, *onset_s_, train_fraction_);
  ChatterNetwork net;
  if (weights_file_) {
    net = ChatterNetwork::load(*weights_file_);
    // Loaded: every labelled window is a test window.
    for (std::size_t i = 0; i < lw.train_features.size(); ++i) {
      lw.test_features.push_back(lw.train_features[i]);
      lw.test_labels.push_back(lw.train_labels[i]);
      lw.test_t_s.push_back(std::numeric_limits<double>::quiet_NaN());
    }
    details["training"] = {{"weights_file", *weights_file_}, {"saved_training", net.training}};
  } else {
    net.window_samples = window_;
    net.scaling = FeatureScaling::fit(lw.train_features);
    std::vector<NetworkInput> inputs;
    for (const auto& f : lw.train_features) inputs.push_back(net.scaling.apply(f));
    net.network = BackPropNetwork(options_.seed, options_.biases);
    const TrainingResult r = net.network.train(inputs, lw.train_labels, options_);
    net.training = {{"error", r.error},
                    {"epochs", r.epochs},
                    {"converged", r.converged},
                    {"target_error", options_.target_error},
                    {"eta0", options_.eta0},
                    {"alpha", options_.alpha},
                    {"seed", options_.seed},
                    {"biases", options_.biases},
                    {"train_windows", inputs.size()},
                    {"stable_s", *stable_s_},
                    {"onset_s", *onset_s_}};
    details["training"] = net.training;
  }
  // Test set, as the book's Table 5-1: scaled features, desired and actual output.
  Json rows = Json::array();
  std::size_t tp = 0, fp = 0, tn = 0, fn = 0;
  double test_error = 0.0;
  for (std::size_t i = 0; i < lw.test_features.size(); ++i) {
    const NetworkInput z = net.scaling.apply(lw.test_features[i]);
    const double y = net.network.output(z);
    const bool flagged = y >= alarm_output_, chatter = lw.test_labels[i] == 1.0;
    tp += flagged && chatter;
    fp += flagged && !chatter;
    tn += !flagged && !chatter;
    fn += !flagged && chatter;
    test_error += std::pow(y - lw.test_labels[i], 2);
    rows.push_back({{"t_s", std::isfinite(lw.test_t_s[i]) ? Json(lw.test_t_s[i]) : Json()},
                    {"scaled_features", {z(0), z(1), z(2)}},
                    {"desired", lw.test_labels[i]},
                    {"output", y}});
  }
  details["test"] = {{"windows", rows.size()},
                     {"error", test_error},
                     {"confusion",
                      {{"true_positive", tp},
                       {"false_positive", fp},
                       {"true_negative", tn},
                       {"false_negative", fn}}},
                     {"rows", std::move(rows)}};
  details["weights"] = net.to_json();
  return net;
}

monitor::ScoreTrack BpNetworkAnalysis::scores(const SampledSeries& series, Json& details) const {
  const ChatterNetwork net = trained(series, details);
  monitor::ScoreTrack track{"bp_network", "network output", {}, {}, alarm_output_};
  const std::size_t windows = series.values.size() / window_;
  track.t_s.reserve(windows);
  track.score.reserve(windows);
  for_each_window(series.values, window_, window_, series.sample_interval,
                  [&](std::size_t, double t_s, const WindowFeatures& f) {
                    track.t_s.push_back(t_s);
                    track.score.push_back(net.output(f));
                  });
  return track;
}

Json BpNetworkAnalysis::analyse(const SampledSeries& series, const Json& context) const {
  return analyse_with_arrays(series, context).merged();
}

ResultWithArrays BpNetworkAnalysis::analyse_with_arrays(const SampledSeries& series,
                                                        const Json& /*context*/) const {
  return monitor::detector_result(*this, series);
}

void BpNetworkAnalysis::plot(const Json& result, const SampledSeries& /*series*/,
                             const std::filesystem::path& out_dir) const {
  monitor::plot_scores(result, fmt::format("C2 network output per window of {} samples", window_),
                       "network output (0 stable, 1 chatter onset)", out_dir,
                       "bp_network_output");
}

}  // namespace chatterlab

CHATTERLAB_REGISTER_ANALYSIS(chatterlab::BpNetworkAnalysis);
