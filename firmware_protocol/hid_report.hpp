#pragma once

// Named signals of a parsed HID descriptor and a codec for the raw reports.
//
// Every element of a data (non-constant) variable field becomes one signal,
// named from the HID Usage Tables 1.12: Generic Desktop x, y, z, rx, ry, rz,
// slider, dial, wheel, hat_switch; Simulation throttle, rudder, accelerator,
// brake; Button page button_N; vendor pages (0xFF00..0xFFFF) vendor_PPPP_UUUU;
// anything else usage_PPPP_UUUU (hex). A repeated name gets _2, _3, ...
// Every element of an array field becomes one signal <usage name>_array_N
// whose value is the usage it reports (0 when the slot is empty).
//
// Worked example (Gravis GamePad Pro, no report ids): report `00 FF 05 02`
// decodes to x = 0 (-1.0), y = 255 (+1.0), button_1 = 1, button_3 = 1,
// button_10 = 1, every other button 0.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "firmware_protocol/hid_descriptor.hpp"

namespace rise::firmware_protocol {

enum class HidSignalKind : uint8_t {
  Axis,    ///< absolute value, normalised to -1..1 (sticks, signed ranges) or 0..1
  Button,  ///< Button page or a 1-bit field: 0 or 1
  Hat,     ///< Generic Desktop Hat switch: angle in degrees, null outside the logical range
  Relative,  ///< relative field: the raw value, unscaled
  Array,   ///< one slot of an array field: the usage it reports
};

struct HidSignal {
  std::string name;
  HidSignalKind kind = HidSignalKind::Axis;
  HidReportKind report_kind = HidReportKind::Input;
  uint8_t report_id = 0;
  uint32_t bit_offset = 0;  ///< from the start of the report data (after the id byte when ids are used)
  uint32_t bit_size = 0;
  HidUsage usage = 0;  ///< 0 for array slots
  std::size_t field_index = 0;  ///< into HidDescriptor::fields
  uint32_t element = 0;         ///< element of that field
  int64_t logical_min = 0;
  int64_t logical_max = 0;
  int64_t physical_min = 0;
  int64_t physical_max = 0;
  bool centred = false;  ///< normalised to -1..1 rather than 0..1
};

struct HidSignalValue {
  int64_t raw = 0;      ///< sign-extended when the logical minimum is negative
  double value = 0.0;   ///< normalised (see HidSignalKind); 0 when null
  HidUsage usage = 0;   ///< array slots: the usage pressed, 0 for none
  bool is_null = false; ///< outside the logical range (null state, 6.2.2.5)
};

enum class HidDecodeStatus : uint8_t {
  Ok,
  UnknownReportId,  ///< no input report with this id: nothing written
  TooShort,         ///< shorter than the report: nothing written
  BufferTooSmall,   ///< values span shorter than signals()
};

/// Snake-case name of a usage as above (without the uniqueness suffix).
std::string hid_usage_name(HidUsage usage);

/// Signals per direction are capped here (a hostile descriptor may declare
/// millions of 1-bit elements); real devices have a few hundred at most.
constexpr std::size_t max_hid_signals = 8192;

/// The signals of every report of one direction, in descriptor order, at most
/// max_hid_signals. Allocates: call once at start-up.
std::vector<HidSignal> hid_signals(const HidDescriptor& descriptor, HidReportKind kind);

/// Reads the raw value of `signal` from report data (without the id byte);
/// sign-extended when its logical minimum is negative. No allocation, no
/// throw; 0 when the bits lie outside `data`.
int64_t hid_extract(const HidSignal& signal, std::span<const uint8_t> data);

/// Writes the low `bit_size` bits of `raw` into report data (without the id
/// byte). No allocation, no throw; false (and nothing written) when the bits
/// lie outside `data`.
bool hid_insert(const HidSignal& signal, int64_t raw, std::span<uint8_t> data);

/// The normalised value of a raw value (see HidSignalKind). Cyclic-path safe.
HidSignalValue hid_normalise(const HidSignal& signal, const HidField& field, int64_t raw);

/// The raw value for a normalised one (inverse of hid_normalise for axes and
/// buttons; hats take degrees), clamped to the logical range. Cyclic-path safe.
int64_t hid_raw_from_value(const HidSignal& signal, double value);

/// Index of the signal called `name`, or signals.size() when none. Cyclic-path safe.
std::size_t find_hid_signal(std::span<const HidSignal> signals, std::string_view name);

/// "x, y, button_1, ..." : the first `most` names, for messages that say
/// what a device has; empty when there are none. Allocates.
std::string hid_signal_names(std::span<const HidSignal> signals, std::size_t most = 24);

/// The signals of one direction of a descriptor, grouped by report id: the
/// part the decoder and the encoders share.
class HidReportSignals {
 public:
  /// Allocates: call once at start-up (or when a device is opened).
  HidReportSignals(HidDescriptor descriptor, HidReportKind kind);

