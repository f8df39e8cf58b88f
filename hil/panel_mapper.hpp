#pragma once

// Decode → map → safety: turns the frames of a panel's sources into named
// control values, and decides when the panel cannot be trusted.

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "firmware_protocol/canopen.hpp"
#include "firmware_protocol/console_can.hpp"
#include "firmware_protocol/hid_report.hpp"
#include "hil/control_transforms.hpp"
#include "hil/input_fault.hpp"
#include "msgs/failsafe.hpp"
#include "hil/io/can_error.hpp"
#include "firmware_protocol/console_modbus.hpp"
#include "hil/modbus_poll.hpp"
#include "panels/panel_definition.hpp"

namespace rise::hil {

/// Counters and state of one source, as PanelState reports them.
struct SourceStatus {
  std::string name;
  bool connected = false;
  bool stale = true;
  bool check_failed = false;        ///< a protection check failed; not yet recovered
  int64_t last_frame_age_us = -1;   ///< -1: no valid frame yet
  int64_t frames_ok = 0;
  std::array<int64_t, firmware_protocol::kDecodeErrorCount> errors{};  ///< by DecodeError
  int32_t reconnects = 0;
  int64_t timeouts = 0;             ///< polled transports: requests without an answer
  int64_t exceptions = 0;           ///< polled transports: Modbus exception answers
  firmware_protocol::PanelStatus console_status = firmware_protocol::PanelStatus::Init;
  bool heartbeat_seen = false;
  int64_t error_frames = 0;         ///< CAN error frames seen on the source's bus
  io::CanBusState bus_state = io::CanBusState::Active;  ///< last state the controller reported
  int32_t bus_offs = 0;             ///< times the controller went bus-off
  bool ever_connected = false;      ///< the transport was open at least once
  std::string down_reason;          ///< why it is down ("" while connected); see on_connection

  int64_t frames_bad() const;
};

/// The value of one control after transforms and safety rules.
struct ControlValue {
  float axis = 0.0f;
  bool pressed = false;
  uint8_t position = 0;
  bool forced_safe = false;  ///< at its safe value because of a safety rule
};

struct PanelSnapshot {
  int64_t time_us = 0;              ///< the monotonic time it was evaluated at
  bool failsafe = true;
  msgs::FailsafeCauses failsafe_causes;  ///< why, typed: decide on these, never on the text
  std::string failsafe_reason;      ///< "; "-joined reasons, empty when not failsafe
  bool deadman = false;
  std::vector<ControlValue> controls;  ///< same order as PanelDefinition::controls
  std::vector<SourceStatus> sources;   ///< same order as PanelDefinition::sources
  std::vector<std::string> active_faults;  ///< input faults in effect: "<id>: <kind> <control>"
};

/// Holds the latest decoded state of every source. Not thread-safe: the
/// bridge guards it with a mutex. Times are microseconds of a monotonic clock.
class PanelMapper {
 public:
  explicit PanelMapper(panels::PanelDefinition definition);

  /// Feeds one received CAN frame of `source`. Malformed frames are counted
  /// and dropped. Returns true when a bound control's raw value changed (the
  /// bridge then publishes at once). No throw; allocates nothing.
  /// For a `dbc` source every bound MESSAGE.SIGNAL is read from the frames
  /// with its message's id (`extended` for 29-bit ids). For a `canopen`
  /// source the node's heartbeat gives its NMT state, and its TPDOs, taken
  /// only while it is Operational, the bound objects. For a `j1939` source
  /// the frame is a whole J1939 message (up to 1785 bytes, from the
  /// transport protocol) from the console's address, matched by its PGN.
  bool on_frame(std::size_t source, uint32_t can_id, std::span<const uint8_t> data,
                int64_t now_us, bool extended = false);

  /// Feeds one whole input block of `source` that passed its protection
  /// check (protocol-neutral; rise-modbus-v1 polls yield these). Refreshes
  /// every signal's age. Returns true when a bound control's raw value
  /// changed. No throw; allocates nothing.
  bool on_inputs(std::size_t source, const firmware_protocol::ConsoleInputs& inputs, int64_t now_us);

  /// Feeds one answered poll of a `modbus` source (every read of its plan
  /// answered): each bound point's value, which refreshes the source's age.
  /// Returns true when a bound value changed. No throw; allocates nothing.
  bool on_modbus_poll(std::size_t source, const ModbusPoll& poll, int64_t now_us);

  /// A `hid` source's device was (re)opened with this report descriptor:
  /// binds every control's signal name to it. False, with `error` set and
  /// the source failsafe until the next attach, when the descriptor does not
  /// parse or lacks a bound name. Allocates: call at open, not per report.
  bool attach_hid(std::size_t source, std::span<const uint8_t> descriptor, std::string* error = nullptr);

