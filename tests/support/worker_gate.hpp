// Holds a base::BackgroundWorker until opened: a job scheduled meanwhile cannot have run, so a
// test sees what the calling (device) thread did on its own, then opens the gate and sees the
// worker's part.
#pragma once

#include <future>

#include "base/background_worker.hpp"

namespace rackcat::testing {

class WorkerGate final : public base::BackgroundWorker::Client {
 public:
  // Returns once the worker runs the gate (and so runs nothing else).
  explicit WorkerGate(base::BackgroundWorker& worker) : worker_(worker) {
    worker_.schedule(*this);
    entered_.get_future().wait();
  }
  // Opens the gate if the test did not, and waits until the worker has left it.
  ~WorkerGate() {
    if (!opened_) open();
    worker_.forget(*this);
  }
  WorkerGate(const WorkerGate&) = delete;
  WorkerGate& operator=(const WorkerGate&) = delete;
  void open() {
    opened_ = true;
    open_.set_value();
  }

 private:
  bool run_one() override {
    entered_.set_value();
    open_.get_future().wait();
    return false;
  }
  base::BackgroundWorker& worker_;
  bool opened_ = false;
  std::promise<void> entered_;
  std::promise<void> open_;
};

}  // namespace rackcat::testing
