#pragma once

// The inspection commands a lab runs before wiring a console in
// (rise-hild dbc decode, rise-hild modbus decode, rise-hild hid describe).

#include <iosfwd>
#include <string>

namespace rise::hil {

/// Prints the decoded signals of every frame of a CAN log (candump, ASC, TRC,
/// BLF, pcap/pcapng: io::CanLogReader), one candump line per frame
/// (cantools' "decode --single-line" layout), then a coverage count.
/// Returns the process exit code (0 ok, 2 unreadable input).
int dbc_decode(const std::string& dbc_file, const std::string& log_file, std::ostream& out, std::ostream& err);

/// Prints the Modbus/TCP transactions of a pcap/pcapng capture as a table:
/// time since the first request, client, server, transaction id, unit,
/// function, address, count, the response (ok, exception, none) and its
/// delay in ms; then the counts (exceptions, retransmissions, ...).
/// Returns the process exit code (0 ok, 2 unreadable input or no Modbus/TCP).
int modbus_decode(const std::string& capture_file, std::ostream& out, std::ostream& err);

/// Prints every field of a HID report descriptor file (report id, direction,
/// usage, bit offset and size, logical range, flags, the signal it becomes).
/// Returns the process exit code (0 ok, 2 unreadable or malformed input).
int hid_describe(const std::string& file, std::ostream& out, std::ostream& err);

}  // namespace rise::hil
