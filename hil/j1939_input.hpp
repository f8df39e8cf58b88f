#pragma once

// What a received CAN frame does on a j1939 source, shared by the live
// source (j1939_source.hpp) and the offline replay (replay_verify.cpp), so a
// recorded session replays through the very decisions the daemon made: the
// bridge's address claim (J1939-81), the transport protocol's reassembly
// (BAM, RTS/CTS to our address), the console's address learned from its
// claim by NAME, and whole messages from that address handed to the mapper
// (matched by PGN). Frames this node must send (claims, CTS, acks, aborts)
// are collected for the caller, which sends them (live) or not (replay).

#include <array>
#include <cstddef>
#include <cstdint>

#include "firmware_protocol/j1939.hpp"
#include "hil/io/can_frame.hpp"
#include "hil/panel_mapper.hpp"

namespace rise::hil {

/// Frames to send after one call, in order.
struct J1939Replies {
  // A claim and a request, or a TP reply and a claim reply, or every TP session's abort.
  std::array<firmware_protocol::j1939::Frame, firmware_protocol::j1939::TpReceiver::kSessions + 2> frames{};
  std::size_t count = 0;
  void push(const firmware_protocol::j1939::Frame& f) {
    if (count < frames.size()) frames[count++] = f;
  }
};

class J1939Input {
 public:
  /// `source` is a j1939 source (its NAME, addresses, console).
  explicit J1939Input(const panels::SourceDefinition& source);

  /// Starts (or restarts, after the bus came back) our claim; the claim and a
  /// request for everyone's claims go into `out` (the console answers with
  /// its own, so it is found at once). No throw, no allocation.
  void start(int64_t now_ms, J1939Replies& out);
  /// Runs the timers: our claim's 250 ms, the TP sessions' T1/T2. No throw.
  void tick(int64_t now_ms, J1939Replies& out);
  /// One received frame of `source`: an error frame goes to the mapper's bus
  /// state; a 29-bit classic data frame to the claim, the transport protocol
  /// and, as a whole message from the console's address, to the mapper.
  /// True when the panel changed. No throw, no allocation.
  bool on_frame(PanelMapper& mapper, std::size_t source, const io::CanFrame& frame, int64_t now_us, J1939Replies& out);

  /// Our address while claimed, else 254.
  uint8_t own_address() const { return claimer_.address(); }
  firmware_protocol::j1939::AddressClaimer::State claim_state() const { return claimer_.state(); }
  /// Where the console's messages are taken from now; 254 while unknown.
  uint8_t console_address() const;
  const firmware_protocol::j1939::TpCounters& transport_counters() const { return tp_.counters(); }
  /// Whole messages from addresses other than the console's (dropped).
  uint64_t foreign_messages() const { return foreign_; }

 private:
  bool deliver(PanelMapper& mapper, std::size_t source, const firmware_protocol::j1939::Id& id,
               std::span<const uint8_t> data, int64_t now_us);

  uint64_t console_name_ = 0;
  bool has_console_name_ = false;
  uint8_t fixed_console_address_;
  firmware_protocol::j1939::AddressClaimer claimer_;
  firmware_protocol::j1939::TpReceiver tp_;
  uint64_t foreign_ = 0;
};

/// The CAN frame of a J1939 frame (29-bit, classic).
io::CanFrame to_can_frame(const firmware_protocol::j1939::Frame& frame);

}  // namespace rise::hil
