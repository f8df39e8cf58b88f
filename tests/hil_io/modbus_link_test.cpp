// libmodbus client (ModbusLink) against our ModbusServer: TCP on 127.0.0.1
// and RTU over a socat pty pair.

#include <catch2/catch.hpp>

#include <unistd.h>

#include <array>
#include <filesystem>
#include <stdexcept>

#include "hil/io/modbus_link.hpp"
#include "hil/io/modbus_server.hpp"
#include "tests/hil_io/test_support.hpp"
#include "tests/socat_ptys.hpp"

namespace {
using rise::hil::io::ModbusServer;
using rise::hil::io::ModbusStatus;

// Fills the server with a recognisable block.
void fill(ModbusServer& server) {
  std::array<uint16_t, 18> regs{};
  for (std::size_t i = 0; i < regs.size(); ++i) regs[i] = static_cast<uint16_t>(0x1000 + i);
  server.set_inputs(regs, 0x80000005u);
}

std::string tcp_url(const ModbusServer& server, int timeout_ms = 200) {
  return "modbus+tcp://127.0.0.1:" + std::to_string(server.port()) + "?unit=1&timeout_ms=" + std::to_string(timeout_ms);
}
}  // namespace

TEST_CASE("modbus URLs parse into their address and reject mistakes", "[hil_io]") {
  using rise::hil::io::ModbusAddress;
  SECTION("good URLs") {
    const auto tcp = rise::hil::io::parse_modbus_url("modbus+tcp://10.0.0.5:1502?unit=7&timeout_ms=30");
    CHECK(tcp.kind == ModbusAddress::Kind::Tcp);
    CHECK(tcp.host == "10.0.0.5");
    CHECK(tcp.port == 1502);
    CHECK(tcp.unit == 7);
    CHECK(tcp.timeout_ms == 30);
    CHECK_FALSE(tcp.listen);
    const auto rtu = rise::hil::io::parse_modbus_url("modbus+rtu:///dev/ttyUSB0?baud=115200&parity=N&data=8&stop=2&unit=3");
    CHECK(rtu.kind == ModbusAddress::Kind::Rtu);
    CHECK(rtu.device == "/dev/ttyUSB0");
    CHECK(rtu.baud == 115200);
    CHECK(rtu.parity == 'N');
    CHECK(rtu.stop_bits == 2);
    CHECK(rtu.unit == 3);
    CHECK(rise::hil::io::parse_modbus_url("modbus+tcp-listen://127.0.0.1:0").listen);
    CHECK(rise::hil::io::is_modbus_url("modbus+rtu-listen:///dev/pts/4"));
    CHECK_FALSE(rise::hil::io::is_modbus_url("socketcan://can0"));
  }
  SECTION("bad URLs") {
    const auto bad = GENERATE(as<std::string>{}, "modbus+udp://h:1", "modbus+tcp://:502", "modbus+tcp://h:0",
                              "modbus+tcp://h:1?unit=300", "modbus+tcp://h:1?baud=9600", "modbus+rtu://dev",
                              "modbus+rtu:///dev/x?parity=X", "modbus+tcp://h:1?unit");
    CHECK_THROWS_AS(rise::hil::io::parse_modbus_url(bad), std::invalid_argument);
  }
}

TEST_CASE("modbus TCP URLs reject the ports HOST:PORT parsing rejects, naming the port", "[hil_io]") {
  const std::string port = GENERATE(as<std::string>{}, "abc", "99999", "80x", "-1", "65536", "", " 1");
  for (const std::string scheme : {"modbus+tcp", "modbus+tcp-listen"}) {
    const std::string url = scheme + "://127.0.0.1:" + port + "?unit=1";
    CAPTURE(url);
    CHECK_THROWS_WITH(rise::hil::io::parse_modbus_url(url),
                      Catch::Contains("'" + url + "': port '" + port + "' is not a number"));
  }
  SECTION("port 0 is any free port for a server only; no port is 502") {
    CHECK(rise::hil::io::parse_modbus_url("modbus+tcp-listen://127.0.0.1:0").port == 0);
    CHECK_THROWS_WITH(rise::hil::io::parse_modbus_url("modbus+tcp://127.0.0.1:0"),
                      Catch::Contains("port '0' is not a number 1..65535"));
    CHECK(rise::hil::io::parse_modbus_url("modbus+tcp://10.0.0.5?unit=2").port == 502);
  }
}

TEST_CASE("a second modbus TCP server on a busy address fails with 'address in use' while the first serves",
          "[hil_io]") {
  ModbusServer first("modbus+tcp-listen://127.0.0.1:0?unit=1", {});
  REQUIRE(first.port() != 0);
  fill(first);
  const std::string address = "127.0.0.1:" + std::to_string(first.port());
  CHECK_THROWS_WITH(ModbusServer("modbus+tcp-listen://" + address + "?unit=1", {}), address + ": address in use");
  auto link = rise::hil::io::open_modbus_link(tcp_url(first));
  std::array<uint16_t, 18> regs{};
  REQUIRE(link->read_input_registers(0, regs).ok());
  CHECK(regs[0] == 0x1000);
  CHECK(first.requests_served() == 1);
}

