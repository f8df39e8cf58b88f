#pragma once

// The console's firmware, emulated: sends the rise-can-v1 frames of one
// source at the firmware's rates with alive counters and CRCs, and decodes
// the feedback frames the bridge sends back; or, for rise-modbus-v1, serves
// the same state in a Modbus register map. Doubles as the test double for
// hil/.

#include <array>
#include <cstdint>
#include <map>
#include <string>

#include "firmware_protocol/console_can.hpp"
#include "firmware_protocol/console_modbus.hpp"
#include "hil/io/can_bus.hpp"
#include "hil/io/modbus_server.hpp"
#include "panels/panel_definition.hpp"
#include "panels/timeline.hpp"

namespace rise::panels {

/// What the console shows, as last received from the bridge.
struct ConsoleFeedback {
  uint32_t leds_on = 0;
  firmware_protocol::BuzzerMode buzzer = firmware_protocol::BuzzerMode::Off;
  std::map<uint8_t, firmware_protocol::DisplayFrame> displays;  ///< by display index
  int64_t frames = 0;
  int64_t bad_frames = 0;
  bool operator==(const ConsoleFeedback& o) const;
};

class ConsoleEmulator {
 public:
  ConsoleEmulator(const PanelDefinition& definition, std::size_t source);

  /// Applies a scripted event (a control moved, a directive).
  void apply(const TimelineEvent& event);

  /// A looped script starts again: every input back where it rests at
  /// power-up and every directive's state undone (@silent, @corrupt,
  /// @invalid, @status, @end). The alive counter and the frame schedule go
  /// on, as a console that keeps running would. No allocation, no throw.
  void restart();

  /// Sends every frame that is due at now_us (monotonic). Returns the number
  /// of frames sent. Does not throw.
  int tick(hil::io::CanBus& bus, int64_t now_us);

  /// Takes a frame from the bus; returns true when the console's feedback
  /// (LEDs, displays, buzzer) changed.
  bool on_frame(const hil::io::CanFrame& frame);

  /// The firmware's state at now_us as one block (both protocols read it).
  firmware_protocol::ConsoleInputs inputs(int64_t now_us) const;

  /// Modbus firmware cycle: every 10 ms writes the input registers and
  /// discrete inputs with the alive counter +1; silent or ended → the
  /// registers freeze (still served, counter stopped). Returns true when a
  /// cycle ran. Does not throw.
  bool tick_modbus(hil::io::ModbusServer& server, int64_t now_us);
  /// Reads the coils and holding registers the host wrote; returns true when
  /// the console's feedback changed. Does not throw.
  bool poll_modbus_feedback(const hil::io::ModbusServer& server);
  /// Table sizes of the rise-modbus-v1 map.
  static hil::io::ModbusTableSizes modbus_table_sizes();

  const ConsoleFeedback& feedback() const { return feedback_; }
  /// "leds power=on fault=off estop=off; display speed=0.42; buzzer off"
  std::string feedback_text() const;
  bool silent() const { return silent_; }
  bool ended() const { return ended_; }
  int64_t frames_sent() const { return frames_sent_; }

  /// Raw values as the firmware reads them (for tests).
  int16_t axis_raw(std::size_t index) const { return axes_[index]; }

 private:
  bool send(hil::io::CanBus& bus, const firmware_protocol::Message& message);
  void power_up_inputs();

  const PanelDefinition& definition_;
  std::size_t source_;
  firmware_protocol::Encoder encoder_;
  firmware_protocol::Decoder feedback_decoder_;
  std::array<int16_t, firmware_protocol::kMaxAxes> axes_{};
  uint32_t buttons_ = 0;
  std::array<uint8_t, firmware_protocol::kMaxSwitches> switches_{};
  firmware_protocol::PanelStatus status_ = firmware_protocol::PanelStatus::Operational;
  bool silent_ = false;
  bool ended_ = false;
  int corrupt_left_ = 0;
  bool digital_changed_ = true;
  int64_t start_us_ = -1;
  int64_t next_axes_us_ = 0;
  int64_t next_digital_us_ = 0;
  int64_t next_heartbeat_us_ = 0;
  int64_t next_modbus_cycle_us_ = 0;
  uint16_t alive_counter_ = 0;
  int64_t frames_sent_ = 0;
  ConsoleFeedback feedback_;
};

}  // namespace rise::panels
