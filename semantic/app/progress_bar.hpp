#pragma once

// A progress bar for the rise-semantic program's long runs (6D SLAM over
// many scans). On a terminal it redraws one line per stage in place; when
// the stream is not a terminal (a log file, CI) it writes one plain line as
// each stage ends, so logs stay readable.

#include <chrono>
#include <cstddef>
#include <cstdio>
#include <functional>
#include <string>
#include <string_view>

namespace rise::semantic {

/// "stage   [#########.........]  45%  9/20": the bar line, `width` cells
/// of bar. done is clamped to total; total 0 draws an empty bar at 0 %.
std::string progress_line(std::size_t done, std::size_t total, std::string_view stage, int width = 30);

class ProgressBar {
 public:
  /// Draws on `out` (not owned); redraws in place when it is a terminal.
  explicit ProgressBar(std::FILE* out = stderr);
  /// Forces the mode, for streams isatty() cannot judge.
  ProgressBar(std::FILE* out, bool terminal);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  /// Reports `done` of `total` steps of `stage`; a new stage name ends the
  /// previous one. Cheap when nothing visible changes.
  void update(std::size_t done, std::size_t total, std::string_view stage);
  /// Ends the current stage's line (also done by the destructor).
  void finish();
  /// This bar as a progress callback (e.g. for slam()); it must outlive it.
  std::function<void(std::size_t, std::size_t, std::string_view)> callback();

 private:
  void end_stage();

  std::FILE* out_;
  bool terminal_;
  std::string stage_;
  std::size_t done_ = 0;
  std::size_t total_ = 0;
  int drawn_percent_ = -1;
  bool open_ = false;  ///< a stage is being reported
  std::chrono::steady_clock::time_point stage_start_;
};

}  // namespace rise::semantic
