#pragma once

// A J1939 console's firmware, emulated (protocol j1939): claims its address
// with its NAME (J1939-81), answers requests for the claim and yields to a
// lower NAME, and sends every message of its J1939 DBC that a control of the
// source binds, at the message's GenMsgCycleTime (100 ms if none), encoded
// from the controls' scripted values; a message longer than 8 bytes goes out
// as a BAM (J1939-21 5.10.3.3: 50 ms between packets). The test double for
// hil/j1939_source.hpp next to can-utils' kernel J1939 tools.

#include <cstdint>
#include <string>
#include <vector>

#include "firmware_protocol/dbc.hpp"
#include "firmware_protocol/j1939.hpp"
#include "hil/io/can_bus.hpp"
#include "panels/panel_definition.hpp"
#include "panels/timeline.hpp"

namespace rise::panels {

struct J1939EmulatorSettings {
  /// Where the console claims; 254 = the source's console_address (0x21 if none).
  uint8_t address = firmware_protocol::j1939::kNullAddress;
  /// Its NAME; 0 = the source's console_name (0x00A0000000C0FFEE if none).
  uint64_t name = 0;
  int64_t bam_packet_gap_us = 50000;
};

class J1939Emulator {
 public:
  /// Throws std::runtime_error when `source` is not a j1939 source.
  J1939Emulator(const PanelDefinition& definition, std::size_t source, J1939EmulatorSettings settings = {});

  void apply(const TimelineEvent& event);
  /// Every input back at rest, @silent and @end undone.
  void restart();
  /// Claims at the first call, then sends what is due at now_us (monotonic);
  /// nothing while the address is not claimed or the console is silent.
  /// Returns the number of frames sent. No throw.
  int tick(hil::io::CanBus& bus, int64_t now_us);
  /// A frame from the bus (requests for the claim, contending claims).
  void on_frame(hil::io::CanBus& bus, const hil::io::CanFrame& frame, int64_t now_us);

  /// The claimed address, or 254.
  uint8_t address() const { return claimer_.address(); }
  bool ended() const { return ended_; }
  bool silent() const { return silent_; }
  int64_t frames_sent() const { return frames_sent_; }

 private:
  struct Message {
    const firmware_protocol::DbcMessage* dbc = nullptr;
    int64_t period_us = 100000;
    int64_t next_us = 0;
    std::vector<std::size_t> controls;  ///< indices into definition_.controls
  };
  void rest();
  bool send(hil::io::CanBus& bus, const firmware_protocol::j1939::Frame& frame);
  std::vector<uint8_t> encode(const Message& m) const;
  int send_message(hil::io::CanBus& bus, Message& m, int64_t now_us);

  const PanelDefinition& definition_;
  std::size_t source_;
  J1939EmulatorSettings settings_;
  firmware_protocol::j1939::AddressClaimer claimer_;
  firmware_protocol::j1939::BamSender bam_;
  int64_t bam_next_us_ = 0;
  std::vector<Message> messages_;
  std::vector<double> values_;  ///< physical value of each control's signal
  bool claimed_once_ = false;
  bool silent_ = false;
  bool ended_ = false;
  int64_t frames_sent_ = 0;
};

}  // namespace rise::panels
