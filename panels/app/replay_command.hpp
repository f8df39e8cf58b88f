#pragma once

// rise-panel replay: plays a CAN capture onto a live transport, as
// can-utils' canplayer does, through the replay:// transport (timing
// anchored to the wall clock, no drift; speed, loops, window, id and channel
// filters, step mode) with a progress line on long files.

#include <string>

namespace CLI {
class App;
}

namespace rise::panels {

struct ReplayOptions {
  std::string file;
  std::string to;
  double speed = 1.0;
  int loop = 0;
  double start_s = 0.0;
  double stop_s = -1.0;
  std::string ids;      ///< "123,1F334455"
  std::string channel;
  bool fast = false;
  bool step = false;
  bool wait_peer = false;
  double progress_every_s = 1.0;
};

/// Adds the `replay` subcommand's options to `app` (a subcommand).
void add_replay_options(CLI::App& app, ReplayOptions& options);

/// Runs it; the exit code (0 done, 2 bad input or an unusable transport).
int run_replay(const ReplayOptions& options, const volatile int& stop);

}  // namespace rise::panels
