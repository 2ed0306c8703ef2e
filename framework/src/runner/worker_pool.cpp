#include "runner/worker_pool.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "chatterlab/errors.hpp"
#include "chatterlab/input_files.hpp"
#include "runner/results_io.hpp"
#include "runner/worker_protocol.hpp"

extern char** environ;

namespace chatterlab::runner {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

std::string describe_wait_status(int status) {
  if (WIFSIGNALED(status)) {
    const int signal = WTERMSIG(status);
    const char* name = sigabbrev_np(signal);
    return fmt::format("killed by signal {} (SIG{}: {})", signal, name != nullptr ? name : "?",
                       strsignal(signal));
  }
  if (WIFEXITED(status)) return fmt::format("exited with status {}", WEXITSTATUS(status));
  return "ended";
}

ComputedPoint failed_point(std::size_t columns, const std::string& status, double elapsed_s) {
  ComputedPoint computed;
  computed.result.done = true;
  computed.result.outputs.assign(columns, Json());
  computed.result.status = status;
  computed.result.elapsed_s = elapsed_s;
  computed.compute_s = elapsed_s;
  return computed;
}

}  // namespace

WorkerPool::WorkerPool(const Study& study, const std::vector<std::string>& columns,
                       const RunOptions& options, int workers,
                       std::optional<double> point_timeout_s)
    : study_(&study),
      executable_(options.worker_executable.string()),
      timeout_s_(point_timeout_s),
      columns_(columns.size()) {
  Json inputs = Json::array();
  if (study.inputs) {
    for (const InputFileRecord& file : study.inputs->files()) {
      std::shared_ptr<const std::string> bytes = study.inputs->bytes_of(file.path);
      // Data and the study text travel with the setup; plugin libraries are loaded from disk by
      // the worker after it checked their hash.
      const bool send = bytes && file.role != InputRole::plugin;
      inputs.push_back({{"path", file.path.string()},
                        {"role", input_role_name(file.role)},
                        {"bytes", file.bytes},
                        {"sha256", file.sha256},
                        {"sent", send}});
      if (send) sent_bytes_.push_back(std::move(bytes));
    }
  }
  Json setup = {{"study", worker::study_to_json(study)},
                {"columns", columns},
                {"threads", workers},
                {"out_dir", options.out_dir.string()},
                {"plots", options.plots},
                {"inputs", std::move(inputs)}};
  setup_ = json_text(setup);
  for (int w = 0; w < workers; ++w) {
    Worker worker = spawn();
    if (worker.pid < 0)
      throw InputError(fmt::format("cannot start a worker process ({} {}): {}", executable_,
                                   worker::command_name, start_error_));
    workers_.push_back(worker);
  }
}

WorkerPool::~WorkerPool() {
  for (Worker& worker : workers_)
    if (worker.pid > 0) reap(worker, /*kill=*/true);
}

// A new worker, set up and ready; pid -1 with start_error_ set when it could not start.
WorkerPool::Worker WorkerPool::spawn() {
  Worker worker;
  int sockets[2];
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sockets) != 0) {
    start_error_ = fmt::format("socketpair: {}", std::strerror(errno));
    return worker;
  }
  // The worker's end becomes its fd 3 (dup2 clears close-on-exec there); never 3 already, where
  // dup2 would do nothing and leave the flag.
  if (sockets[1] == worker::socket_fd) {
    const int moved = ::fcntl(sockets[1], F_DUPFD_CLOEXEC, 10);
    ::close(sockets[1]);
    sockets[1] = moved;
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, sockets[1], worker::socket_fd);
  std::string program = executable_, command = worker::command_name,
              fd = std::to_string(worker::socket_fd), parent = std::to_string(::getpid());
  char* argv[] = {program.data(), command.data(), fd.data(), parent.data(), nullptr};
  pid_t pid = -1;
  const int error = posix_spawn(&pid, executable_.c_str(), &actions, nullptr, argv, environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(sockets[1]);
  if (error != 0) {
    ::close(sockets[0]);
    start_error_ = std::strerror(error);
    return worker;
  }
  worker.pid = pid;
  worker.fd = sockets[0];
  bool sent = worker::write_frame(worker.fd, setup_);
  for (const auto& bytes : sent_bytes_) sent = sent && worker::write_frame(worker.fd, *bytes);
  std::optional<std::string> reply = sent ? worker::read_frame(worker.fd) : std::nullopt;
  Json answer = reply ? Json::parse(*reply, nullptr, false) : Json();
  if (answer.is_object() && answer.value("ready", false)) return worker;
  start_error_ = answer.is_object() && answer.contains("fatal")
                     ? answer["fatal"].get<std::string>()
                     : "it ended during setup (" + reap(worker, false) + ")";
  if (worker.pid > 0) reap(worker, true);
  worker.pid = -1;
  return worker;
}

