#include "firmware_protocol/hid_descriptor.hpp"

#include <algorithm>
#include <limits>

namespace rise::firmware_protocol {

namespace {

// Item types and tags (HID 1.11 6.2.2.2, 6.2.2.4, 6.2.2.7, 6.2.2.8).
constexpr uint8_t type_main = 0;
constexpr uint8_t type_global = 1;
constexpr uint8_t type_local = 2;
constexpr uint8_t long_item_prefix = 0xFE;

enum MainTag : uint8_t { input = 0x8, output = 0x9, collection = 0xA, feature = 0xB, end_collection = 0xC };
enum GlobalTag : uint8_t {
  usage_page = 0x0,
  logical_min = 0x1,
  logical_max = 0x2,
  physical_min = 0x3,
  physical_max = 0x4,
  unit_exponent = 0x5,
  unit = 0x6,
  report_size = 0x7,
  report_id = 0x8,
  report_count = 0x9,
  push = 0xA,
  pop = 0xB,
};
enum LocalTag : uint8_t { usage = 0x0, usage_min = 0x1, usage_max = 0x2, delimiter = 0xA };

constexpr std::size_t max_push_depth = 16;
constexpr std::size_t max_collection_depth = 32;
constexpr std::size_t max_fields = 4096;
constexpr uint64_t max_report_bits = 8192u * 8u;

// An item's data as read, before its signedness is known: Logical Maximum is
// signed or not depending on Logical Minimum, which may come later.
struct RawValue {
  uint32_t bits = 0;
  uint8_t size = 0;  ///< bytes: 0, 1, 2 or 4

  int64_t as_signed() const {
    switch (size) {
      case 1: return static_cast<int8_t>(bits);
      case 2: return static_cast<int16_t>(bits);
      case 4: return static_cast<int32_t>(bits);
      default: return 0;
    }
  }
  int64_t as_unsigned() const { return bits; }
};

struct GlobalState {
  uint16_t usage_page = 0;
  RawValue logical_min, logical_max, physical_min, physical_max;
  int32_t unit_exponent = 0;
  uint32_t unit = 0;
  uint32_t report_size = 0;
  uint32_t report_id = 0;
  uint32_t report_count = 0;
};

// A local usage before the main item fixes its page: 4-byte usages carry
// their page; shorter ones take the Usage Page in effect at the main item.
struct LocalUsage {
  uint32_t first = 0;
  uint32_t last = 0;
  bool extended = false;
};

struct LocalState {
  std::vector<LocalUsage> usages;
  bool have_min = false;
  LocalUsage pending_min;
  int delimiter_depth = 0;
  bool delimiter_taken = false;  ///< the open delimiter set already gave its usage

  void clear() {
    usages.clear();
    have_min = false;
    delimiter_depth = 0;
    delimiter_taken = false;
  }
};

class Parser {
 public:
  explicit Parser(std::span<const uint8_t> bytes) : bytes_(bytes) {}

  HidParseResult run() {
    std::size_t pos = 0;
    while (pos < bytes_.size()) {
      const std::size_t item_offset = pos;
      const uint8_t prefix = bytes_[pos];
      if (prefix == long_item_prefix) {
        // Long item (6.2.2.3): prefix, bDataSize, bLongItemTag, data. No long
        // items are defined, so they are skipped.
        if (pos + 3 > bytes_.size()) return fail(HidParseError::TruncatedItem, item_offset);
        const std::size_t data_size = bytes_[pos + 1];
        if (pos + 3 + data_size > bytes_.size()) return fail(HidParseError::TruncatedItem, item_offset);
        pos += 3 + data_size;
        continue;
      }
      const uint8_t size_code = prefix & 0x3u;
      const uint8_t size = size_code == 3 ? 4 : size_code;
      const uint8_t type = (prefix >> 2) & 0x3u;
      const uint8_t tag = prefix >> 4;
      if (pos + 1 + size > bytes_.size()) return fail(HidParseError::TruncatedItem, item_offset);
      RawValue value{0, size};
      for (uint8_t i = 0; i < size; ++i) value.bits |= uint32_t{bytes_[pos + 1 + i]} << (8u * i);
      pos += 1u + size;

      HidParseError error = HidParseError::None;
      switch (type) {
        case type_main: error = main_item(tag, value); break;
        case type_global: error = global_item(tag, value); break;
        case type_local: error = local_item(tag, value); break;
        default: break;  // reserved item type: skipped
      }
      if (error != HidParseError::None) return fail(error, item_offset);
    }
    if (!collections_.empty()) return fail(HidParseError::UnclosedCollection, bytes_.size());
    HidParseResult result;
    result.descriptor = std::move(descriptor_);
    return result;
  }

 private:
  HidParseResult fail(HidParseError error, std::size_t offset) const {
    HidParseResult result;
    result.error = error;
    result.error_offset = offset;
    return result;
  }

