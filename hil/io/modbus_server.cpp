#include "hil/io/modbus_server.hpp"

#include <arpa/inet.h>
#include <modbus.h>
#include <netinet/in.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <stdexcept>
#include <string>
#include <vector>

#include "hil/io/host_port.hpp"

namespace rise::hil::io {
namespace {
constexpr int kSelectTimeoutUs = 20000;  // how quickly the thread notices stop
}  // namespace

ModbusServer::ModbusServer(std::string_view url, ModbusTableSizes sizes) : address_(parse_modbus_url(url)) {
  if (!address_.listen) throw std::invalid_argument("modbus server: '" + std::string(url) + "' is not a -listen URL");
  const ModbusAddress& a = address_;
  ctx_ = a.kind == ModbusAddress::Kind::Tcp ? modbus_new_tcp(a.host.c_str(), a.port)
                                            : modbus_new_rtu(a.device.c_str(), a.baud, a.parity, a.data_bits,
                                                             a.stop_bits);
  if (ctx_ == nullptr) throw std::runtime_error("modbus server: cannot create a context for " + std::string(url));
  modbus_set_slave(ctx_, a.unit);
  mapping_ = modbus_mapping_new(sizes.coils, sizes.discrete_inputs, sizes.holding_registers, sizes.input_registers);
  if (mapping_ == nullptr) {
    modbus_free(ctx_);
    throw std::runtime_error("modbus server: cannot allocate the register map");
  }
  if (a.kind == ModbusAddress::Kind::Tcp) {
    // libmodbus 3.1 sets SO_REUSEADDR only: a second server on the port fails with EADDRINUSE.
    listen_fd_ = modbus_tcp_listen(ctx_, 8);
    if (listen_fd_ < 0) {
      const int listen_errno = errno;
      modbus_mapping_free(mapping_);
      modbus_free(ctx_);
      if (listen_errno == EADDRINUSE) throw std::runtime_error(format_host_port(a.host, a.port) + ": address in use");
      throw std::runtime_error("modbus server: cannot listen on " + std::string(url) + ": " + modbus_strerror(listen_errno));
    }
    sockaddr_in bound{};
    socklen_t size = sizeof bound;
    if (::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&bound), &size) == 0) port_ = ntohs(bound.sin_port);
    thread_ = std::thread([this] { serve_tcp(); });
  } else {
    if (modbus_connect(ctx_) != 0) {
      const std::string why = modbus_strerror(errno);
      modbus_mapping_free(mapping_);
      modbus_free(ctx_);
      throw std::runtime_error("modbus server: cannot open " + a.device + ": " + why);
    }
    thread_ = std::thread([this] { serve_rtu(); });
  }
}

ModbusServer::~ModbusServer() {
  running_ = false;
  if (thread_.joinable()) thread_.join();
  if (listen_fd_ >= 0) ::close(listen_fd_);
  modbus_close(ctx_);
  modbus_mapping_free(mapping_);
  modbus_free(ctx_);
}

void ModbusServer::set_inputs(std::span<const uint16_t> input_registers, uint32_t discrete_bits) {
  std::lock_guard lock(mutex_);
  const auto n = std::min<std::size_t>(input_registers.size(), static_cast<std::size_t>(mapping_->nb_input_registers));
  std::copy_n(input_registers.begin(), n, mapping_->tab_input_registers);
  const auto bits = std::min<std::size_t>(32, static_cast<std::size_t>(mapping_->nb_input_bits));
  for (std::size_t i = 0; i < bits; ++i) mapping_->tab_input_bits[i] = static_cast<uint8_t>((discrete_bits >> i) & 1u);
}

uint32_t ModbusServer::coil_bits() const {
  std::lock_guard lock(mutex_);
  uint32_t bits = 0;
  const auto n = std::min<std::size_t>(32, static_cast<std::size_t>(mapping_->nb_bits));
  for (std::size_t i = 0; i < n; ++i)
    if (mapping_->tab_bits[i] != 0) bits |= 1u << i;
  return bits;
}

void ModbusServer::holding_registers(std::span<uint16_t> out) const {
  std::lock_guard lock(mutex_);
  const auto n = std::min<std::size_t>(out.size(), static_cast<std::size_t>(mapping_->nb_registers));
  std::copy_n(mapping_->tab_registers, n, out.begin());
}

