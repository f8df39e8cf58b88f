#pragma once

// The inspection commands a lab runs before wiring a console in
// (rise-hild dbc decode, rise-hild hid describe).

#include <iosfwd>
#include <string>

namespace rise::hil {

/// Prints the decoded signals of every frame of a candump log, one line per
/// frame (cantools' "decode --single-line" layout), then a coverage count.
/// Returns the process exit code (0 ok, 2 unreadable input).
int dbc_decode(const std::string& dbc_file, const std::string& log_file, std::ostream& out, std::ostream& err);

/// Prints every field of a HID report descriptor file (report id, direction,
/// usage, bit offset and size, logical range, flags, the signal it becomes).
/// Returns the process exit code (0 ok, 2 unreadable or malformed input).
int hid_describe(const std::string& file, std::ostream& out, std::ostream& err);

}  // namespace rise::hil
