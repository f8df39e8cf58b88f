#pragma once

// The files the builder pages edit (training graphs today; robots, worlds,
// panels, scenarios later), in one folder the server is told (`rise-instructor
// serve --designs DIR`). A page loads a file with its version (a hash of its
// bytes) and saves with the version it loaded: when the file changed on disk
// since (another page, an editor, a git pull), nothing is written and the
// page is told (HTTP 409), so no one's edit is silently overwritten. Saving
// is atomic: a reader (rise-trainer, rise-sim) sees the old file or the new
// one, never a part (sim/training/report.hpp write_file_atomically).

#include <mutex>
#include <string>
#include <vector>

namespace rise::instructor {

/// A file's version: FNV-1a 64 of its bytes as 16 hex digits. It detects a
/// change; it is no signature (the token guards who may save).
std::string content_version(const std::string& bytes);

/// A name a builder may read or write: letters, digits, _ . - (not first
/// '.'), at most 128, ending in `extension` (".yaml"). No folders.
bool valid_design_name(const std::string& name, const std::string& extension);

struct DesignText {
  std::string text;
  std::string version;
};

/// An error of a file a builder would save, as the page shows it beside
/// what the user changed.
struct BuilderError {
  std::string file;     ///< the file the error is in: the training, or a task file it names (file name only)
  int line = 0;         ///< in that file (the training: in `yaml`)
  std::string key;      ///< "transitions[3].if", or the entry the line holds ("nodes[1]"), or ""
  std::string message;  ///< without file, line and key
};

enum class SaveStatus { Saved, Conflict };

struct SaveOutcome {
  SaveStatus status = SaveStatus::Saved;
  std::string version;  ///< Saved: the new file's; Conflict: the one on disk now ("" when it is gone)
};

class DesignFolder {
 public:
  /// `dir` "": no folder (every call throws).
  explicit DesignFolder(std::string dir) : dir_(std::move(dir)) {}

  const std::string& dir() const { return dir_; }
  /// The folder's files whose name is valid with `extension`, sorted.
  std::vector<std::string> list(const std::string& extension) const;
  /// The full path of `name` (checked with valid_design_name by the caller).
  std::string path(const std::string& name) const;
  /// Throws std::runtime_error "path: cannot open: reason".
  DesignText read(const std::string& name) const;
  /// Writes `text` as `name` when the file on disk is still at
  /// `expected_version` ("": it must not exist yet); else writes nothing and
  /// returns Conflict. A link is written through (it stays a link) and the
  /// file keeps its permissions. Saves through this folder are one at a time; a
  /// process writing between the check and the rename is not seen (no lock
  /// binds every editor). Throws std::runtime_error when the write fails.
  SaveOutcome save(const std::string& name, const std::string& text, const std::string& expected_version);

 private:
  std::string dir_;
  std::mutex save_mutex_;
};

}  // namespace rise::instructor
