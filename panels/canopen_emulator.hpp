#pragma once

// A console's firmware as a CANopen node (CiA 301), from its EDS: boots up
// (7NN#00) into Pre-operational, obeys NMT commands to its node id or to
// all, produces its heartbeat every 0x1017 ms, and in Operational sends its
// TPDOs as their transmission types say: every n-th SYNC (1..240), on the
// SYNC after a change (0), or on change no sooner than the inhibit time
// and at the event timer (0xFE/0xFF); entering Operational sends each TPDO
// once, so the master reads the start-up state. It decodes its RPDOs (LEDs,
// displays) as feedback. Doubles as the test double for hil/'s canopen
// source. Not done: SDO, EMCY, LSS, RTR-triggered PDOs (0xFC/0xFD are
// never sent).
//
// Timeline directives: @silent powers the node off (nothing sent or obeyed)
// and @resume on again (boot-up); @status init|fault puts it in
// Pre-operational on its own (as its error behaviour 0x1029 would),
// @status shutdown Stopped, @status operational Operational; @corrupt N
// sends the next N TPDOs one byte short of their mapping; @end ends it.

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "firmware_protocol/canopen.hpp"
#include "hil/io/can_bus.hpp"
#include "panels/panel_definition.hpp"
#include "panels/timeline.hpp"

namespace rise::panels {

class CanopenEmulator {
 public:
  /// Source `source` of `definition` must be protocol canopen.
  CanopenEmulator(const PanelDefinition& definition, std::size_t source);

  /// Applies a scripted event (a control moved, a directive).
  void apply(const TimelineEvent& event);
  /// A looped script starts again: inputs at their power-up rest, powered,
  /// not ended. The NMT state goes on.
  void restart();

  /// Sends what is due at now_us (monotonic): the boot-up once powered, the
  /// heartbeat, event-driven TPDOs. Returns the frames sent. No throw.
  int tick(hil::io::CanBus& bus, int64_t now_us);
  /// Takes a frame from the bus: NMT (state change; a reset boots again),
  /// SYNC (synchronous TPDOs go out at once), an RPDO (feedback). True when
  /// the feedback changed. No throw.
  bool on_frame(hil::io::CanBus& bus, const hil::io::CanFrame& frame, int64_t now_us);

  firmware_protocol::canopen::NmtState state() const { return state_; }
  bool powered() const { return powered_; }
  bool ended() const { return ended_; }
  int64_t frames_sent() const { return frames_sent_; }
  /// Heartbeats sent (the boot-up message too): how often the node has been heard, whatever its state.
  int64_t heartbeats_sent() const { return heartbeats_sent_; }
  int64_t syncs_seen() const { return syncs_seen_; }
  /// The value an LED or display of the source shows (LEDs 1/0, displays
  /// raw / 10^decimals); nullopt before its RPDO came.
  std::optional<double> feedback(const std::string& name) const;
  /// "leds power=on fault=off; display speed=0.42" (- before its RPDO came).
  std::string feedback_text() const;
  /// Raw value of a TPDO-mapped object as the firmware reads it (for tests).
  int64_t object_raw(uint16_t index, uint8_t subindex) const;

 private:
  struct TpdoState {
    std::vector<int64_t> raw;  // per signal of the message
    bool changed = true;
    int64_t last_sent_us = -1;
    uint32_t syncs = 0;
  };
  void power_up_inputs();
  void boot(int64_t now_us);
  void enter(firmware_protocol::canopen::NmtState state);
  bool send(hil::io::CanBus& bus, const firmware_protocol::canopen::Frame& frame);
  bool send_tpdo(hil::io::CanBus& bus, std::size_t pdo, int64_t now_us);
  void on_sync(hil::io::CanBus& bus, int64_t now_us);
  bool on_rpdo(const hil::io::CanFrame& frame);
  void set_control(const ControlDefinition& c, const TimelineEvent& e);

  const PanelDefinition& definition_;
  std::size_t source_;
  const SourceDefinition& def_;
  std::vector<TpdoState> tpdos_;
  std::map<std::string, double> feedback_;
  firmware_protocol::canopen::NmtState state_ = firmware_protocol::canopen::NmtState::BootUp;
  bool powered_ = true;
  bool boot_due_ = true;
  bool ended_ = false;
  int corrupt_left_ = 0;
  int64_t next_heartbeat_us_ = 0;
  int64_t frames_sent_ = 0;
  int64_t heartbeats_sent_ = 0;
  int64_t syncs_seen_ = 0;
};

}  // namespace rise::panels
