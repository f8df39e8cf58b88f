#pragma once

// What one transport event of a source does to the PanelMapper: a received
// CAN frame, the answer to a Modbus request, a polled input block. The live
// bridge (bridge.cpp) and the offline replay (replay_verify.cpp) both go
// through these, so a capture replays through the very decisions the daemon
// made. Callers hold whatever lock guards the mapper.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

#include "hil/io/can_frame.hpp"
#include "hil/io/modbus_link.hpp"
#include "hil/panel_mapper.hpp"

namespace rise::hil {

/// One frame received on a CAN source's bus: an error frame updates the bus
/// state, a remote frame (and an FD frame on a rise-can-v1 source, which is
/// classic 11-bit only) is ignored, any other goes to the decoder. True when
/// the panel changed (publish at once). No throw; allocates nothing.
bool apply_can_frame(PanelMapper& mapper, std::size_t source, const io::CanFrame& frame, int64_t now_us);

/// The outcome of one Modbus request of `source`: a timeout, exception or
/// RTU CRC error is counted; a link left closed (`link_open` false) by
/// anything but a timeout marks the source disconnected — after a timeout
/// the link was only closed for a clean restart, so the source's age judges
/// it. False when the link is closed (the poll cycle ends). No throw.
bool apply_modbus_result(PanelMapper& mapper, std::size_t source, const io::ModbusResult& result, bool link_open,
                         int64_t now_us);

/// A polled rise-modbus-v1 input block (input registers and discrete
/// inputs) of `source`: checked (CRC, ranges, alive counter against
/// `last_counter`, which it advances) and fed to the mapper, or counted as
/// the error it is. True when a bound control changed. No throw; allocates
/// nothing.
bool apply_modbus_inputs(PanelMapper& mapper, std::size_t source, std::span<const uint16_t> registers,
                         std::span<const uint8_t> bits, std::optional<uint16_t>& last_counter, int64_t now_us);

/// One poll of a Modbus source whose every read was answered (`poll` holds
/// modbus_poll_reads()' reads): a rise-modbus-v1 block goes through
/// apply_modbus_inputs(), a modbus device's points to the mapper. True when
/// a bound control changed. No throw; allocates nothing.
bool apply_modbus_poll(PanelMapper& mapper, std::size_t source, const ModbusPoll& poll,
                       std::optional<uint16_t>& last_counter, int64_t now_us);

}  // namespace rise::hil
