#pragma once

// What a SocketCAN error frame says (linux/can/error.h): the error classes in
// its id, the controller's new state, the error counters.
//
// Worked example: candump's `20000004#0010000000000000` is class CAN_ERR_CRTL
// (0x004) with data[1] = CAN_ERR_CRTL_RX_PASSIVE (0x10): the controller went
// error-passive; `20000040#…` is CAN_ERR_BUSOFF; `20000100#…` is
// CAN_ERR_RESTARTED (the controller left bus-off, back to error-active).

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "hil/io/can_frame.hpp"

namespace rise::hil::io {

/// The fault confinement states of ISO 11898-1 (§12.1.4), as SocketCAN
/// reports them (enum can_state of linux/can/netlink.h; warning is its
/// CAN_STATE_ERROR_WARNING, counters ≥ 96).
enum class CanBusState : uint8_t { Active, Warning, Passive, BusOff };

std::string_view to_string(CanBusState state);

struct CanErrorReport {
  uint32_t classes = 0;                  ///< CAN_ERR_* class bits of the id
  std::optional<CanBusState> state;      ///< set when the frame reports a state change
  std::optional<uint8_t> tx_errors;      ///< transmit error counter (CAN_ERR_CNT)
  std::optional<uint8_t> rx_errors;      ///< receive error counter (CAN_ERR_CNT)
};

/// Reads an error frame (frame.error set; id = class bits, data per
/// linux/can/error.h). A frame that is not an error frame gives classes 0.
/// No allocation, no throw.
CanErrorReport describe_can_error(const CanFrame& frame);

/// candump -e style text: "bus-off", "controller-problem{rx-error-passive}",
/// "restarted-after-bus-off", joined by ", ". Allocates.
std::string can_error_text(const CanFrame& frame);

}  // namespace rise::hil::io
