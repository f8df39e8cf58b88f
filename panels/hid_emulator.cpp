#include "panels/hid_emulator.hpp"

#include <algorithm>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace rise::panels {
namespace {
namespace fp = rise::firmware_protocol;

constexpr std::size_t npos = static_cast<std::size_t>(-1);

// The value a signal nobody moves rests at.
int64_t resting_raw(const fp::HidSignal& s) {
  if (s.kind == fp::HidSignalKind::Hat) return fp::hid_raw_from_value(s, -1.0);  // released: null
  if (s.kind == fp::HidSignalKind::Array) return s.logical_min;
  return fp::hid_raw_from_value(s, 0.0);
}

// A raw value just outside the logical range that the field's bits still
// hold (6.2.2.5 null state), or nullopt when the range fills the field.
std::optional<int64_t> null_raw(const fp::HidSignal& s) {
  if (s.bit_size == 0 || s.bit_size > 32) return std::nullopt;
  const bool is_signed = s.logical_min < 0;
  const int64_t lowest = is_signed ? -(int64_t{1} << (s.bit_size - 1)) : 0;
  const int64_t highest = is_signed ? (int64_t{1} << (s.bit_size - 1)) - 1 : (int64_t{1} << s.bit_size) - 1;
  if (s.logical_max < highest) return s.logical_max + 1;
  if (s.logical_min > lowest) return s.logical_min - 1;
  return std::nullopt;
}

}  // namespace

HidEmulator::HidEmulator(const PanelDefinition& definition, std::size_t source, fp::HidDescriptor descriptor,
                         HidEmulatorSettings settings)
    : definition_(definition),
      source_(source),
      settings_(settings),
      input_(descriptor),
      output_(std::move(descriptor), fp::HidReportKind::Output) {
  const SourceDefinition& def = definition_.sources.at(source_);
  if (!def.is_hid())
    throw std::runtime_error(definition_.file + ": source '" + def.name + "' is protocol " + def.protocol +
                             ", not hid");
  for (const ControlDefinition& c : definition_.controls) {
    if (c.source != source_) {
      signal_of_control_.push_back(npos);
      continue;
    }
    const std::size_t index = input_.find(c.hid_signal);
    if (index >= input_.signals().size())
      throw std::runtime_error(definition_.file + ":" + std::to_string(c.line) + ": controls." + c.name +
                               ".signal: the descriptor has no input signal '" + c.hid_signal +
                               "' (it has: " + fp::hid_signal_names(input_.signals()) + ")");
    signal_of_control_.push_back(index);
  }
  raw_.resize(input_.signals().size());
  restart_scratch_.resize(raw_.size());
  power_up_inputs(raw_);
  report_index_.fill(-1);
  for (const uint8_t id : input_.report_ids()) {
    report_index_[id] = static_cast<int16_t>(reports_.size());
    Report r;
    r.id = id;
    r.bytes.resize(input_.report_length(id));
    reports_.push_back(std::move(r));
  }
  for (Report& r : reports_) encode(r);
  outputs_.resize(output_.signals().size());
  decoded_.resize(output_.signals().size());
}

void HidEmulator::power_up_inputs(std::vector<int64_t>& raw) const {
  for (std::size_t i = 0; i < raw.size(); ++i) raw[i] = resting_raw(input_.signals()[i]);
  for (std::size_t control = 0; control < signal_of_control_.size(); ++control) {
    const std::size_t index = signal_of_control_[control];
    if (index == npos) continue;
    const ControlDefinition& c = definition_.controls[control];
    // At power-up a switch rests where it is; the script starts it safe.
    if (c.kind == ControlKind::Switch) raw[index] = c.safe_switch;
    if (c.kind == ControlKind::Button) raw[index] = fp::hid_raw_from_value(input_.signals()[index], 0.0);
  }
}

void HidEmulator::restart() {
  std::vector<int64_t>& rest = restart_scratch_;
  power_up_inputs(rest);
  for (std::size_t i = 0; i < rest.size(); ++i) set_raw(i, rest[i]);
  silent_ = false;
  ended_ = false;
  corrupt_left_ = 0;
}

void HidEmulator::encode(Report& report) { input_.encode_report(report.id, raw_, report.bytes); }

void HidEmulator::set_raw(std::size_t signal, int64_t raw) {
  if (raw_[signal] == raw) return;
  raw_[signal] = raw;
  const int16_t r = report_index_[input_.signals()[signal].report_id];
  if (r < 0) return;
  Report& report = reports_[static_cast<std::size_t>(r)];
  encode(report);
  report.dirty = true;
}

