#pragma once

// The virtual panel (a browser page's sticks, buttons, keyboard and gamepad)
// as one more source of the daemon's PanelMapper: the page's control values
// enter as whole input blocks, and the daemon's own safety rules decide what
// is published (timeout → stale → failsafe, dead-man, e-stop, safe values).

#include <cstdint>
#include <map>
#include <optional>
#include <string>

#include "hil/panel_mapper.hpp"
#include "instructor/virtual_controls.hpp"
#include "panels/panel_definition.hpp"
#include "rise_msgs/FaultCommand.hpp"
#include "rise_msgs/PanelState.hpp"

namespace rise::instructor {

/// The name of the virtual source in PanelState.sources.
inline constexpr const char* kVirtualSourceName = "virtual";

/// One trainee's virtual panel. Not thread-safe (the server guards it).
/// Times are monotonic microseconds.
class VirtualPanel {
 public:
  /// `definition` must have exactly one source (a console definition such
  /// as panels/definitions/rise_console.yaml); it is renamed "virtual" and
  /// goes stale `timeout_ms` after the page's last update. Throws
  /// std::runtime_error naming the definition file otherwise.
  VirtualPanel(panels::PanelDefinition definition, uint32_t timeout_ms, std::string client);

  /// Takes the page's controls at now_us. Returns an error naming the first
  /// unknown control or switch position (nothing is taken then).
  std::optional<std::string> update(const VirtualControls& controls, int64_t now_us);
  /// The page said goodbye (or its connection ended): the source is
  /// disconnected, so the next PanelState is the safe state.
  void disconnect(int64_t now_us);

  /// Applies a FaultCommand that passed its signature check: an input fault
  /// (stuck_at, offset, drift, noise, out_of_range, intermittent, disconnect
  /// on a control; hil/input_fault.hpp) is injected into the mapper for its
  /// duration, as rise-hild does; a clear removes it ("" = every one).
  /// Returns "" or why it was not taken (another layer's kind: a virtual
  /// panel has no wire; an unknown control).
  std::string apply(const rise_msgs::FaultCommand& command, int64_t now_us);
  /// A rejected command is reported in active_faults ("rejected: <why>") for 10 s.
  void note_rejected(const std::string& why, int64_t now_us);

  /// The PanelState to publish at now_us (`utime` wall clock), after the
  /// safety rules; seq counts up by one per call.
  rise_msgs::PanelState state(const std::string& trainee_id, int64_t now_us, int64_t utime);

  const panels::PanelDefinition& definition() const { return mapper_.definition(); }
  int64_t last_update_us() const { return last_update_us_; }

 private:
  hil::PanelMapper mapper_;
  std::string url_;
  int64_t seq_ = 0;
  int64_t last_update_us_ = 0;
  uint16_t alive_ = 0;
  std::string rejected_note_;
  int64_t rejected_until_us_ = 0;
};

/// The definition a virtual panel uses: `definition` with its one source
/// renamed "virtual" and its timeout set. Throws for several sources.
panels::PanelDefinition virtual_definition(panels::PanelDefinition definition, uint32_t timeout_ms);

}  // namespace rise::instructor
