#pragma once

// rise-hild verify: replays captures against a golden PanelState log
// (hil/replay_verify.hpp) and says pass or the first difference.

#include <ostream>
#include <string>
#include <vector>

namespace rise::hil {

struct VerifyOptions {
  std::string panel;                  ///< panel definition file
  std::vector<std::string> captures;  ///< capture files (SOURCE=FILE or named after the source)
  std::string record_dir;             ///< or: every capture and panel_state.lcmlog of a --record DIR
  std::string golden;                 ///< golden LCM log (default DIR/panel_state.lcmlog)
  std::string id;                     ///< station id: channel rise/<id>/panel_state; empty: the log's one
  double axis_tolerance = 1e-3;
  double time_tolerance_ms = 2.0;
};

/// Exit code: 0 every golden message matched, 1 a difference (printed with
/// its time and control), 2 bad input (a file, a line of it, the panel).
int verify_command(const VerifyOptions& options, std::ostream& out, std::ostream& err);

}  // namespace rise::hil