void HidEmulator::apply(const TimelineEvent& e) {
  using K = TimelineEvent::Kind;
  const std::size_t signal = e.control < signal_of_control_.size() ? signal_of_control_[e.control] : npos;
  switch (e.kind) {
    case K::Set: {
      if (signal == npos) return;
      const fp::HidSignal& s = input_.signals()[signal];
      switch (definition_.controls[e.control].kind) {
        case ControlKind::Axis: set_raw(signal, fp::hid_raw_from_value(s, e.axis)); break;
        case ControlKind::Button: set_raw(signal, fp::hid_raw_from_value(s, e.pressed ? 1.0 : 0.0)); break;
        case ControlKind::Switch: set_raw(signal, e.position); break;
      }
      break;
    }
    case K::Invalid:
      if (signal == npos) return;
      if (const auto raw = null_raw(input_.signals()[signal])) set_raw(signal, *raw);
      break;
    case K::Silent: silent_ = true; break;
    case K::Resume: silent_ = false; break;
    case K::Corrupt: corrupt_left_ += e.count; break;
    case K::End: ended_ = true; break;
    case K::Status: break;
  }
}

int HidEmulator::tick(int64_t now_us, const ReportSink& send) {
  bool periodic = false;
  if (next_period_us_ < 0) {
    next_period_us_ = now_us;
  }
  if (settings_.report_period_us > 0 && now_us >= next_period_us_) {
    periodic = true;
    next_period_us_ += settings_.report_period_us;
    if (next_period_us_ <= now_us) next_period_us_ = now_us + settings_.report_period_us;  // late: no burst
  }
  if (silent_ || ended_) return 0;
  int sent = 0;
  for (Report& r : reports_) {
    if (!periodic && !r.dirty) continue;
    std::span<const uint8_t> bytes = r.bytes;
    if (corrupt_left_ > 0) {
      bytes = bytes.first(bytes.size() - 1);  // one byte short: the host's decoder refuses it
      --corrupt_left_;
    }
    if (!bytes.empty() && send(bytes)) {
      r.dirty = false;
      ++sent;
    }
  }
  reports_sent_ += sent;
  return sent;
}

int HidEmulator::tick(hil::io::UhidDevice& device, int64_t now_us) {
  return tick(now_us, [&device](std::span<const uint8_t> r) { return device.send_input(r) == hil::io::IoStatus::Ok; });
}

bool HidEmulator::on_output(std::span<const uint8_t> report) {
  ++outputs_received_;
  // hidraw passes a report of a descriptor without ids on with its leading 0.
  if (!output_.descriptor().uses_report_ids && !report.empty() && report[0] == 0 &&
      report.size() == output_.report_length(0) + 1)
    report = report.subspan(1);
  std::copy(outputs_.begin(), outputs_.end(), decoded_.begin());
  if (output_.decode(report, decoded_) != fp::HidDecodeStatus::Ok) {
    ++bad_outputs_;
    return false;
  }
  bool changed = false;
  for (std::size_t i = 0; i < outputs_.size(); ++i) {
    changed = changed || decoded_[i].raw != outputs_[i].raw;
    outputs_[i] = decoded_[i];
  }
  return changed;
}

std::span<const uint8_t> HidEmulator::report(uint8_t report_id) const {
  const int16_t r = report_index_[report_id];
  if (r < 0) return {};
  return reports_[static_cast<std::size_t>(r)].bytes;
}

std::string HidEmulator::feedback_text() const {
  // LEDs by the definition's names, then every output signal no LED binds.
  std::ostringstream out;
  std::vector<bool> shown(outputs_.size(), false);
  bool any_led = false;
  for (const LedDefinition& led : definition_.leds) {
    if (led.source != source_ || led.hid_signal.empty()) continue;
    out << (any_led ? " " : "leds ") << led.name << '=';
    any_led = true;
    const std::size_t i = output_.find(led.hid_signal);
    if (i >= outputs_.size()) {
      out << '-';  // the device has no such output
      continue;
    }
    shown[i] = true;
    out << (outputs_[i].value != 0.0 ? "on" : "off");
  }
  bool any_output = false;
  for (std::size_t i = 0; i < outputs_.size(); ++i) {
    if (shown[i]) continue;
    out << (any_output ? " " : any_led ? "; outputs " : "outputs ") << output_.signals()[i].name << '='
        << outputs_[i].raw;
    any_output = true;
  }
  if (!any_led && !any_output) out << "outputs none";
  return out.str();
}

}  // namespace rise::panels
