#include "rotorid/report/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <utility>

namespace rotorid {

namespace {

// At most 10 redraws per second.
constexpr std::chrono::milliseconds kMinRedrawInterval(100);
constexpr int kBarWidth = 28;

void WriteAll(int fd, const std::string& text) {
  size_t written = 0;
  while (written < text.size()) {
    const ssize_t n = ::write(fd, text.data() + written, text.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;  // progress is best effort: a closed terminal must not stop the work
    written += static_cast<size_t>(n);
  }
}

}  // namespace

Progress::Progress(std::string label, int64_t total, bool quiet) : Progress(std::move(label), total, quiet, 2) {}

Progress::Progress(std::string label, int64_t total, bool quiet, int fd)
    : label_(std::move(label)), total_(total), fd_(fd), enabled_(!quiet && ::isatty(fd) == 1) {
  start_ = std::chrono::steady_clock::now();
  last_draw_ = start_ - kMinRedrawInterval;
}

Progress::~Progress() { Finish(); }

void Progress::Update(int64_t done) {
  if (!enabled_) return;
  // A blocking lock: a step-wise count (a refinement's passes) must not lose an update to the ticker
  // drawing at that moment; a draw is one short write.
  std::unique_lock<std::mutex> lock(mutex_);
  if (finished_) return;
  last_done_ = std::max(last_done_, done);
  const auto now = std::chrono::steady_clock::now();
  if (now - last_draw_ < kMinRedrawInterval) return;
  last_draw_ = now;
  Draw(last_done_, false);
}

void Progress::StartTicking(std::chrono::milliseconds interval) {
  if (!enabled_ || ticker_.joinable()) return;
  ticker_ = std::thread([this, interval] {
    std::unique_lock<std::mutex> lock(mutex_);
    while (!finished_) {
      if (stop_ticking_.wait_for(lock, interval, [this] { return finished_; })) break;
      last_draw_ = std::chrono::steady_clock::now();
      Draw(last_done_, false);
    }
  });
}

void Progress::Finish() {
  if (!enabled_) return;
  std::unique_lock<std::mutex> lock(mutex_);
  if (finished_) return;
  finished_ = true;
  if (ticker_.joinable()) {
    stop_ticking_.notify_all();
    lock.unlock();
    ticker_.join();
    lock.lock();
  }
  // Only a line that was started needs its final state; short work stays silent.
  if (drawn_) Draw(total_ > 0 ? std::max(last_done_, total_) : last_done_, true);
}

void Progress::Draw(int64_t done, bool final_line) {
  const double elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  char numbers[96];
  std::string line = "\r" + label_ + " ";
  if (total_ > 0) {
    const double fraction = std::clamp(static_cast<double>(done) / static_cast<double>(total_), 0.0, 1.0);
    const int filled = static_cast<int>(fraction * kBarWidth + 0.5);
    line += "[" + std::string(filled, '#') + std::string(kBarWidth - filled, '.') + "]";
    std::snprintf(numbers, sizeof(numbers), " %3d%% (%lld/%lld) %.1f s", static_cast<int>(100.0 * fraction),
                  static_cast<long long>(done), static_cast<long long>(total_), elapsed_s);
    if (!final_line && fraction > 0.02 && fraction < 1.0) {
      const size_t used = std::char_traits<char>::length(numbers);
      std::snprintf(numbers + used, sizeof(numbers) - used, ", ~%.0f s left", elapsed_s * (1.0 - fraction) / fraction);
    }
  } else {
    if (done > 0)
      std::snprintf(numbers, sizeof(numbers), "%lld done, %.1f s", static_cast<long long>(done), elapsed_s);
    else
      std::snprintf(numbers, sizeof(numbers), final_line ? "done in %.1f s" : "running, %.1f s", elapsed_s);
  }
  line += numbers;
  // Clear what a longer previous line left behind.
  line += "\x1b[K";
  if (final_line) line += "\n";
  WriteAll(fd_, line);
  drawn_ = true;
}

}  // namespace rotorid
