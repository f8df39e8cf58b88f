#include "firmware_protocol/hid_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <unordered_map>

namespace rise::firmware_protocol {

namespace {

// HID Usage Tables 1.12: pages 0x01 (Generic Desktop), 0x02 (Simulation), 0x09 (Button).
constexpr uint16_t page_generic_desktop = 0x01;
constexpr uint16_t page_simulation = 0x02;
constexpr uint16_t page_button = 0x09;
constexpr uint16_t usage_hat_switch = 0x39;

std::string hex4(uint16_t v) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "%04x", static_cast<unsigned>(v));
  return buf;
}

const char* generic_desktop_name(uint16_t id) {
  switch (id) {
    case 0x30: return "x";
    case 0x31: return "y";
    case 0x32: return "z";
    case 0x33: return "rx";
    case 0x34: return "ry";
    case 0x35: return "rz";
    case 0x36: return "slider";
    case 0x37: return "dial";
    case 0x38: return "wheel";
    case 0x39: return "hat_switch";
    case 0x90: return "dpad_up";
    case 0x91: return "dpad_down";
    case 0x92: return "dpad_right";
    case 0x93: return "dpad_left";
    default: return nullptr;
  }
}

const char* simulation_name(uint16_t id) {
  switch (id) {
    case 0xBA: return "rudder";
    case 0xBB: return "throttle";
    case 0xC4: return "accelerator";
    case 0xC5: return "brake";
    default: return nullptr;
  }
}

// Sticks are centred; a 0..N stick reads -1..1 as Android and SDL report it.
bool is_centred(HidUsage usage, const HidField& field) {
  if (field.logical_min < 0) return true;
  return hid_usage_page(usage) == page_generic_desktop && hid_usage_id(usage) >= 0x30 &&
         hid_usage_id(usage) <= 0x35;
}

std::string unique_name(std::string name, std::unordered_map<std::string, int>& used) {
  int& n = used[name];
  ++n;
  if (n == 1) return name;
  std::string candidate = name + "_" + std::to_string(n);
  while (used.count(candidate) != 0) candidate = name + "_" + std::to_string(++n);
  used[candidate] = 1;
  return candidate;
}

}  // namespace

std::string hid_usage_name(HidUsage usage) {
  const uint16_t page = hid_usage_page(usage);
  const uint16_t id = hid_usage_id(usage);
  const char* known = nullptr;
  if (page == page_generic_desktop) known = generic_desktop_name(id);
  if (page == page_simulation) known = simulation_name(id);
  if (known != nullptr) return known;
  if (page == page_button && id > 0) return "button_" + std::to_string(id);
  if (page >= 0xFF00) return "vendor_" + hex4(page) + "_" + hex4(id);
  return "usage_" + hex4(page) + "_" + hex4(id);
}

std::vector<HidSignal> hid_signals(const HidDescriptor& descriptor, HidReportKind kind) {
  std::vector<HidSignal> out;
  std::unordered_map<std::string, int> used;
  for (std::size_t i = 0; i < descriptor.fields.size(); ++i) {
    const HidField& f = descriptor.fields[i];
    if (f.kind != kind || f.is_constant()) continue;
    for (uint32_t e = 0; e < f.count && out.size() < max_hid_signals; ++e) {
      HidSignal s;
      s.report_kind = kind;
      s.report_id = f.report_id;
      s.bit_offset = f.bit_offset + e * f.bit_size;
      s.bit_size = f.bit_size;
      s.field_index = i;
      s.element = e;
      s.logical_min = f.logical_min;
      s.logical_max = f.logical_max;
      s.physical_min = f.physical_min;
      s.physical_max = f.physical_max;
      if (!f.is_variable()) {
        s.kind = HidSignalKind::Array;
        s.name = unique_name("array_" + hex4(f.usage_page), used);
      } else {
        s.usage = f.usages.empty() ? hid_usage(f.usage_page, 0) : f.usage_at(e);
        s.name = unique_name(hid_usage_name(s.usage), used);
        if (f.is_relative()) {
          s.kind = HidSignalKind::Relative;
        } else if (s.usage == hid_usage(page_generic_desktop, usage_hat_switch)) {
          s.kind = HidSignalKind::Hat;
        } else if (hid_usage_page(s.usage) == page_button || f.bit_size == 1) {
          s.kind = HidSignalKind::Button;
        } else {
          s.kind = HidSignalKind::Axis;
          s.centred = is_centred(s.usage, f);
        }
      }
      out.push_back(std::move(s));
    }
  }
  return out;
}

