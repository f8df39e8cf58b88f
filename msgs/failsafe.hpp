#pragma once

// Why a panel is in failsafe, typed: PanelState.failsafe_causes carries a
// set of these flags (their values are PanelState's FAILSAFE_* constants),
// and failsafe_reason the text for people. Programs and tests decide on the
// causes; rewording a message changes nothing they do.

#include <cstdint>
#include <string>

#include "rise_msgs/PanelState.hpp"

namespace rise::msgs {

enum class FailsafeCause : int32_t {
  SourceDown = rise_msgs::PanelState::FAILSAFE_SOURCE_DOWN,
  SourceStale = rise_msgs::PanelState::FAILSAFE_SOURCE_STALE,
  ProtectionFailed = rise_msgs::PanelState::FAILSAFE_PROTECTION_FAILED,
  SourceError = rise_msgs::PanelState::FAILSAFE_SOURCE_ERROR,
  ControlInvalid = rise_msgs::PanelState::FAILSAFE_CONTROL_INVALID,
  InputFault = rise_msgs::PanelState::FAILSAFE_INPUT_FAULT,
  Estop = rise_msgs::PanelState::FAILSAFE_ESTOP,
};

/// Every cause, in the order to_string() lists them.
inline constexpr FailsafeCause kFailsafeCauses[] = {
    FailsafeCause::SourceDown,     FailsafeCause::SourceStale, FailsafeCause::ProtectionFailed,
    FailsafeCause::SourceError,    FailsafeCause::ControlInvalid, FailsafeCause::InputFault,
    FailsafeCause::Estop};

/// A set of causes: PanelState.failsafe_causes as a value.
struct FailsafeCauses {
  int32_t bits = 0;

  void add(FailsafeCause cause) { bits |= static_cast<int32_t>(cause); }
  bool has(FailsafeCause cause) const { return (bits & static_cast<int32_t>(cause)) != 0; }
  bool any() const { return bits != 0; }
  bool operator==(const FailsafeCauses&) const = default;
};

/// Whether a message's failsafe_causes (or a snapshot's) holds `cause`.
inline bool has(int32_t causes, FailsafeCause cause) { return FailsafeCauses{causes}.has(cause); }
inline bool has(FailsafeCauses causes, FailsafeCause cause) { return causes.has(cause); }

/// "source down", "source stale", "protection failed", "source error",
/// "control invalid", "input fault", "e-stop".
const char* to_string(FailsafeCause cause);
/// The causes joined with ", " ("" for none), in kFailsafeCauses' order.
std::string to_string(FailsafeCauses causes);

}  // namespace rise::msgs
