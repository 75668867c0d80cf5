#pragma once

// Progress of long work (refine, ablate, diagnose, long logs) on stderr, for people watching a
// terminal. It draws only when stderr is a terminal and quiet is off, at most 10 times a second,
// and prints nothing at all otherwise, so logs, pipes and CI output stay clean.
//
//   Progress progress("ablate", configurations.size(), options.quiet);
//   for (size_t k = 0; k < configurations.size(); ++k) {
//     ...
//     progress.Update(k + 1);
//   }
//   progress.Finish();  // or let the destructor do it

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>

namespace rotorid {

class Progress {
 public:
  // `total` <= 0: the amount of work is unknown; a count and the elapsed time are shown.
  Progress(std::string label, int64_t total, bool quiet = false);
  // Draws on `fd` instead of stderr (for tests and callers with their own terminal).
  Progress(std::string label, int64_t total, bool quiet, int fd);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  // Reports that `done` units are finished. Thread-safe; cheap when nothing is drawn.
  void Update(int64_t done);
  // Redraws on its own every `interval` until Finish, for work that reports no steps (a single
  // solver run): the line then shows the elapsed time. Nothing happens when nothing is drawn.
  void StartTicking(std::chrono::milliseconds interval = std::chrono::milliseconds(250));
  // Draws the final state and ends the line (once; later calls do nothing).
  void Finish();
  // Whether anything is drawn at all.
  bool enabled() const { return enabled_; }

 private:
  void Draw(int64_t done, bool final_line);

  std::string label_;
  int64_t total_ = 0;
  int fd_ = 2;
  bool enabled_ = false;
  bool finished_ = false;
  bool drawn_ = false;
  int64_t last_done_ = 0;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
  std::mutex mutex_;
  std::condition_variable stop_ticking_;
  std::thread ticker_;
};

}  // namespace rotorid