  const HidDescriptor& descriptor() const { return descriptor_; }
  HidReportKind kind() const { return kind_; }
  const std::vector<HidSignal>& signals() const { return signals_; }
  /// Index of the signal called `name`, or signals().size() when none.
  std::size_t find(std::string_view name) const { return find_hid_signal(signals_, name); }
  /// Report length on the wire (id byte included when ids are used); 0 when
  /// this direction has no report `report_id`. Cyclic-path safe.
  std::size_t report_length(uint8_t report_id) const { return descriptor_.report_length(report_id, kind_); }
  /// The ids of this direction's reports, ascending (one 0 when ids are unused).
  const std::vector<uint8_t>& report_ids() const { return report_ids_; }
  /// Indices into signals() of the signals of report `report_id`, in
  /// descriptor order. Cyclic-path safe.
  std::span<const uint32_t> signals_of(uint8_t report_id) const;

 private:
  HidDescriptor descriptor_;
  HidReportKind kind_;
  std::vector<HidSignal> signals_;
  std::vector<uint8_t> report_ids_;
  // Signal indices grouped by report id: those of id k are
  // by_report_[report_begin_[k] .. report_begin_[k + 1]).
  std::vector<uint32_t> by_report_;
  std::array<uint32_t, 257> report_begin_{};
};

/// Decodes the reports of one direction (input: what the host reads; output:
/// what a device receives) into a caller-owned buffer.
class HidReportDecoder : public HidReportSignals {
 public:
  explicit HidReportDecoder(HidDescriptor descriptor, HidReportKind kind = HidReportKind::Input)
      : HidReportSignals(std::move(descriptor), kind) {}

  /// Decodes one report as it travels (with its id byte when the descriptor
  /// uses ids) into `values` (indexed like signals()). Only the signals of
  /// that report are written. No allocation, no throw.
  HidDecodeStatus decode(std::span<const uint8_t> report, std::span<HidSignalValue> values) const;

  /// Convenience: decode into a fresh buffer of zeroed values. Allocates.
  std::vector<HidSignalValue> decode(std::span<const uint8_t> report) const;
};

/// Builds the reports of one direction from raw signal values
/// (hid_raw_from_value turns normalised values into raw ones).
class HidReportEncoder : public HidReportSignals {
 public:
  HidReportEncoder(HidDescriptor descriptor, HidReportKind kind) : HidReportSignals(std::move(descriptor), kind) {}

  /// Writes signal `index` as `raw` into `report` (a buffer of
  /// report_length() bytes for that signal's report, id byte first when ids
  /// are used; the id byte is set too). No allocation, no throw; false when
  /// the index or the buffer does not fit.
  bool encode(std::size_t index, int64_t raw, std::span<uint8_t> report) const;

  /// Builds the whole report `report_id` from `raw` (one value per signal,
  /// indexed like signals()): id byte first when ids are used, constant
  /// (padding) bits 0. Returns its length on the wire; 0 (nothing written)
  /// when there is no such report or `raw` or `report` is too short. No
  /// allocation, no throw.
  std::size_t encode_report(uint8_t report_id, std::span<const int64_t> raw, std::span<uint8_t> report) const;
};

/// Builds input reports from signal values: what a device sends (the HID
/// emulator's side).
class HidInputEncoder : public HidReportEncoder {
 public:
  explicit HidInputEncoder(HidDescriptor descriptor) : HidReportEncoder(std::move(descriptor), HidReportKind::Input) {}
};

/// Builds output reports (LEDs, rumble / force feedback) from signal values:
/// what the host writes.
class HidOutputEncoder : public HidReportEncoder {
 public:
  explicit HidOutputEncoder(HidDescriptor descriptor) : HidReportEncoder(std::move(descriptor), HidReportKind::Output) {}
};

}  // namespace rise::firmware_protocol