int64_t hid_extract(const HidSignal& signal, std::span<const uint8_t> data) {
  if (signal.bit_size == 0 || signal.bit_size > 32) return 0;
  const uint64_t end_bit = uint64_t{signal.bit_offset} + signal.bit_size;
  if (end_bit > uint64_t{data.size()} * 8u) return 0;
  uint64_t raw = 0;
  for (uint32_t b = 0; b < signal.bit_size; ++b) {
    const uint64_t bit = uint64_t{signal.bit_offset} + b;
    if ((data[bit / 8u] >> (bit % 8u)) & 1u) raw |= uint64_t{1} << b;
  }
  if (signal.logical_min < 0 && ((raw >> (signal.bit_size - 1)) & 1u) != 0) {
    raw |= ~uint64_t{0} << signal.bit_size;  // two's complement sign extension
  }
  return static_cast<int64_t>(raw);
}

bool hid_insert(const HidSignal& signal, int64_t raw, std::span<uint8_t> data) {
  if (signal.bit_size == 0 || signal.bit_size > 32) return false;
  const uint64_t end_bit = uint64_t{signal.bit_offset} + signal.bit_size;
  if (end_bit > uint64_t{data.size()} * 8u) return false;
  const auto bits = static_cast<uint64_t>(raw);
  for (uint32_t b = 0; b < signal.bit_size; ++b) {
    const uint64_t bit = uint64_t{signal.bit_offset} + b;
    const auto mask = static_cast<uint8_t>(1u << (bit % 8u));
    if ((bits >> b) & 1u) {
      data[bit / 8u] = static_cast<uint8_t>(data[bit / 8u] | mask);
    } else {
      data[bit / 8u] = static_cast<uint8_t>(data[bit / 8u] & ~mask);
    }
  }
  return true;
}

HidSignalValue hid_normalise(const HidSignal& signal, const HidField& field, int64_t raw) {
  HidSignalValue v;
  v.raw = raw;
  const int64_t lo = signal.logical_min;
  const int64_t hi = signal.logical_max;
  const bool in_range = raw >= lo && raw <= hi;
  const double span = static_cast<double>(hi) - static_cast<double>(lo);
  switch (signal.kind) {
    case HidSignalKind::Hat:
      // 6.2.2.5 null state: a hat reports a value outside its range when released.
      if (!in_range || hi <= lo) {
        v.is_null = true;
      } else {
        v.value = static_cast<double>(raw - lo) * 360.0 / (span + 1.0);
      }
      break;
    case HidSignalKind::Button:
      v.value = raw != 0 && raw != lo ? 1.0 : 0.0;
      if (lo == 0 && hi == 0) v.value = raw != 0 ? 1.0 : 0.0;
      break;
    case HidSignalKind::Relative: v.value = static_cast<double>(raw); break;
    case HidSignalKind::Array: {
      const int64_t index = raw - lo;
      if (!in_range || index < 0 || static_cast<uint64_t>(index) >= field.usage_count()) {
        v.is_null = true;
        break;
      }
      v.usage = field.usage_at(static_cast<uint64_t>(index));
      if (hid_usage_id(v.usage) == 0) v.usage = 0;  // usage 0 = "no event" (e.g. keyboard 0x00)
      v.value = hid_usage_id(v.usage);
      break;
    }
    case HidSignalKind::Axis:
      if (field.has_null_state() && !in_range) {
        v.is_null = true;
        break;
      }
      if (hi <= lo) break;
      if (signal.centred && lo < 0) {
        const double scale = std::max(-static_cast<double>(lo), static_cast<double>(hi));
        v.value = static_cast<double>(raw) / scale;
      } else if (signal.centred) {
        v.value = 2.0 * (static_cast<double>(raw) - static_cast<double>(lo)) / span - 1.0;
      } else {
        v.value = (static_cast<double>(raw) - static_cast<double>(lo)) / span;
      }
      v.value = std::clamp(v.value, -1.0, 1.0);
      break;
  }
  return v;
}

int64_t hid_raw_from_value(const HidSignal& signal, double value) {
  const int64_t lo = signal.logical_min;
  const int64_t hi = std::max(signal.logical_max, lo);
  if (!std::isfinite(value)) return lo;
  const auto clamp_raw = [&](double r) {
    const double c = std::clamp(std::round(r), static_cast<double>(lo), static_cast<double>(hi));
    return static_cast<int64_t>(c);
  };
  const double span = static_cast<double>(hi) - static_cast<double>(lo);
  switch (signal.kind) {
    case HidSignalKind::Button:
      if (lo == 0 && hi == 0) return value >= 0.5 ? 1 : 0;
      return value >= 0.5 ? hi : lo;
    case HidSignalKind::Hat: {
      if (value < 0.0) return lo > 0 ? lo - 1 : hi + 1;  // null state: just outside the range
      const double positions = span + 1.0;
      const double step = std::fmod(std::round(value * positions / 360.0), positions);
      return lo + static_cast<int64_t>(step);
    }
    case HidSignalKind::Axis:
      if (signal.centred && lo < 0) {
        return clamp_raw(value * std::max(-static_cast<double>(lo), static_cast<double>(hi)));
      }
      if (signal.centred) return clamp_raw((value + 1.0) * 0.5 * span + static_cast<double>(lo));
      return clamp_raw(value * span + static_cast<double>(lo));
    case HidSignalKind::Relative:
    case HidSignalKind::Array: return clamp_raw(value);
  }
  return lo;
}

