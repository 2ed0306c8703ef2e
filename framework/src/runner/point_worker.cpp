// The worker side of point isolation (runner/worker_protocol.hpp): `chatterlab __worker FD PID`,
// started by the runner, never by hand. It rebuilds the runner's study from the setup frame
// (no file is read again: the data files' bytes come with it, and each plugin library is
// checked against the hash the runner recorded before it is loaded), then computes one point
// per request with the same code as an in-process run.
#include <omp.h>
#include <sys/prctl.h>
#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <memory>
#include <string>

#include "chatterlab/errors.hpp"
#include "chatterlab/input_files.hpp"
#include "chatterlab/plugin_api.hpp"
#include "chatterlab/runner.hpp"
#include "chatterlab/study_kind.hpp"
#include "runner/point_compute.hpp"
#include "runner/results_io.hpp"
#include "runner/worker_protocol.hpp"

namespace chatterlab {

namespace {

using runner::json_text;
namespace worker = runner::worker;

InputRole role_named(const std::string& name) {
  if (name == "study") return InputRole::study;
  if (name == "plugin") return InputRole::plugin;
  return InputRole::data;
}

// The runner's snapshot, rebuilt: data and study bytes as sent; plugin libraries checked
// against their recorded hashes (a library rebuilt on disk since the run began would compute
// with other code) and loaded.
std::shared_ptr<InputSnapshot> receive_inputs(int fd, const Json& records,
                                              const std::vector<std::string>& libraries) {
  auto snapshot = std::make_shared<InputSnapshot>();
  for (const Json& r : records) {
    InputFileRecord record{r.at("path").get<std::string>(), role_named(r.at("role")),
                           r.at("bytes").get<std::uint64_t>(), r.at("sha256").get<std::string>()};
    if (r.at("sent").get<bool>()) {
      std::optional<std::string> bytes = worker::read_frame(fd);
      if (!bytes) throw std::runtime_error("the runner closed the connection during setup");
      snapshot->add(record, std::make_shared<const std::string>(std::move(*bytes)));
    } else {
      snapshot->add(record, nullptr);
    }
  }
  for (const std::string& library : libraries) {
    const std::string recorded = [&] {
      for (const InputFileRecord& f : snapshot->files())
        if (f.path == input_key(library)) return f.sha256;
      return std::string();
    }();
    std::shared_ptr<const std::string> bytes = [&] {
      InputScope direct(nullptr);  // from disk, not from the (hash-only) snapshot
      return read_input_file(library, InputRole::plugin);
    }();
    if (!recorded.empty() && sha256_hex(*bytes) != recorded)
      throw InputError(library + ": changed since the run read it (the plugin library on disk "
                                 "is not the one the run started with)");
    load_plugin_library(library);
  }
  return snapshot;
}

int serve(int fd) {
  std::optional<std::string> setup_text = worker::read_frame(fd);
  if (!setup_text) return 2;
  const Json setup = Json::parse(*setup_text);
  const Study study = [&] {
    Study s = worker::study_from_json(setup.at("study"));
    s.inputs = receive_inputs(fd, setup.at("inputs"), s.plugin_libraries);
    return s;
  }();
  InputScope reads_through(study.inputs);
  auto kind = study_kind_registry().at(study.kind).create(ParamValues{});
  const auto columns = setup.at("columns").get<std::vector<std::string>>();
  const std::filesystem::path out_dir = setup.at("out_dir").get<std::string>();
  const bool plots = setup.at("plots").get<bool>();
  // The OpenMP team a point's own parallel loops get, as in the runner's threads: inside the
  // runner's parallel loop over points (threads > 1) nested regions run on one thread (the
  // default max-active-levels of 1); with threads = 1 that loop is inactive and they get the
  // default team. Same team, same reduction order, same bytes.
  if (setup.at("threads").get<int>() > 1 && omp_get_max_active_levels() <= 1)
    omp_set_num_threads(1);
  if (!worker::write_frame(fd, json_text(Json{{"ready", true}}))) return 2;

  for (;;) {
    std::optional<std::string> request = worker::read_frame(fd);
    if (!request) return 0;  // the runner is done (or gone)
    const std::size_t point = Json::parse(*request).at("point").get<std::size_t>();
    runner::ComputedPoint computed =
        runner::compute_point(*kind, study, point, columns, out_dir, plots);
    Json reply = {{"record", runner::journal_line(point, computed.result)},
                  {"compute_s", computed.compute_s},
                  {"output_failed", computed.output_failed}};
    if (!worker::write_frame(fd, json_text(reply))) return 0;
  }
}

}  // namespace

int run_point_worker(int argc, char** argv) {
  if (argc < 4) return 2;
  const int fd = std::atoi(argv[2]);
  const pid_t parent = static_cast<pid_t>(std::atol(argv[3]));
  // A worker never outlives its runner (killed with kill -9, its workers go too), so it can
  // never hold on to the output directory or keep computing for nobody.
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (::getppid() != parent) return 2;
  try {
    return serve(fd);
  } catch (...) {
    worker::write_frame(fd, json_text(Json{{"fatal", describe_current_exception()}}));
    return 2;
  }
}

}  // namespace chatterlab
