#pragma once

#include <cstdint>
#include <string>
#include <string_view>

namespace rise::hil::io {

/// A Modbus endpoint:
///   modbus+tcp://HOST:PORT?unit=N&timeout_ms=T              (client)
///   modbus+rtu:///dev/ttyUSB0?baud=115200&parity=E&data=8&stop=1&unit=N&timeout_ms=T
///   modbus+tcp-listen://HOST:PORT?unit=N                    (server; PORT 0 = any free port)
///   modbus+rtu-listen:///dev/pts/3?baud=...&unit=N          (server)
/// Defaults: port 502, unit 1, timeout_ms 100, baud 19200, parity E, data 8,
/// stop 1 (Modbus over Serial Line V1.02 §2.5.1: even parity is the default).
struct ModbusAddress {
  enum class Kind { Tcp, Rtu } kind = Kind::Tcp;
  bool listen = false;
  std::string host;    ///< TCP
  uint16_t port = 502; ///< TCP
  std::string device;  ///< RTU
  int baud = 19200;
  char parity = 'E';   ///< 'N', 'E' or 'O'
  int data_bits = 8;
  int stop_bits = 1;
  int unit = 1;        ///< slave / unit id 1..247
  int timeout_ms = 100;
};

/// Parses a Modbus URL. Throws std::invalid_argument naming the URL and what
/// is wrong. Not for the cyclic path.
ModbusAddress parse_modbus_url(std::string_view url);

/// True when the URL's scheme is one of the modbus+ schemes above.
bool is_modbus_url(std::string_view url);

}  // namespace rise::hil::io