  /// Feeds one input report of a `hid` source (with its id byte when the
  /// descriptor uses ids). Axes take the decoder's normalised value, buttons
  /// value ≠ 0, switches the signal's raw value (a hat's direction index).
  /// Returns true when a bound value changed. No throw; allocates nothing.
  bool on_hid_report(std::size_t source, std::span<const uint8_t> report, int64_t now_us);

  /// A `hid` source's evdev device (hil/io/evdev_signals.hpp) was (re)opened
  /// with these signal names: binds every control's signal name to one of
  /// them. False, with `error` set and the source failsafe until the next
  /// attach, when a bound name is missing (`missing_note`, when given, is
  /// added to the message: why, e.g. no SDL mapping for the device).
  /// Allocates: call at open, not per frame.
  bool attach_named(std::size_t source, std::span<const std::string> names, std::string* error = nullptr,
                    const std::string& missing_note = {});

  /// Feeds the values of an attached evdev source's signals, indexed like
  /// the names given to attach_named(): axes take the value, buttons value
  /// ≠ 0, switches the value as a position. Refreshes the source's age.
  /// Returns true when a bound value changed. No throw; allocates nothing.
  bool on_named_values(std::size_t source, std::span<const double> values, int64_t now_us);
  /// An attached evdev source's device is open and has nothing new: an
  /// evdev device sends events only on change and the kernel removes it
  /// when it goes, so it is fresh. Counts no frame. No throw.
  void on_named_alive(std::size_t source, int64_t now_us);

  /// Feeds one CAN error frame of `source`'s bus (linux/can/error.h): counts
  /// it and takes the controller state it reports. Bus-off makes the source
  /// unsafe until the controller reports its restart or error-active (the
  /// kernel sends both: can_restart(), can_change_state()) or the interface
  /// is opened afresh; frames still read meanwhile do not clear it. Returns
  /// true when the state changed. No throw; allocates nothing.
  bool on_bus_error(std::size_t source, const io::CanErrorReport& report, int64_t now_us);

  /// What went wrong with one poll of a polled source.
  enum class SourceError {
    BadCrc,        ///< block failed its end-to-end CRC → failed check
    BadValue,      ///< field out of range → failed check
    StaleCounter,  ///< alive counter did not move: no new data (ages keep growing)
    Timeout,       ///< no answer
    Exception,     ///< the slave answered with an exception
    LinkCrc,       ///< the transport's own CRC failed (RTU)
  };
  /// Counts a poll's failure; BadCrc and BadValue fail the protection check
  /// until recovery_frames good blocks in a row. No throw.
  void on_source_error(std::size_t source, SourceError kind, int64_t now_us);

  /// Transport state of a source. A disconnect makes it stale at once and
  /// forgets its alive counters (the console restarts its counters too).
  /// `down_reason` says why a source is down (the transport's last error:
  /// the OS's error, the host that did not resolve, the permission that is
  /// missing); it is kept in SourceStatus::down_reason until it connects.
  /// Allocates only when the reason changes; no throw.
  void on_connection(std::size_t source, bool connected, int64_t now_us, std::string_view down_reason = {});

  /// Applies the safety rules at `now_us`: a source that is disconnected,
  /// stale (a bound frame type older than timeout_ms), failing its protection
  /// check, or whose console reports a fault puts its controls at their safe
  /// values and the panel in failsafe; the e-stop pressed → failsafe; the
  /// dead-man released → motion controls at their safe values. Then the
  /// per-control transforms (shaping, low-pass, button modes, switches from
  /// bits) run; a control that was forced safe restarts its filters, so a
  /// toggle or a filtered axis never carries state across a source loss.
  /// const, yet it advances those transforms' state (the `mutable`
  /// filters_): call it with non-decreasing times, from one thread at a time
  /// (the bridge holds its mutex); preview() leaves the state as it was.
  PanelSnapshot evaluate(int64_t now_us) const;
  /// What evaluate(now_us) would return, leaving the transforms' state as
  /// it was (an offline replay tries several candidate times this way).
  /// Allocates: not for the cyclic path.
  PanelSnapshot preview(int64_t now_us) const;

  const panels::PanelDefinition& definition() const { return definition_; }

  /// Adds an input fault (hil/input_fault.hpp), applied between decode and
  /// the transforms from its start_us to its end_us. A fault with the same
  /// id replaces it. Returns an empty string, or why it was refused (a kind
  /// the control cannot take, a control index out of range). Allocates: not
  /// for the cyclic path.
  std::string inject_input_fault(InputFault fault);
  /// Removes the input fault `id` ("" = every one) and those that ended
  /// before now_us; returns how many of the named were removed.
  std::size_t clear_input_faults(const std::string& id, int64_t now_us);
  const std::vector<InputFault>& input_faults() const { return input_faults_; }