TEST_CASE("a libmodbus TCP client reads the inputs our server holds and writes its feedback", "[hil_io]") {
  ModbusServer server("modbus+tcp-listen://127.0.0.1:0?unit=1", {});
  REQUIRE(server.port() != 0);
  fill(server);
  auto link = rise::hil::io::open_modbus_link(tcp_url(server));
  REQUIRE(link->is_open());

  SECTION("reads") {
    std::array<uint16_t, 18> regs{};
    REQUIRE(link->read_input_registers(0, regs).ok());
    CHECK(regs[0] == 0x1000);
    CHECK(regs[17] == 0x1011);
    std::array<uint8_t, 32> bits{};
    REQUIRE(link->read_discrete_inputs(0, bits).ok());
    CHECK(bits[0] == 1);
    CHECK(bits[1] == 0);
    CHECK(bits[2] == 1);
    CHECK(bits[31] == 1);
    CHECK(link->counters().ok == 2);
  }
  SECTION("writes") {
    std::array<uint8_t, 32> coils{};
    coils[3] = coils[31] = 1;
    REQUIRE(link->write_coils(0, coils).ok());
    std::array<uint16_t, 25> holding{};
    holding[0] = 2;
    holding[24] = 0xBEEF;
    REQUIRE(link->write_registers(0, holding).ok());
    CHECK(server.coil_bits() == ((1u << 3) | (1u << 31)));
    std::array<uint16_t, 25> back{};
    server.holding_registers(back);
    CHECK(back == holding);
    CHECK(server.writes_served() == 2);
  }
  SECTION("a read beyond the map is an exception with its code kept") {
    std::array<uint16_t, 4> regs{};
    const auto r = link->read_input_registers(16, regs);
    CHECK(r.status == ModbusStatus::Exception);
    CHECK(r.exception_code == 2);  // ILLEGAL DATA ADDRESS
    CHECK(link->counters().exceptions == 1);
    CHECK(link->is_open());  // an exception is an answer: the link stays up
  }
  SECTION("two clients are served at once") {
    auto second = rise::hil::io::open_modbus_link(tcp_url(server));
    std::array<uint16_t, 2> a{}, b{};
    CHECK(link->read_input_registers(0, a).ok());
    CHECK(second->read_input_registers(1, b).ok());
    CHECK(b[0] == 0x1001);
  }
}

TEST_CASE("a modbus link to a server that went away reports Disconnected and reopens when it is back",
          "[hil_io]") {
  auto server = std::make_unique<ModbusServer>("modbus+tcp-listen://127.0.0.1:0?unit=1", rise::hil::io::ModbusTableSizes{});
  const uint16_t port = server->port();
  fill(*server);
  auto link = rise::hil::io::open_modbus_link(tcp_url(*server));
  std::array<uint16_t, 18> regs{};
  REQUIRE(link->read_input_registers(0, regs).ok());

  server.reset();
  const auto lost = link->read_input_registers(0, regs);
  CHECK((lost.status == ModbusStatus::Disconnected || lost.status == ModbusStatus::Timeout));
  CHECK_FALSE(link->is_open());
  CHECK(link->reopen() == ModbusStatus::Disconnected);  // nobody listens
  // Why, for SourceHealth.down_reason: the address and the OS's error.
  CHECK(link->last_error() == "modbus+tcp://127.0.0.1:" + std::to_string(port) + ": connect: Connection refused");
  CHECK(link->read_input_registers(0, regs).status == ModbusStatus::Disconnected);

  server = std::make_unique<ModbusServer>("modbus+tcp-listen://127.0.0.1:" + std::to_string(port) + "?unit=1",
                                          rise::hil::io::ModbusTableSizes{});
  fill(*server);
  REQUIRE(link->reopen() == ModbusStatus::Ok);
  CHECK(link->read_input_registers(0, regs).ok());
  CHECK(regs[5] == 0x1005);
  CHECK(link->counters().reopens == 1);
}

TEST_CASE("a libmodbus RTU client reads our RTU server across a socat pty pair", "[hil_io]") {
  if (!rise::test::have_socat()) {
    WARN("socat not installed: RTU test skipped");
    return;
  }
  const std::string dir = std::filesystem::temp_directory_path() / ("rise-rtu-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string server_end = dir + "/server", client_end = dir + "/client";
  rise::test::SocatPtys socat(server_end, client_end, dir + "/socat.log");
  REQUIRE(socat.ready());

  ModbusServer server("modbus+rtu-listen://" + server_end + "?baud=115200&unit=5", {});
  fill(server);
  auto link = rise::hil::io::open_modbus_link("modbus+rtu://" + client_end + "?baud=115200&unit=5&timeout_ms=500");
  REQUIRE(link->is_open());
  std::array<uint16_t, 18> regs{};
  REQUIRE(link->read_input_registers(0, regs).ok());
  CHECK(regs[17] == 0x1011);
  std::array<uint8_t, 32> coils{};
  coils[7] = 1;
  REQUIRE(link->write_coils(0, coils).ok());
  CHECK(server.coil_bits() == (1u << 7));

  SECTION("another unit's request gets no answer: Timeout") {
    link->close();  // one opener of the pty end at a time
    auto other = rise::hil::io::open_modbus_link("modbus+rtu://" + client_end + "?baud=115200&unit=6&timeout_ms=100");
    REQUIRE(other->is_open());
    CHECK(other->read_input_registers(0, regs).status == ModbusStatus::Timeout);
  }
  std::filesystem::remove_all(dir);
}

TEST_CASE("a modbus TCP peer that accepts but never answers is a Timeout, and the link restarts clean",
          "[hil_io]") {
  uint16_t port = 0;
  const int listener = rise::hil::io::test::listen_loopback(port);
  REQUIRE(listener >= 0);
  auto link = rise::hil::io::open_modbus_link("modbus+tcp://127.0.0.1:" + std::to_string(port) + "?unit=1&timeout_ms=30");
  REQUIRE(link->is_open());  // the kernel completes the handshake from the backlog
  std::array<uint16_t, 18> regs{};
  CHECK(link->read_input_registers(0, regs).status == ModbusStatus::Timeout);
  CHECK(link->counters().timeouts == 1);
  // A late answer must not be read as the next request's: the link closed.
  CHECK_FALSE(link->is_open());
  CHECK(link->reopen() == ModbusStatus::Ok);
  ::close(listener);
}