  HidUsage resolve(uint32_t usage, bool extended) const {
    return extended ? usage : hid_usage(global_.usage_page, static_cast<uint16_t>(usage));
  }

  HidParseError main_item(uint8_t tag, RawValue value) {
    HidParseError error = HidParseError::None;
    switch (tag) {
      case input: error = add_field(HidReportKind::Input, value.bits); break;
      case output: error = add_field(HidReportKind::Output, value.bits); break;
      case feature: error = add_field(HidReportKind::Feature, value.bits); break;
      case collection: {
        if (collections_.size() >= max_collection_depth) return HidParseError::CollectionTooDeep;
        HidCollection c;
        c.type = static_cast<uint8_t>(value.bits & 0xFFu);
        if (!local_.usages.empty()) c.usage = resolve(local_.usages.front().first, local_.usages.front().extended);
        collections_.push_back(c);
        break;
      }
      case end_collection:
        if (collections_.empty()) return HidParseError::EndCollectionWithoutCollection;
        collections_.pop_back();
        break;
      default: break;  // reserved main tag (e.g. the trailing 0x00 some devices send)
    }
    if (local_.delimiter_depth != 0) error = error == HidParseError::None ? HidParseError::DelimiterMismatch : error;
    local_.clear();
    return error;
  }

  HidParseError add_field(HidReportKind kind, uint32_t flags) {
    if (global_.report_count > 0 && global_.report_size == 0) {
      // A zero-bit constant field is harmless padding that real devices send
      // (the Saitek joystick in hid-tools); Linux ignores it too.
      if ((flags & hid_flags::constant) != 0) return HidParseError::None;
      return HidParseError::ZeroReportSizeWithCount;
    }
    if (global_.report_size > 32) return HidParseError::FieldTooWide;
    HidReportLayout* layout = find_layout(kind, static_cast<uint8_t>(global_.report_id));
    const uint64_t bits = uint64_t{global_.report_size} * global_.report_count;
    const uint64_t before = layout == nullptr ? 0 : layout->size_bits;
    if (bits > max_report_bits || before + bits > max_report_bits) return HidParseError::ReportTooLong;
    if (global_.report_count == 0) return HidParseError::None;
    if (descriptor_.fields.size() >= max_fields) return HidParseError::TooManyFields;
    if (layout == nullptr) {
      descriptor_.reports.push_back({kind, static_cast<uint8_t>(global_.report_id), 0});
      layout = &descriptor_.reports.back();
    }

    HidField f;
    f.kind = kind;
    f.report_id = static_cast<uint8_t>(global_.report_id);
    f.bit_offset = layout->size_bits;
    f.bit_size = global_.report_size;
    f.count = global_.report_count;
    f.logical_min = global_.logical_min.as_signed();
    f.logical_max = f.logical_min < 0 ? global_.logical_max.as_signed() : global_.logical_max.as_unsigned();
    // 6.2.2.7: Physical Minimum and Maximum both 0 mean "same as logical".
    const bool no_physical = global_.physical_min.bits == 0 && global_.physical_max.bits == 0;
    if (no_physical) {
      f.physical_min = f.logical_min;
      f.physical_max = f.logical_max;
    } else {
      f.physical_min = global_.physical_min.as_signed();
      f.physical_max =
          f.physical_min < 0 ? global_.physical_max.as_signed() : global_.physical_max.as_unsigned();
    }
    f.unit_exponent = global_.unit_exponent;
    f.unit = global_.unit;
    f.flags = flags;
    f.usage_page = global_.usage_page;
    f.usages.reserve(local_.usages.size());
    for (const LocalUsage& u : local_.usages) {
      f.usages.push_back({resolve(u.first, u.extended), resolve(u.last, u.extended)});
    }
    f.collection_path = collections_;
    layout->size_bits = static_cast<uint32_t>(before + bits);
    descriptor_.fields.push_back(std::move(f));
    return HidParseError::None;
  }

  HidReportLayout* find_layout(HidReportKind kind, uint8_t id) {
    for (HidReportLayout& r : descriptor_.reports) {
      if (r.kind == kind && r.report_id == id) return &r;
    }
    return nullptr;
  }

  HidParseError global_item(uint8_t tag, RawValue value) {
    switch (tag) {
      case usage_page: global_.usage_page = static_cast<uint16_t>(value.bits & 0xFFFFu); break;
      case logical_min: global_.logical_min = value; break;
      case logical_max: global_.logical_max = value; break;
      case physical_min: global_.physical_min = value; break;
      case physical_max: global_.physical_max = value; break;
      case unit_exponent:
        // 6.2.2.7: a 4-bit two's complement nibble in practice (0x0E = -2).
        global_.unit_exponent = value.bits <= 0xFu ? static_cast<int32_t>((value.bits ^ 0x8u)) - 8
                                                   : static_cast<int32_t>(value.as_signed());
        break;
      case unit: global_.unit = value.bits; break;
      case report_size: global_.report_size = value.bits; break;
      case report_id:
        if (value.bits == 0 || value.bits > 255) return HidParseError::BadReportId;
        global_.report_id = value.bits;
        descriptor_.uses_report_ids = true;
        break;
      case report_count: global_.report_count = value.bits; break;
      case push:
        if (stack_.size() >= max_push_depth) return HidParseError::PushTooDeep;
        stack_.push_back(global_);
        break;
      case pop:
        if (stack_.empty()) return HidParseError::PopWithoutPush;
        global_ = stack_.back();
        stack_.pop_back();
        break;
      default: break;  // reserved global tag
    }
    return HidParseError::None;
  }