 private:
  // One control's signal of a dbc, hid or modbus source: the DBC signal it decodes, the HID
  // report signal it reads, or the Modbus point it polls, and the value last taken.
  struct SignalBinding {
    const firmware_protocol::DbcMessage* message = nullptr;
    const firmware_protocol::DbcSignal* signal = nullptr;
    const firmware_protocol::DbcSignal* multiplexer = nullptr;  // set for multiplexed signals
    double value = 0.0;
    int64_t last_us = 0;  // 0 = never
    std::size_t hid_signal = 0;  // hid sources: index into the decoder's signals
    bool hid_raw = false;        // hid switches take the raw value
    std::optional<panels::ModbusPoint> modbus;  // modbus sources: the point read
    panels::ModbusValueType modbus_type = panels::ModbusValueType::UInt16;
  };
  struct SourceState {
    explicit SourceState(firmware_protocol::Decoder d) : decoder(d) {}
    std::vector<SignalBinding> bindings;  // dbc, hid and modbus sources
    std::unique_ptr<firmware_protocol::HidReportDecoder> hid;  // hid sources, once attached
    std::size_t named = 0;  // evdev hid sources, once attached: how many values each frame has
    std::vector<firmware_protocol::HidSignalValue> hid_values;
    std::string hid_error;  // why the last attach failed
    int64_t hid_last_us = 0;  // last decoded report since connecting, 0 = none
    int64_t poll_last_us = 0;  // modbus sources: last answered poll since connecting, 0 = none
    firmware_protocol::Decoder decoder;
    SourceStatus status;
    std::array<int64_t, firmware_protocol::kFrameTypeCount> last_valid_us{};  // 0 = never
    bool needs_type[firmware_protocol::kFrameTypeCount] = {};
    int64_t last_any_valid_us = 0;
    uint32_t ok_in_row = 0;
    uint8_t protocol_version = 0;
    std::array<int16_t, firmware_protocol::kMaxAxes> axes{};
    uint32_t buttons = 0;
    std::array<uint8_t, firmware_protocol::kMaxSwitches> switches{};
    bool axes_seen[firmware_protocol::kAxisFrames] = {};
    bool buttons_seen = false;
    bool switches_seen = false;
    // canopen sources: the node's NMT state from its last heartbeat.
    firmware_protocol::canopen::NmtState nmt_state = firmware_protocol::canopen::NmtState::BootUp;
    int64_t heartbeat_us = 0;  // 0 = none since connecting
  };

  void count_valid(SourceState& s);
  // A bound signal's value at now_us; true when it changed (or came first since a loss).
  static bool take(SignalBinding& b, double value, int64_t now_us);
  // Why a source's controls cannot be trusted now; nullopt while they can.
  struct SourceTrouble {
    msgs::FailsafeCause cause;
    std::string reason;  // "<source>: <what>"
  };
  std::optional<SourceTrouble> source_trouble(const SourceState& s, int64_t now_us) const;

  // evaluate()'s steps. They advance the mutable filters_ (see below).
  struct Failsafe;
  std::vector<bool> evaluate_sources(int64_t now_us, PanelSnapshot& snap, Failsafe& why) const;
  void map_axis(std::size_t i, const SourceState& s, int64_t now_us, ControlValue& v, Failsafe& why) const;
  void map_button(std::size_t i, const SourceState& s, int64_t now_us, ControlValue& v, Failsafe& why) const;
  void map_switch(std::size_t i, const SourceState& s, int64_t now_us, ControlValue& v, Failsafe& why) const;
  void map_bits_switch(std::size_t i, const SourceState& s, int64_t now_us, ControlValue& v, Failsafe& why) const;

  panels::PanelDefinition definition_;
  std::vector<SourceState> sources_;

  // Per-control transform state (low-pass, button filters, last valid switch
  // position). evaluate() advances it: it is called with non-decreasing times
  // under the bridge's mutex.
  struct ControlFilter {
    LowPass lowpass;
    ButtonFilter button;
    bool was_safe = true;  // forced safe at the last evaluation: restart filters
    std::optional<uint8_t> last_position;
  };
  mutable std::vector<ControlFilter> filters_;
  std::vector<int> binding_of_control_;  // index into the source's bindings, -1 if none
  std::vector<InputFault> input_faults_;  // injection order

  bool on_dbc_frame(SourceState& s, uint32_t can_id, bool extended, std::span<const uint8_t> data, int64_t now_us,
                    bool j1939);
  bool on_canopen_frame(SourceState& s, const panels::SourceDefinition& def, uint32_t can_id, bool extended,
                        std::span<const uint8_t> data, int64_t now_us);
  std::optional<SourceTrouble> canopen_trouble(const SourceState& s, const panels::SourceDefinition& def,
                                               int64_t now_us) const;
};

/// Age after which a missing heartbeat makes a source stale: three heartbeat
/// periods, or the source timeout if that is longer.
int64_t heartbeat_timeout_us(const panels::SourceDefinition& source);

}  // namespace rise::hil