std::string WorkerPool::reap(Worker& worker, bool kill) {
  if (worker.fd >= 0) ::close(worker.fd);
  worker.fd = -1;
  if (worker.pid <= 0) return {};
  if (kill) ::kill(worker.pid, SIGKILL);
  int status = 0;
  while (::waitpid(worker.pid, &status, 0) < 0 && errno == EINTR) {
  }
  worker.pid = -1;
  return describe_wait_status(status);
}

void WorkerPool::run(const std::vector<std::size_t>& todo,
                     const std::function<void(std::size_t, ComputedPoint&&)>& done,
                     const std::atomic<bool>& stop) {
  std::size_t next = 0, finished = 0;
  auto replace = [&](Worker& worker) {
    if (next >= todo.size()) return;  // nothing left for a new worker
    worker = spawn();
  };
  while (finished < todo.size() && !stop.load()) {
    // Hand out points to idle workers.
    for (Worker& worker : workers_) {
      if (worker.pid < 0 || worker.busy || next >= todo.size()) continue;
      worker.k = next++;
      worker.busy = true;
      worker.started = Clock::now();
      if (!worker::write_frame(worker.fd, json_text(Json{{"point", todo[worker.k]}}))) {
        // Died while idle (killed from outside): not this point's fault; hand it on.
        const std::string how = reap(worker, true);
        worker.busy = false;
        --next;
        replace(worker);
        if (worker.pid < 0)
          start_error_ = fmt::format("a worker {} and no new one could start: {}", how,
                                     start_error_);
      }
    }
    const bool any_alive = std::any_of(workers_.begin(), workers_.end(),
                                       [](const Worker& w) { return w.pid > 0; });
    if (!any_alive) {  // nothing can compute the rest: they fail with the reason
      for (; next < todo.size(); ++next, ++finished)
        done(next, failed_point(columns_,
                                failure_status("no worker process could be started: " +
                                               start_error_),
                                0.0));
      break;
    }

    // Wait for a result, the nearest deadline, or 0.2 s (to notice `stop`).
    std::vector<pollfd> fds;
    std::vector<Worker*> polled;
    int wait_ms = 200;
    const Clock::time_point now = Clock::now();
    for (Worker& worker : workers_) {
      if (worker.pid < 0 || !worker.busy) continue;
      fds.push_back({worker.fd, POLLIN, 0});
      polled.push_back(&worker);
      if (timeout_s_) {
        const double left = *timeout_s_ - seconds_between(worker.started, now);
        wait_ms = std::min(wait_ms, std::max(0, static_cast<int>(left * 1000.0) + 1));
      }
    }
    if (::poll(fds.data(), fds.size(), wait_ms) < 0 && errno != EINTR)
      throw std::runtime_error(fmt::format("poll: {}", std::strerror(errno)));

    for (std::size_t i = 0; i < fds.size(); ++i) {
      Worker& worker = *polled[i];
      const double elapsed = seconds_between(worker.started, Clock::now());
      if (fds[i].revents != 0) {
        std::optional<std::string> frame = worker::read_frame(worker.fd);
        Json reply = frame ? Json::parse(*frame, nullptr, false) : Json();
        if (reply.is_object() && reply.contains("record")) {
          JournalContents parsed = parse_journal_records(reply["record"].get<std::string>(),
                                                         todo[worker.k] + 1, columns_);
          if (parsed.records.size() != 1 || parsed.records[0].first != todo[worker.k])
            throw std::logic_error("runner: a worker returned a garbled result");
          ComputedPoint computed;
          computed.result = std::move(parsed.records[0].second);
          computed.compute_s = reply.value("compute_s", elapsed);
          computed.output_failed = reply.value("output_failed", false);
          worker.busy = false;
          ++finished;
          done(worker.k, std::move(computed));
          continue;
        }
        // The worker ended in the middle of the point: a crash, abort() or exit() in a plugin.
        const std::string how = reap(worker, true);
        worker.busy = false;
        ++finished;
        // No time in the text: results.csv must not depend on how fast a crash came.
        const std::string what =
            fmt::format("the point's worker process {}; the rest of the run goes on", how);
        done(worker.k,
             failed_point(columns_,
                          failure_status(with_plugin_context(
                              what, study_->point_document(todo[worker.k]), study_->file.string())),
                          elapsed));
        replace(worker);
        continue;
      }
      if (timeout_s_ && elapsed >= *timeout_s_) {
        reap(worker, true);
        worker.busy = false;
        ++finished;
        done(worker.k, failed_point(columns_,
                                    timeout_status(fmt::format(
                                        "still running after the time limit of {} s "
                                        "(point_timeout_s); its worker process was killed",
                                        *timeout_s_)),
                                    elapsed));
        replace(worker);
      }
    }
  }
  if (stop.load())
    for (Worker& worker : workers_)
      if (worker.pid > 0 && worker.busy) reap(worker, true);
}

}  // namespace chatterlab::runner
