#include "base/background_worker.hpp"

#include <algorithm>

#include "base/real_time.hpp"

namespace rackcat::base {

BackgroundWorker& BackgroundWorker::shared() {
  static auto* const worker = new BackgroundWorker();  // NOLINT(cppcoreguidelines-owning-memory)
  return *worker;
}

BackgroundWorker::~BackgroundWorker() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void BackgroundWorker::schedule(Client& client) {
  {
    std::lock_guard lock(mutex_);
    if (std::find(queue_.begin(), queue_.end(), &client) != queue_.end()) return;
    queue_.push_back(&client);
    if (!thread_.joinable()) thread_ = std::thread([this] { run(); });
  }
  cv_.notify_all();
}

void BackgroundWorker::forget(Client& client) {
  std::unique_lock lock(mutex_);
  queue_.erase(std::remove(queue_.begin(), queue_.end(), &client), queue_.end());
  cv_.wait(lock, [&] { return running_ != &client; });
}

void BackgroundWorker::run() {
  (void)base::leave_real_time();  // a helper thread, not the device thread
  std::unique_lock lock(mutex_);
  for (;;) {
    cv_.wait(lock, [this] { return stop_ || !queue_.empty(); });
    if (queue_.empty()) return;  // stop requested and nothing queued
    Client* client = queue_.front();
    queue_.pop_front();
    running_ = client;
    lock.unlock();
    const bool more = client->run_one();
    lock.lock();
    running_ = nullptr;
    // Round robin: a client with more work goes to the back (unless it rescheduled itself).
    if (more && std::find(queue_.begin(), queue_.end(), client) == queue_.end()) {
      queue_.push_back(client);
    }
    cv_.notify_all();
  }
}

}  // namespace rackcat::base
