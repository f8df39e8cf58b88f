#pragma once

// Reports of tasks and trainings — JSON for the training manager and tools,
// HTML for people (an inline SVG of the robot's trajectory over a top-down
// map of the world file, and an event timeline) — written atomically, and
// the training journal a training resumes from after a kill -9.

#include <optional>
#include <string>
#include <vector>

#include "sim/training/task_executor.hpp"
#include "sim/training/training_graph.hpp"
#include "sim/world_description.hpp"

namespace rise::sim::training {

/// The trajectory's stroke colour in the HTML plot (tests look for it).
inline constexpr const char* kTrajectoryColour = "#d62728";

std::string task_result_json(const TaskResult& result);
/// Throws std::runtime_error naming the key that is missing or bad.
TaskResult task_result_from_json(const std::string& json);

std::string task_report_html(const TaskResult& result, const WorldDescription& world);

/// A training's state for its report: the visits so far and how it ended.
struct TrainingReport {
  std::string training;
  std::string title;
  std::string file;
  std::string trainee_id;
  std::vector<TrainingVisit> visits;
  bool finished = false;
  std::string end_reason;
  int total_score = 0;
  /// Per visit, the task report's HTML file name (relative), for links.
  std::vector<std::string> task_report_files;
};
std::string training_report_json(const TrainingReport& report);
std::string training_report_html(const TrainingReport& report);

/// Writes `content` to `path` so that a reader sees the old or the new file,
/// never a part: a temporary beside it, fsync, rename, fsync of the folder.
/// Throws std::runtime_error "path: what failed: errno text".
void write_file_atomically(const std::string& path, const std::string& content);

/// One line of a training journal (JSON lines).
struct JournalEntry {
  std::string type;  ///< training_started, task_started, task_finished, training_finished
  std::string training;
  std::string trainee_id;
  std::string node;
  int attempt = 0;
  std::optional<TaskResult> result;  ///< task_finished
  std::string detail;
};

/// Append-only: each entry is one line written with a single write() and
/// fsync'd before append() returns, so a kill -9 loses at most the line
/// being written. Throws std::runtime_error on I/O errors.
void append_journal(const std::string& path, const JournalEntry& entry);
/// All entries; a torn last line (no newline at the end, or not JSON) is
/// dropped, a bad line before it throws "path:line: message". A missing
/// file gives no entries.
std::vector<JournalEntry> read_journal(const std::string& path);

}  // namespace rise::sim::training