template <typename T>
void ModbusServer::put(T* table, int size, uint16_t address, std::span<const T> from) {
  std::lock_guard lock(mutex_);  // the table pointers themselves never change
  for (std::size_t i = 0; i < from.size() && address + i < static_cast<std::size_t>(size); ++i)
    table[address + i] = from[i];
}

void ModbusServer::set_coils(uint16_t a, std::span<const uint8_t> b) { put(mapping_->tab_bits, mapping_->nb_bits, a, b); }
void ModbusServer::set_discrete_inputs(uint16_t a, std::span<const uint8_t> b) {
  put(mapping_->tab_input_bits, mapping_->nb_input_bits, a, b);
}
void ModbusServer::set_holding_registers(uint16_t a, std::span<const uint16_t> r) {
  put(mapping_->tab_registers, mapping_->nb_registers, a, r);
}
void ModbusServer::set_input_registers(uint16_t a, std::span<const uint16_t> r) {
  put(mapping_->tab_input_registers, mapping_->nb_input_registers, a, r);
}

void ModbusServer::coils(uint16_t address, std::span<uint8_t> out) const {
  std::lock_guard lock(mutex_);
  for (std::size_t i = 0; i < out.size(); ++i)
    out[i] = address + i < static_cast<std::size_t>(mapping_->nb_bits) ? mapping_->tab_bits[address + i] : 0;
}

void ModbusServer::reply(const uint8_t* query, int length) {
  const int offset = modbus_get_header_length(ctx_);
  const uint8_t function = query[offset];
  // Counted before the reply goes out, so a client that got its answer
  // sees the counters include it; the lock makes readers of the counter
  // wait for the tables modbus_reply() updates.
  std::lock_guard lock(mutex_);
  ++requests_;
  if (function == 0x05 || function == 0x06 || function == 0x0F || function == 0x10) ++writes_;
  modbus_reply(ctx_, query, length, mapping_);
}

// Several clients at once with select(), as libmodbus'
// tests/bandwidth-server-many-up.c does; one context, its socket switched
// to the client being served.
void ModbusServer::serve_tcp() {
  std::vector<int> clients;
  std::vector<uint8_t> query(MODBUS_TCP_MAX_ADU_LENGTH);
  while (running_) {
    fd_set readable;
    FD_ZERO(&readable);
    FD_SET(listen_fd_, &readable);
    int max_fd = listen_fd_;
    for (int fd : clients) {
      FD_SET(fd, &readable);
      max_fd = std::max(max_fd, fd);
    }
    timeval tv{0, kSelectTimeoutUs};
    if (::select(max_fd + 1, &readable, nullptr, nullptr, &tv) <= 0) continue;
    if (FD_ISSET(listen_fd_, &readable)) {
      const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
      if (fd >= 0) clients.push_back(fd);
    }
    for (auto it = clients.begin(); it != clients.end();) {
      if (!FD_ISSET(*it, &readable)) {
        ++it;
        continue;
      }
      modbus_set_socket(ctx_, *it);
      const int rc = modbus_receive(ctx_, query.data());
      if (rc > 0) reply(query.data(), rc);
      if (rc == -1) {
        ::close(*it);
        it = clients.erase(it);
      } else {
        ++it;
      }
    }
  }
  for (int fd : clients) ::close(fd);
  modbus_set_socket(ctx_, -1);
}

void ModbusServer::serve_rtu() {
  std::vector<uint8_t> query(MODBUS_RTU_MAX_ADU_LENGTH);
  int fd = modbus_get_socket(ctx_);
  while (running_) {
    if (fd < 0) {
      // The device went away (USB adapter unplugged, pty peer gone): reopen
      // it by name every kReopenUs until it is back.
      constexpr int kReopenUs = 100000;
      ::usleep(kReopenUs);
      if (modbus_connect(ctx_) == 0) fd = modbus_get_socket(ctx_);
      continue;
    }
    fd_set readable;
    FD_ZERO(&readable);
    FD_SET(fd, &readable);
    timeval tv{0, kSelectTimeoutUs};
    if (::select(fd + 1, &readable, nullptr, nullptr, &tv) <= 0) continue;
    const int rc = modbus_receive(ctx_, query.data());
    if (rc > 0) reply(query.data(), rc);
    // rc == -1 with a bad CRC or a broken frame: libmodbus flushed it, go on.
    if (rc == -1 && (errno == EIO || errno == ECONNRESET || errno == EBADF || errno == ENXIO)) {
      modbus_close(ctx_);
      fd = -1;
    }
  }
}

}  // namespace rise::hil::io
