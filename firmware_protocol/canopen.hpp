#pragma once

// CANopen (CiA 301 v4.2) as the bridge speaks it to a console node: the
// NMT, SYNC and heartbeat frames of the pre-defined connection set, and the
// PDO payload layout. Pure encode/decode: no I/O, no allocation, no throw.
//
// Worked examples (node 0x05, CiA 301 §7.2.8.3 and §7.3.2):
//   NMT Start Remote Node      000#0105   (command specifier 0x01, node id)
//   SYNC (no counter)          080#
//   boot-up                    705#00
//   heartbeat, operational     705#05
//   heartbeat, pre-operational 705#7F
//   TPDO1 (default COB-ID)     185#...    0x180 + node id

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

namespace rise::firmware_protocol::canopen {

/// Function codes of the pre-defined connection set (CiA 301 §7.3.5).
constexpr uint32_t kNmtCobId = 0x000;
constexpr uint32_t kSyncCobId = 0x080;
constexpr uint32_t kEmcyBase = 0x080;
constexpr uint32_t kHeartbeatBase = 0x700;
constexpr uint32_t kTpdoBase[4] = {0x180, 0x280, 0x380, 0x480};
constexpr uint32_t kRpdoBase[4] = {0x200, 0x300, 0x400, 0x500};

/// NMT state as a heartbeat's (or boot-up's) one byte reports it (§7.2.8.3.2.3).
enum class NmtState : uint8_t {
  BootUp = 0x00,
  Stopped = 0x04,
  Operational = 0x05,
  PreOperational = 0x7F,
};

/// NMT module control command specifiers (§7.2.8.3.1).
enum class NmtCommand : uint8_t {
  Start = 0x01,
  Stop = 0x02,
  EnterPreOperational = 0x80,
  ResetNode = 0x81,
  ResetCommunication = 0x82,
};

/// A classic CAN frame of the protocol (11-bit identifier; a PDO may have
/// a 29-bit one, bit 29 of its COB-ID entry).
struct Frame {
  uint32_t cob_id = 0;
  bool extended = false;
  uint8_t len = 0;
  std::array<uint8_t, 8> data{};
};

/// A node id a device can have: 1..127 (0 addresses every node in NMT).
constexpr bool is_node_id(int node) { return node >= 1 && node <= 127; }

/// NMT command to `node` (0 = all nodes): 000#CCNN.
Frame nmt_frame(NmtCommand command, uint8_t node);
/// SYNC without a counter (sync counter overflow 0): 080# with no data.
Frame sync_frame();
/// Heartbeat (or boot-up with NmtState::BootUp) of `node`: 7NN#SS.
Frame heartbeat_frame(uint8_t node, NmtState state);

/// What a received frame means to the master of `node`.
enum class HeartbeatRead : uint8_t {
  NotHeartbeat,  ///< another identifier
  Ok,            ///< `state` holds the node's state
  BadLength,     ///< a heartbeat is exactly one byte
  BadState,      ///< not one of the four states (bit 7, the node-guarding toggle, is 0 in a heartbeat)
};
struct HeartbeatResult {
  HeartbeatRead read = HeartbeatRead::NotHeartbeat;
  NmtState state = NmtState::BootUp;
};
/// Reads the heartbeat of `node` from a frame (id 0x700 + node).
HeartbeatResult read_heartbeat(uint8_t node, uint32_t cob_id, std::span<const uint8_t> data);

/// An NMT command as a node receives it; `ok` false when the frame is not a
/// well-formed NMT command (id 0, two bytes, a known specifier).
struct NmtRequest {
  bool ok = false;
  NmtCommand command = NmtCommand::Start;
  uint8_t node = 0;  ///< 0 = all nodes
  /// Whether the command addresses `self`.
  bool addresses(uint8_t self) const { return ok && (node == 0 || node == self); }
};
NmtRequest read_nmt(uint32_t cob_id, std::span<const uint8_t> data);

/// The state a node moves to on `command` from `state` (§7.3.2.2, Figure 48):
/// reset commands go through initialisation to BootUp (the node then sends
/// its boot-up and enters PreOperational).
NmtState next_state(NmtState state, NmtCommand command);

/// PDO transmission types (0x1800+n / 0x1400+n sub 2, §7.5.2.35): 0 acyclic
/// synchronous, 1..240 every n-th SYNC, 0xFC/0xFD on RTR, 0xFE/0xFF event-driven.
constexpr bool is_cyclic_sync(uint8_t transmission_type) {
  return transmission_type >= 1 && transmission_type <= 240;
}
constexpr bool is_synchronous(uint8_t transmission_type) { return transmission_type <= 240; }

std::string_view to_string(NmtState state);

/// Default COB-ID of TPDO n (1..4) or RPDO n of `node`; 0 for n outside 1..4.
uint32_t default_tpdo_cob_id(unsigned n, uint8_t node);
uint32_t default_rpdo_cob_id(unsigned n, uint8_t node);

/// The bridge as NMT master of one node and SYNC producer (CiA 301
/// §7.2.8.2.1, CiA 302-2's start-up reduced to one node): at open it resets
/// the node's communication, so the node boots up afresh whatever state it
/// was left in; it starts the node (NMT Start Remote Node) on each boot-up
/// and when the node's heartbeat returns, after a silence longer than the
/// consumer time, in a state other than Operational; it sends SYNC every
/// sync period. A node that leaves Operational on its own (or by another
/// master) is not started again until it boots up or returns. Times are
/// monotonic µs; no allocation, no throw.
class NmtMaster {
 public:
  /// `heartbeat_timeout_us`: the consumer time; `sync_period_us` 0: no SYNC.
  NmtMaster(uint8_t node, int64_t heartbeat_timeout_us, int64_t sync_period_us);

  /// The bus was (re)opened at now_us.
  void opened(int64_t now_us);
  /// A frame received on the bus (only the node's heartbeat matters).
  void on_frame(uint32_t cob_id, std::span<const uint8_t> data, int64_t now_us);
  /// The next frame to send at now_us: a pending NMT command first, then
  /// SYNC when due. Call until nullopt.
  std::optional<Frame> next(int64_t now_us);
  /// When next() has a SYNC again (INT64_MAX without SYNC); now when an NMT
  /// command waits.
  int64_t next_due_us() const;

  /// The node's state by its last heartbeat (BootUp before the first).
  NmtState state() const { return state_; }
  bool heard() const { return last_heartbeat_us_ != 0; }
  uint64_t starts_sent() const { return starts_sent_; }
  uint64_t syncs_sent() const { return syncs_sent_; }

 private:
  uint8_t node_;
  int64_t heartbeat_timeout_us_;
  int64_t sync_period_us_;
  std::optional<NmtCommand> pending_;
  NmtState state_ = NmtState::BootUp;
  int64_t last_heartbeat_us_ = 0;
  int64_t next_sync_us_ = 0;
  uint64_t starts_sent_ = 0;
  uint64_t syncs_sent_ = 0;
};

}  // namespace rise::firmware_protocol::canopen
