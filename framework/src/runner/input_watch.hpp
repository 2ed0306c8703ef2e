#pragma once
// Watches a run's input files while its points are computed: every `interval` it compares them
// with the hashes the run read (InputSnapshot::poll_changes: a stat() per file, a re-hash only
// when that changed). A change raises `changed` (the runner stops handing out points: their
// results would describe data that is no longer there) and keeps the messages. The end of the
// run compares every file once more in full (InputSnapshot::changes).
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "chatterlab/input_files.hpp"

namespace chatterlab::runner {

class InputWatch {
 public:
  static constexpr std::chrono::milliseconds interval{1000};

  explicit InputWatch(std::shared_ptr<InputSnapshot> snapshot);  // null: watches nothing
  ~InputWatch();
  InputWatch(const InputWatch&) = delete;
  InputWatch& operator=(const InputWatch&) = delete;

  const std::atomic<bool>& changed() const { return changed_; }
  std::vector<std::string> changes() const;

 private:
  std::shared_ptr<InputSnapshot> snapshot_;
  std::atomic<bool> changed_{false};
  std::vector<std::string> changes_;
  bool stop_ = false;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::thread thread_;
};

}  // namespace chatterlab::runner
