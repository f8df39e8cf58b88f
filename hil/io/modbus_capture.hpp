#pragma once

// Modbus/TCP transactions from a packet capture (pcap or pcapng, read by
// Debian's libpcap): Ethernet (VLAN tags too), Linux cooked SLL/SLL2 or raw
// IP; IPv4 or IPv6; TCP to or from the Modbus port. Each direction of a TCP
// connection is a byte stream of MBAP ADUs (an ADU may span segments, a
// segment may hold several); requests and responses are paired by
// connection, transaction id and unit id.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "hil/io/modbus_trace.hpp"

namespace rise::hil::io {

struct ModbusCaptureTransaction {
  int64_t request_us = 0;                 ///< request time, microseconds since the Unix epoch
  std::optional<int64_t> response_us;     ///< response time, if one came
  std::string client;                     ///< "ADDRESS:PORT" of the side that asked
  std::string server;                     ///< "ADDRESS:PORT" of the side that answered
  uint16_t transaction_id = 0;
  uint8_t unit = 0;
  uint8_t function = 0;                   ///< the request's function code
  std::optional<uint16_t> address;        ///< first coil/register (read part of FC 23)
  std::optional<uint16_t> count;          ///< how many (1 for FC 5 and 6)
  std::optional<uint8_t> exception;       ///< exception code when the response is one
  std::vector<uint8_t> request_pdu;       ///< function code and data
  std::vector<uint8_t> response_pdu;
};

struct ModbusCaptureStats {
  uint64_t packets = 0;          ///< every packet of the file
  uint64_t modbus_segments = 0;  ///< TCP segments with payload to or from the port
  uint64_t requests = 0;
  uint64_t responses = 0;
  uint64_t exceptions = 0;
  uint64_t retransmissions = 0;       ///< segments whose bytes were all seen already
  uint64_t unmatched_responses = 0;   ///< responses to no pending request
  uint64_t malformed = 0;             ///< ADUs with a bad MBAP header, lost stream bytes
};

struct ModbusCapture {
  std::vector<ModbusCaptureTransaction> transactions;  ///< in request order
  ModbusCaptureStats stats;
};

/// Reads every transaction of a capture. Throws std::runtime_error naming
/// the path when it cannot be opened or its link type carries no IP.
ModbusCapture read_modbus_capture(const std::string& path, uint16_t port = 502);

/// True when path is a pcap/pcapng whose packets are IP (Ethernet, raw IP,
/// or a Linux cooked capture whose first packet is not CAN): a capture for
/// a Modbus source rather than a CAN one. Does not throw.
bool looks_like_modbus_capture(const std::string& path);

/// The capture's transactions as trace records (modbus_trace.hpp) of one
/// source, for replay://CAPTURE.pcap on a Modbus source: the functions a
/// trace knows (01-04, 15, 16) with the values read or written, exceptions,
/// and requests without an answer as timeouts (rtt: until the next request
/// on the connection, or 1 s); other functions are left out, and so is a
/// write whose request holds fewer values than its count (a write's line
/// always says what it wrote).
std::vector<ModbusTraceRecord> modbus_trace_from_capture(const ModbusCapture& capture, const std::string& source);

/// "Read Coils", "Write Multiple Registers", ... ("function N" otherwise).
std::string modbus_function_name(uint8_t function);
/// "illegal data address", ... ("exception N" otherwise).
std::string modbus_exception_name(uint8_t code);

}  // namespace rise::hil::io