  HidParseError local_item(uint8_t tag, RawValue value) {
    const bool extended = value.size == 4;
    const uint32_t usage_value = extended ? value.bits : (value.bits & 0xFFFFu);
    switch (tag) {
      case usage:
        if (local_.delimiter_depth > 0) {
          // 6.2.2.8: inside a delimiter set the usages are alternatives; the
          // first one is the preferred usage.
          if (local_.delimiter_taken) break;
          local_.delimiter_taken = true;
        }
        if (local_.usages.size() < max_fields) local_.usages.push_back({usage_value, usage_value, extended});
        break;
      case usage_min:
        local_.have_min = true;
        local_.pending_min = {usage_value, usage_value, extended};
        break;
      case usage_max:
        if (local_.usages.size() >= max_fields) break;
        if (local_.have_min) {
          LocalUsage range = local_.pending_min;
          range.last = usage_value;
          if (range.last < range.first) std::swap(range.first, range.last);
          local_.usages.push_back(range);
          local_.have_min = false;
        } else {
          local_.usages.push_back({usage_value, usage_value, extended});
        }
        break;
      case delimiter:
        if (value.bits == 1) {
          if (local_.delimiter_depth != 0) return HidParseError::DelimiterMismatch;
          local_.delimiter_depth = 1;
          local_.delimiter_taken = false;
        } else if (value.bits == 0) {
          if (local_.delimiter_depth != 1) return HidParseError::DelimiterMismatch;
          local_.delimiter_depth = 0;
        } else {
          return HidParseError::DelimiterMismatch;
        }
        break;
      default: break;  // Designator and String items carry nothing we decode
    }
    return HidParseError::None;
  }

  std::span<const uint8_t> bytes_;
  HidDescriptor descriptor_;
  GlobalState global_;
  LocalState local_;
  std::vector<GlobalState> stack_;
  std::vector<HidCollection> collections_;
};

}  // namespace

HidUsage HidField::usage_at(uint64_t index) const {
  if (usages.empty()) return 0;
  for (const HidUsageRange& r : usages) {
    const uint64_t n = uint64_t{r.last} - r.first + 1;
    if (index < n) return static_cast<HidUsage>(r.first + index);
    index -= n;
  }
  return usages.back().last;
}

uint64_t HidField::usage_count() const {
  uint64_t n = 0;
  for (const HidUsageRange& r : usages) n += uint64_t{r.last} - r.first + 1;
  return n;
}

std::size_t HidDescriptor::report_length(uint8_t report_id, HidReportKind kind) const {
  for (const HidReportLayout& r : reports) {
    if (r.kind == kind && r.report_id == report_id) {
      return (r.size_bits + 7u) / 8u + (uses_report_ids ? 1u : 0u);
    }
  }
  return 0;
}

HidParseResult parse_hid_descriptor(std::span<const uint8_t> bytes) { return Parser(bytes).run(); }

std::string_view to_string(HidParseError error) {
  switch (error) {
    case HidParseError::None: return "no error";
    case HidParseError::TruncatedItem: return "truncated item";
    case HidParseError::PopWithoutPush: return "Pop without Push";
    case HidParseError::PushTooDeep: return "Push nested too deep";
    case HidParseError::ZeroReportSizeWithCount: return "Report Size 0 with a Report Count";
    case HidParseError::EndCollectionWithoutCollection: return "End Collection without Collection";
    case HidParseError::UnclosedCollection: return "collection not closed at the end";
    case HidParseError::CollectionTooDeep: return "collections nested too deep";
    case HidParseError::FieldTooWide: return "Report Size over 32 bits";
    case HidParseError::ReportTooLong: return "report longer than 8192 bytes";
    case HidParseError::BadReportId: return "Report ID 0 or over 255";
    case HidParseError::DelimiterMismatch: return "unbalanced Delimiter";
    case HidParseError::TooManyFields: return "more than 4096 main items";
  }
  return "unknown error";
}

std::string_view to_string(HidReportKind kind) {
  switch (kind) {
    case HidReportKind::Input: return "input";
    case HidReportKind::Output: return "output";
    case HidReportKind::Feature: return "feature";
  }
  return "?";
}

}  // namespace rise::firmware_protocol
