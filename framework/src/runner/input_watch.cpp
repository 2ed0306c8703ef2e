#include "runner/input_watch.hpp"

namespace chatterlab::runner {

InputWatch::InputWatch(std::shared_ptr<InputSnapshot> snapshot) : snapshot_(std::move(snapshot)) {
  if (!snapshot_) return;
  thread_ = std::thread([this] {
    std::unique_lock lock(mutex_);
    while (!stop_ && !changed_) {
      if (wake_.wait_for(lock, interval, [this] { return stop_; })) break;
      lock.unlock();
      std::vector<std::string> found = snapshot_->poll_changes();
      lock.lock();
      if (!found.empty()) {
        changes_ = std::move(found);
        changed_ = true;
      }
    }
  });
}

InputWatch::~InputWatch() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_one();
  if (thread_.joinable()) thread_.join();
}

std::vector<std::string> InputWatch::changes() const {
  std::lock_guard lock(mutex_);
  return changes_;
}

}  // namespace chatterlab::runner
