// One worker thread shared by every device of the process for its slow file work, so that the
// device thread never waits for a disk: the Fusion.IO device's 0xFBF0 reset, 0xFBF2 store,
// 0xFBF3 checksum, 0xFBF4 load (mdp/parameter_writer.hpp), and the FoE files of devices
// emulated from their ESI (device/foe_files.hpp). A process with 256 slaves has one such
// thread, not 256: the thread count does not grow with the slave count.
// The thread starts with the first job, so a process that never stores has none
// (and ecat::drop_privileges, which refuses a multi-threaded process, is unaffected).
//
// A client (a ParameterWriter, a FoeFiles) schedules itself when it has queued work; the worker
// calls its run_one() until the client says nothing is left. Clients are served round robin, one
// job at a time, so a long store of one device delays another device's command by one job at most.
#pragma once

#include <condition_variable>
#include <deque>
#include <mutex>
#include <thread>

namespace rackcat::base {

class BackgroundWorker {
 public:
  class Client {
   public:
    // Runs one queued job; returns true when more are queued.
    virtual bool run_one() = 0;

   protected:
    ~Client() = default;
  };

  // The process-wide worker (created on first use, never destroyed: its thread may still be
  // waiting for work when static objects are torn down at exit).
  static BackgroundWorker& shared();

  BackgroundWorker() = default;
  ~BackgroundWorker();
  BackgroundWorker(const BackgroundWorker&) = delete;
  BackgroundWorker& operator=(const BackgroundWorker&) = delete;

  // `client` has work: run_one() will be called on the worker thread. Scheduling a client
  // that is already scheduled is a no-op.
  void schedule(Client& client);
  // After this returns the worker neither holds nor runs `client` (its destructor calls it).
  void forget(Client& client);

 private:
  void run();

  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Client*> queue_;
  Client* running_ = nullptr;
  bool stop_ = false;
  std::thread thread_;
};

}  // namespace rackcat::base
