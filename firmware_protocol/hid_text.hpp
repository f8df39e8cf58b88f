#pragma once

// Readers for the textual and binary forms HID report descriptors come in,
// and a human-readable description of a parsed descriptor (what
// `rise-hild hid describe FILE` prints).
//
// Formats (all return the descriptor bytes; none of them interpret items):
// - hex text: `05 01 09 05`, `0x05, 0x01,` or a C array body, with `//`,
//   `/* */` and `#` comments (hidapi's .rpt_desc files);
// - hid-recorder: `R: <len> <hex bytes>`, `N: <name>`, `I: <bus> <vid> <pid>`
//   (other lines such as `E:` events are ignored);
// - Markdown: the first fenced block holding only hex bytes (xpadneo docs);
// - Android CTS "register" JSON: `"descriptor": [0x05, 0x01, ...]` with
//   0x literals (not strict JSON), plus `"name"`, `"vid"`, `"pid"`;
// - raw binary, as /sys/class/hidraw/hidrawN/device/report_descriptor.
//
// Errors throw std::runtime_error("file:line: key: message"). Allocates and
// throws: not for the cyclic path.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "firmware_protocol/hid_descriptor.hpp"

namespace rise::firmware_protocol {

enum class HidTextFormat : uint8_t { HexText, HidRecorder, Markdown, CtsJson, Binary };

struct HidDescriptorSource {
  std::vector<uint8_t> bytes;
  std::vector<uint32_t> lines;  ///< source line of each byte (0 for binary)
  std::string name;             ///< device name when the file gives one
  uint32_t bus = 0;             ///< hid-recorder `I:` bus (3 USB, 5 Bluetooth)
  uint16_t vendor_id = 0;
  uint16_t product_id = 0;
};

/// Guesses the format from the content (and `file_name`'s extension).
HidTextFormat detect_hid_format(std::string_view content, std::string_view file_name);

/// Reads descriptor bytes from `content` in `format`; `file_name` only names
/// the source in error messages.
HidDescriptorSource read_hid_descriptor(std::string_view content, HidTextFormat format,
                                        const std::string& file_name);

/// Reads a file in any of the formats above (detected).
HidDescriptorSource read_hid_descriptor_file(const std::string& path);

/// Reads and parses a file; a parse error names the file, the source line of
/// the offending item and its byte offset.
HidDescriptor load_hid_descriptor_file(const std::string& path);

/// Every field (report id, direction, usage page and usages, bit offset and
/// size, count, logical and physical range, flags) and the signals it becomes.
std::string describe_hid_descriptor(const HidDescriptor& descriptor);

}  // namespace rise::firmware_protocol
