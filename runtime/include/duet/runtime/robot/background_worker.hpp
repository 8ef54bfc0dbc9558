#pragma once
/// @file background_worker.hpp
/// The runtime's background tasks (DESIGN.md §3: mapping, decisions and loop closure never
/// block control): one thread that runs submitted jobs in order, each inside the runtime's TBB
/// task arena (the kernels parallelise there). submit() never waits for a job.
/// Thread safety: submit(), pending() and wait_idle() may be called from any thread; the jobs
/// run one at a time on the worker's thread. The destructor waits for the running job and
/// drops the queued ones.
#include <tbb/task_arena.h>

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>

namespace duet {

class BackgroundWorker {
 public:
  /// `threads`: the arena's concurrency (0 = TBB's default, the machine's cores).
  explicit BackgroundWorker(int threads = 0);
  ~BackgroundWorker();
  BackgroundWorker(const BackgroundWorker&) = delete;
  BackgroundWorker& operator=(const BackgroundWorker&) = delete;

  /// Queues a job. An exception a job throws is kept and rethrown by rethrow_if_failed().
  void submit(std::function<void()> job);
  /// Jobs queued or running.
  [[nodiscard]] std::size_t pending() const;
  /// Blocks until no job is queued or running (not for a control thread: for shutdown and tests).
  void wait_idle();
  /// Rethrows the first exception a job threw (then forgets it).
  void rethrow_if_failed();

 private:
  void run();
  tbb::task_arena arena_;
  mutable std::mutex mutex_;
  std::condition_variable wake_, idle_;
  std::deque<std::function<void()>> queue_;
  std::size_t running_ = 0;
  bool stop_ = false;
  std::exception_ptr failure_;
  std::thread thread_;  // last: started once the rest exists
};

}  // namespace duet