std::size_t find_hid_signal(std::span<const HidSignal> signals, std::string_view name) {
  for (std::size_t i = 0; i < signals.size(); ++i) {
    if (signals[i].name == name) return i;
  }
  return signals.size();
}

std::string hid_signal_names(std::span<const HidSignal> signals, std::size_t most) {
  std::string out;
  for (std::size_t i = 0; i < signals.size() && i < most; ++i) out += (i ? ", " : "") + signals[i].name;
  if (signals.size() > most) out += ", ...";
  return out;
}

HidReportSignals::HidReportSignals(HidDescriptor descriptor, HidReportKind kind)
    : descriptor_(std::move(descriptor)), kind_(kind), signals_(hid_signals(descriptor_, kind)) {
  for (const HidReportLayout& r : descriptor_.reports) {
    if (r.kind == kind) report_ids_.push_back(r.report_id);
  }
  std::sort(report_ids_.begin(), report_ids_.end());
  report_ids_.erase(std::unique(report_ids_.begin(), report_ids_.end()), report_ids_.end());
  // A counting sort by report id keeps each report's signals in descriptor order.
  for (const HidSignal& s : signals_) ++report_begin_[s.report_id + 1u];
  for (std::size_t k = 1; k < report_begin_.size(); ++k) report_begin_[k] += report_begin_[k - 1];
  std::array<uint32_t, 256> next{};
  for (std::size_t k = 0; k < next.size(); ++k) next[k] = report_begin_[k];
  by_report_.resize(signals_.size());
  for (std::size_t i = 0; i < signals_.size(); ++i) by_report_[next[signals_[i].report_id]++] = static_cast<uint32_t>(i);
}

std::span<const uint32_t> HidReportSignals::signals_of(uint8_t report_id) const {
  return std::span<const uint32_t>(by_report_).subspan(report_begin_[report_id],
                                                        report_begin_[report_id + 1u] - report_begin_[report_id]);
}

HidDecodeStatus HidReportDecoder::decode(std::span<const uint8_t> report,
                                         std::span<HidSignalValue> values) const {
  if (values.size() < signals().size()) return HidDecodeStatus::BufferTooSmall;
  uint8_t id = 0;
  std::span<const uint8_t> data = report;
  if (descriptor().uses_report_ids) {
    if (report.empty()) return HidDecodeStatus::TooShort;
    id = report[0];
    data = report.subspan(1);
  }
  const std::size_t length = report_length(id);
  if (length == 0) return HidDecodeStatus::UnknownReportId;
  if (report.size() < length) return HidDecodeStatus::TooShort;
  for (const uint32_t k : signals_of(id)) {
    const HidSignal& s = signals()[k];
    values[k] = hid_normalise(s, descriptor().fields[s.field_index], hid_extract(s, data));
  }
  return HidDecodeStatus::Ok;
}

std::vector<HidSignalValue> HidReportDecoder::decode(std::span<const uint8_t> report) const {
  std::vector<HidSignalValue> values(signals().size());
  decode(report, values);
  return values;
}

bool HidReportEncoder::encode(std::size_t index, int64_t raw, std::span<uint8_t> report) const {
  if (index >= signals().size()) return false;
  const HidSignal& s = signals()[index];
  if (report.size() < report_length(s.report_id)) return false;
  std::span<uint8_t> data = report;
  if (descriptor().uses_report_ids) {
    report[0] = s.report_id;
    data = report.subspan(1);
  }
  return hid_insert(s, raw, data);
}

std::size_t HidReportEncoder::encode_report(uint8_t report_id, std::span<const int64_t> raw,
                                            std::span<uint8_t> report) const {
  const std::size_t length = report_length(report_id);
  if (length == 0 || report.size() < length || raw.size() < signals().size()) return 0;
  std::fill(report.begin(), report.begin() + static_cast<std::ptrdiff_t>(length), uint8_t{0});
  std::span<uint8_t> data = report.first(length);
  if (descriptor().uses_report_ids) {
    report[0] = report_id;
    data = data.subspan(1);
  }
  for (const uint32_t k : signals_of(report_id)) hid_insert(signals()[k], raw[k], data);
  return length;
}

}  // namespace rise::firmware_protocol
