#pragma once
// SIGINT and SIGTERM as a request to stop: while a StopSignals lives, the first such signal is
// only recorded (the command finishes the current step, saves what it has and says so); the
// handler resets itself (SA_RESETHAND), so a second Ctrl-C ends the process at once.
namespace duet::app {

class StopSignals {
 public:
  StopSignals();   // installs the handlers (process-wide; one StopSignals at a time)
  ~StopSignals();  // restores the previous handlers
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

  /// The signal received (SIGINT or SIGTERM), 0 while none.
  [[nodiscard]] static int received() noexcept;
  /// "SIGINT", "SIGTERM" or "signal N".
  [[nodiscard]] static const char* name(int signal) noexcept;
  /// The conventional exit code of a process stopped by `signal`: 128 + signal.
  [[nodiscard]] static int exit_code(int signal) noexcept { return 128 + signal; }
};

}  // namespace duet::app
