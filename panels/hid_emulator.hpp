#pragma once

// A HID device's firmware, emulated: the input reports of a described device
// (its report descriptor) carrying the values a timeline gives the panel's
// controls, and the output reports (LEDs, rumble) the host writes back,
// decoded. Runs over hil::io::UhidDevice (rise-panel emulate --hid), so the host
// sees a real HID device; doubles as the test double of the daemon's hid
// sources.
//
// A control of the emulated `hid` source binds a signal name of the
// descriptor (firmware_protocol::hid_signals); the timeline sets the control
// and the emulator writes that signal's raw value: axes through
// hid_raw_from_value (-1..1, or 0..1 for one-sided ones), buttons as the
// logical maximum / minimum, switches their position index as the raw value
// (as the bridge reads them back). Signals no control binds rest: axes at
// their centre, hats released (null), buttons up.

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "firmware_protocol/hid_report.hpp"
#include "hil/io/uhid_device.hpp"
#include "panels/panel_definition.hpp"
#include "panels/timeline.hpp"

namespace rise::panels {

struct HidEmulatorSettings {
  /// Every input report is sent again at this period (a USB device answers
  /// each 125 Hz interrupt poll); 0: only on change.
  int64_t report_period_us = 8000;
};

class HidEmulator {
 public:
  /// Emulates `source` (a `hid` source) of `definition` as the device
  /// `descriptor` describes. Throws std::runtime_error naming the definition
  /// and the control when a control binds a name the descriptor's input
  /// reports lack, or when the source is not a hid source. Allocates.
  HidEmulator(const PanelDefinition& definition, std::size_t source, firmware_protocol::HidDescriptor descriptor,
              HidEmulatorSettings settings = {});

  /// Applies a scripted event: a control set (controls of other sources are
  /// ignored), @silent / @resume (reports stop / restart), @end, @corrupt N
  /// (the next N reports go out one byte short), @invalid CONTROL (its signal
  /// reads outside its logical range: the null state). @status has no HID
  /// meaning and is ignored. No allocation, no throw.
  void apply(const TimelineEvent& event);

  /// A looped script starts again: every input signal back where it rests
  /// at power-up and every directive's state undone (@silent, @corrupt,
  /// @invalid, @end). Changed reports go out at the next tick. No
  /// allocation, no throw.
  void restart();

  /// Where reports go; false when one could not be sent.
  using ReportSink = std::function<bool(std::span<const uint8_t>)>;
  /// Sends every input report whose content changed since it was last sent,
  /// and every report when the period is due (the first call starts the
  /// period). Returns the number of reports sent. No allocation, no throw.
  int tick(int64_t now_us, const ReportSink& send);
  /// tick() through a device (hil::io::UhidDevice::send_input).
  int tick(hil::io::UhidDevice& device, int64_t now_us);

  /// Takes an output report as the host wrote it: id byte first, or (no
  /// report ids) hidraw's leading 0 byte, with or without it. True when an
  /// output signal changed. A report of no known output report is counted
  /// in bad_outputs(). No allocation, no throw.
  bool on_output(std::span<const uint8_t> report);

  /// Input report `report_id` as it goes out now (id byte first when ids
  /// are used); empty when there is no such report.
  std::span<const uint8_t> report(uint8_t report_id) const;
  /// The decoded output signals, indexed like output_signals().
  const std::vector<firmware_protocol::HidSignalValue>& outputs() const { return outputs_; }
  const std::vector<firmware_protocol::HidSignal>& output_signals() const { return output_.signals(); }
  /// The definition's LEDs of this source, then the raw value of every
  /// output signal no LED binds: "leds power=on fault=off; outputs
  /// usage_0008_0003=0 usage_0008_0004=1" ("-" for an LED the device lacks,
  /// "outputs none" when it has no output report).
  std::string feedback_text() const;

  int64_t reports_sent() const { return reports_sent_; }
  int64_t outputs_received() const { return outputs_received_; }
  int64_t bad_outputs() const { return bad_outputs_; }
  bool silent() const { return silent_; }
  bool ended() const { return ended_; }

 private:
  struct Report {
    uint8_t id = 0;
    std::vector<uint8_t> bytes;
    bool dirty = true;
  };
  void set_raw(std::size_t signal, int64_t raw);
  void power_up_inputs(std::vector<int64_t>& raw) const;
  void encode(Report& report);

  const PanelDefinition& definition_;
  std::size_t source_;
  HidEmulatorSettings settings_;
  firmware_protocol::HidInputEncoder input_;
  firmware_protocol::HidReportDecoder output_;
  std::vector<std::size_t> signal_of_control_;  // index into input_.signals(), or npos
  std::vector<int64_t> raw_;                     // indexed like input_.signals()
  std::vector<int64_t> restart_scratch_;         // restart()'s power-up values, allocated once
  std::vector<Report> reports_;
  std::array<int16_t, 256> report_index_{};  // report id → index into reports_, -1 if none
  std::vector<firmware_protocol::HidSignalValue> outputs_;
  std::vector<firmware_protocol::HidSignalValue> decoded_;  // scratch for on_output
  bool silent_ = false;
  bool ended_ = false;
  int corrupt_left_ = 0;
  int64_t next_period_us_ = -1;
  int64_t reports_sent_ = 0;
  int64_t outputs_received_ = 0;
  int64_t bad_outputs_ = 0;
};

}  // namespace rise::panels
