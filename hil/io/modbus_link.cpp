#include "hil/io/modbus_link.hpp"

#include <modbus.h>

#include "hil/io/posix_io.hpp"
#include "hil/io/replay_modbus_link.hpp"

#include <cerrno>
#include <stdexcept>
#include <string>

namespace rise::hil::io {
namespace {

// libmodbus reports a Modbus exception as errno MODBUS_ENOBASE + code
// (modbus.h: EMBXILFUN = MODBUS_ENOBASE + 1, ...).
ModbusResult classify(int rc, int err) {
  if (rc >= 0) return {};
  if (err > MODBUS_ENOBASE && err <= MODBUS_ENOBASE + MODBUS_EXCEPTION_GATEWAY_TARGET)
    return {ModbusStatus::Exception, static_cast<uint8_t>(err - MODBUS_ENOBASE)};
  switch (err) {
    case ETIMEDOUT: return {ModbusStatus::Timeout, 0};
    case EMBBADCRC: return {ModbusStatus::CrcError, 0};
    case ECONNRESET:
    case ECONNREFUSED:
    case EIO:     // the serial device (or the pty's other end) went away
    case ENXIO:
    case ENOENT:
    case EPIPE:
    case EBADF:
    case ENOTCONN: return {ModbusStatus::Disconnected, 0};
    default: return {ModbusStatus::Error, 0};
  }
}

class LibmodbusLink final : public ModbusLink {
 public:
  explicit LibmodbusLink(const ModbusAddress& a) : address_(a) {
    if (a.kind == ModbusAddress::Kind::Tcp)
      ctx_ = modbus_new_tcp(a.host.c_str(), a.port);
    else
      ctx_ = modbus_new_rtu(a.device.c_str(), a.baud, a.parity, a.data_bits, a.stop_bits);
    if (ctx_ == nullptr) throw std::invalid_argument("modbus: cannot create a context for " + a.host + a.device);
    modbus_set_slave(ctx_, a.unit);
    const auto timeout_us = static_cast<uint32_t>(a.timeout_ms) * 1000u;
    modbus_set_response_timeout(ctx_, timeout_us / 1000000u, timeout_us % 1000000u);
    // Do not reconnect behind the caller's back: it counts and backs off.
    modbus_set_error_recovery(ctx_, MODBUS_ERROR_RECOVERY_NONE);
    connect();
  }
  ~LibmodbusLink() override {
    close();
    modbus_free(ctx_);
  }
  LibmodbusLink(const LibmodbusLink&) = delete;
  LibmodbusLink& operator=(const LibmodbusLink&) = delete;

  ModbusResult read_coils(uint16_t address, std::span<uint8_t> bits) override {
    if (!open_) return count({ModbusStatus::Disconnected, 0});
    const int rc = modbus_read_bits(ctx_, address, static_cast<int>(bits.size()), bits.data());
    return finish(rc);
  }
  ModbusResult read_discrete_inputs(uint16_t address, std::span<uint8_t> bits) override {
    if (!open_) return count({ModbusStatus::Disconnected, 0});
    const int rc = modbus_read_input_bits(ctx_, address, static_cast<int>(bits.size()), bits.data());
    return finish(rc);
  }
  ModbusResult read_holding_registers(uint16_t address, std::span<uint16_t> registers) override {
    if (!open_) return count({ModbusStatus::Disconnected, 0});
    const int rc = modbus_read_registers(ctx_, address, static_cast<int>(registers.size()), registers.data());
    return finish(rc);
  }
  ModbusResult read_input_registers(uint16_t address, std::span<uint16_t> registers) override {
    if (!open_) return count({ModbusStatus::Disconnected, 0});
    const int rc =
        modbus_read_input_registers(ctx_, address, static_cast<int>(registers.size()), registers.data());
    return finish(rc);
  }
  ModbusResult write_coils(uint16_t address, std::span<const uint8_t> bits) override {
    if (!open_) return count({ModbusStatus::Disconnected, 0});
    const int rc = modbus_write_bits(ctx_, address, static_cast<int>(bits.size()), bits.data());
    return finish(rc);
  }
  ModbusResult write_registers(uint16_t address, std::span<const uint16_t> registers) override {
    if (!open_) return count({ModbusStatus::Disconnected, 0});
    const int rc = modbus_write_registers(ctx_, address, static_cast<int>(registers.size()), registers.data());
    return finish(rc);
  }

  bool is_open() const override { return open_; }
  ModbusStatus reopen() override {
    close();
    if (!connect()) return ModbusStatus::Disconnected;
    ++counters_.reopens;
    return ModbusStatus::Ok;
  }
  void close() override {
    if (open_) modbus_close(ctx_);
    open_ = false;
  }

 private:
  bool connect() {
    open_ = modbus_connect(ctx_) == 0;
    if (!open_) error_.set("%s: connect: %s", where().c_str(), modbus_strerror(errno));
    return open_;
  }
  std::string where() const {
    return address_.kind == ModbusAddress::Kind::Tcp ? "modbus+tcp://" + address_.host + ":" + std::to_string(address_.port)
                                                     : "modbus+rtu://" + address_.device;
  }
  ModbusResult finish(int rc) {
    const int err = errno;
    const ModbusResult r = count(classify(rc, err));
    if (r.status == ModbusStatus::Disconnected) {
      error_.set("%s: connection lost: %s", where().c_str(), modbus_strerror(err));
      close();
    }
    // A TCP answer that timed out may still arrive and be taken for the next
    // request's: drop the connection, as libmodbus' own recovery would.
    if (r.status == ModbusStatus::Timeout && address_.kind == ModbusAddress::Kind::Tcp) close();
    if (r.status == ModbusStatus::Timeout || r.status == ModbusStatus::CrcError) modbus_flush(ctx_);
    return r;
  }

  ModbusAddress address_;
  modbus_t* ctx_ = nullptr;
  bool open_ = false;
  detail::ErrorText error_;

 public:
  std::string last_error() const override { return error_.get(); }
};

}  // namespace

const char* to_string(ModbusStatus status) {
  switch (status) {
    case ModbusStatus::Ok: return "Ok";
    case ModbusStatus::Timeout: return "Timeout";
    case ModbusStatus::Exception: return "Exception";
    case ModbusStatus::CrcError: return "CrcError";
    case ModbusStatus::Disconnected: return "Disconnected";
    case ModbusStatus::Error: return "Error";
  }
  return "?";
}

ModbusResult ModbusLink::count(ModbusResult r) {
  ++counters_.requests;
  switch (r.status) {
    case ModbusStatus::Ok: ++counters_.ok; break;
    case ModbusStatus::Timeout: ++counters_.timeouts; break;
    case ModbusStatus::Exception: ++counters_.exceptions; break;
    case ModbusStatus::CrcError: ++counters_.crc_errors; break;
    case ModbusStatus::Disconnected: ++counters_.disconnects; break;
    case ModbusStatus::Error: ++counters_.errors; break;
  }
  return r;
}

std::unique_ptr<ModbusLink> open_modbus_link(const ModbusAddress& address) {
  if (address.listen) throw std::invalid_argument("modbus: a -listen URL is a server, not a link");
  return std::make_unique<LibmodbusLink>(address);
}

std::unique_ptr<ModbusLink> open_modbus_link(std::string_view url) {
  if (is_replay_url(url)) return open_modbus_replay(url);
  return open_modbus_link(parse_modbus_url(url));
}

}  // namespace rise::hil::io
