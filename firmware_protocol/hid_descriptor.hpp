#pragma once

// A USB HID report-descriptor parser (Device Class Definition for HID 1.11,
// section 6.2.2). It turns the item stream into a flat list of report fields
// per report id and direction, with the global/local state each field was
// declared under already resolved.
//
// Read: Main Input/Output/Feature/Collection/End Collection; Global Usage
// Page, Logical/Physical Minimum/Maximum, Unit Exponent, Unit, Report Size,
// Report ID, Report Count, Push, Pop; Local Usage, Usage Minimum/Maximum,
// Delimiter. Designator/String locals, reserved items and long items
// (6.2.2.3) are skipped.

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

namespace rise::firmware_protocol {

enum class HidReportKind : uint8_t { Input, Output, Feature };

/// Collection types (HID 1.11 6.2.2.6); values above 0x06 are reserved or vendor.
enum class HidCollectionType : uint8_t {
  Physical = 0x00,
  Application = 0x01,
  Logical = 0x02,
  Report = 0x03,
  NamedArray = 0x04,
  UsageSwitch = 0x05,
  UsageModifier = 0x06,
};

/// An extended usage: usage page in the high 16 bits, usage id in the low 16.
using HidUsage = uint32_t;
constexpr HidUsage hid_usage(uint16_t page, uint16_t id) { return (HidUsage{page} << 16) | id; }
constexpr uint16_t hid_usage_page(HidUsage u) { return static_cast<uint16_t>(u >> 16); }
constexpr uint16_t hid_usage_id(HidUsage u) { return static_cast<uint16_t>(u & 0xFFFFu); }

/// An inclusive usage range; a single Usage item is a range of one.
struct HidUsageRange {
  HidUsage first = 0;
  HidUsage last = 0;
};

struct HidCollection {
  uint8_t type = 0;  ///< HidCollectionType value (raw: reserved values are kept)
  HidUsage usage = 0;
};

/// Bits of the Input/Output/Feature item data (HID 1.11 6.2.2.5).
namespace hid_flags {
constexpr uint32_t constant = 1u << 0;  ///< else data
constexpr uint32_t variable = 1u << 1;  ///< else array
constexpr uint32_t relative = 1u << 2;  ///< else absolute
constexpr uint32_t wrap = 1u << 3;
constexpr uint32_t non_linear = 1u << 4;
constexpr uint32_t no_preferred = 1u << 5;
constexpr uint32_t null_state = 1u << 6;
constexpr uint32_t is_volatile = 1u << 7;
constexpr uint32_t buffered_bytes = 1u << 8;
}  // namespace hid_flags

/// One Input/Output/Feature main item: `count` elements of `bit_size` bits each,
/// packed little-endian from `bit_offset`.
struct HidField {
  HidReportKind kind = HidReportKind::Input;
  uint8_t report_id = 0;    ///< 0 when the descriptor declares no Report ID
  uint32_t bit_offset = 0;  ///< from the start of the report data, after the id byte if ids are used
  uint32_t bit_size = 0;    ///< 1..32 (0 only with count 0)
  uint32_t count = 0;
  int64_t logical_min = 0;  ///< maximum read as unsigned when the minimum is >= 0 (as Linux does)
  int64_t logical_max = 0;
  int64_t physical_min = 0;  ///< equal to the logical range when both are 0 (6.2.2.7)
  int64_t physical_max = 0;
  int32_t unit_exponent = 0;
  uint32_t unit = 0;
  uint32_t flags = 0;       ///< hid_flags bits
  uint16_t usage_page = 0;  ///< the global Usage Page in effect
  std::vector<HidUsageRange> usages;  ///< the local usages in declaration order
  std::vector<HidCollection> collection_path;  ///< outermost first

  bool is_constant() const { return (flags & hid_flags::constant) != 0; }
  bool is_variable() const { return (flags & hid_flags::variable) != 0; }
  bool is_relative() const { return (flags & hid_flags::relative) != 0; }
  bool has_null_state() const { return (flags & hid_flags::null_state) != 0; }
  bool is_signed() const { return logical_min < 0; }
  /// The usage of element `index` (variable fields) or of array index `index`;
  /// the last usage repeats past the end (6.2.2.8). 0 when there is none.
  HidUsage usage_at(uint64_t index) const;
  /// Number of usages listed (ranges expanded), saturating.
  uint64_t usage_count() const;
};

/// The size of one report (id + direction) in bits, without the id byte.
struct HidReportLayout {
  HidReportKind kind = HidReportKind::Input;
  uint8_t report_id = 0;
  uint32_t size_bits = 0;
};

struct HidDescriptor {
  std::vector<HidField> fields;  ///< in descriptor order
  std::vector<HidReportLayout> reports;
  bool uses_report_ids = false;
  /// Report length in bytes on the wire (id byte included when ids are used);
  /// 0 when the report does not exist.
  std::size_t report_length(uint8_t report_id, HidReportKind kind) const;
};

enum class HidParseError : uint8_t {
  None,
  TruncatedItem,          ///< an item's data runs past the end
  PopWithoutPush,
  PushTooDeep,            ///< more than 16 nested Push
  ZeroReportSizeWithCount,  ///< a data field of 0 bits (constant ones are skipped as padding)
  EndCollectionWithoutCollection,
  UnclosedCollection,     ///< the descriptor ends inside a collection
  CollectionTooDeep,      ///< more than 32 nested collections
  FieldTooWide,           ///< Report Size > 32 bits
  ReportTooLong,          ///< a report over 8192 bytes (also catches huge Report Counts)
  BadReportId,            ///< Report ID 0 or > 255, or fields declared before the first id once ids are used
  DelimiterMismatch,
  TooManyFields,          ///< over 4096 main items
};

/// The outcome of parse_hid_descriptor(): `error == None` and the descriptor,
/// or the error and the byte offset of the item that caused it.
struct HidParseResult {
  HidDescriptor descriptor;
  HidParseError error = HidParseError::None;
  std::size_t error_offset = 0;
  explicit operator bool() const { return error == HidParseError::None; }
};

/// Parses a report descriptor. Never throws (except std::bad_alloc) and never
/// reads outside `bytes`. Allocates: not for the cyclic path.
HidParseResult parse_hid_descriptor(std::span<const uint8_t> bytes);

std::string_view to_string(HidParseError error);
std::string_view to_string(HidReportKind kind);

}  // namespace rise::firmware_protocol
