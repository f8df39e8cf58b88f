#include <catch2/catch.hpp>

#include <stdexcept>
#include <string>

#include "hil/io/can_bus.hpp"
#include "hil/io/can_url.hpp"

using namespace rise::hil::io;

TEST_CASE("socketcan URLs give the interface and its raw filters", "[hil_io]") {
  SECTION("a plain interface has no filters") {
    const auto a = std::get<SocketCanAddress>(parse_can_url("socketcan://can0"));
    CHECK(a.interface == "can0");
    CHECK(a.filters.empty());
  }
  SECTION("filters are hex ID:MASK, 8 digits or above 7FF meaning a 29-bit id") {
    const auto a = std::get<SocketCanAddress>(
        parse_can_url("socketcan://vcan0?filter=123:7FF,1ABCDEF0:1FFFFFFF,00000010:FF"));
    REQUIRE(a.filters.size() == 3);
    CHECK(a.filters[0].id == 0x123);
    CHECK(a.filters[0].mask == 0x7FF);
    CHECK_FALSE(a.filters[0].extended);
    CHECK(a.filters[1].id == 0x1ABCDEF0);
    CHECK(a.filters[1].extended);
    CHECK(a.filters[2].id == 0x10);
    CHECK(a.filters[2].extended);
  }
  SECTION("the scheme is case-insensitive") {
    CHECK(std::get<SocketCanAddress>(parse_can_url("SocketCAN://slcan0")).interface == "slcan0");
  }
}

TEST_CASE("socketcand URLs give host, port and bus", "[hil_io]") {
  SECTION("client") {
    const auto a = std::get<SocketcandAddress>(parse_can_url("socketcand://127.0.0.1:29536/can0"));
    CHECK_FALSE(a.listen);
    CHECK(a.host == "127.0.0.1");
    CHECK(a.port == 29536);
    CHECK(a.bus == "can0");
  }
  SECTION("bracketed IPv6 host and host names") {
    CHECK(std::get<SocketcandAddress>(parse_can_url("socketcand://[::1]:1/can0")).host == "::1");
    CHECK(std::get<SocketcandAddress>(parse_can_url("socketcand://console-1.lab:80/vcan_1")).host ==
          "console-1.lab");
  }
  SECTION("server with an ephemeral port and a settle time") {
    const auto a = std::get<SocketcandAddress>(
        parse_can_url("socketcand+listen://0.0.0.0:0/can0?settle_ms=0"));
    CHECK(a.listen);
    CHECK(a.port == 0);
    CHECK(a.settle_ms == 0);
    CHECK(std::get<SocketcandAddress>(parse_can_url("socketcand+listen://0.0.0.0:0/can0")).settle_ms ==
          200);
  }
}

TEST_CASE("mem URLs give the shared bus name", "[hil_io]") {
  CHECK(std::get<MemAddress>(parse_can_url("mem://panel.a-1_x")).name == "panel.a-1_x");
}

TEST_CASE("malformed CAN bus URLs are rejected with a message naming the URL", "[hil_io]") {
  const std::string url = GENERATE(as<std::string>{},
      "", "can0", "://can0", "foo://x", "socketcan:/can0",
      "socketcan://", "socketcan://averyveryverylong0", "socketcan://can/0", "socketcan://can 0",
      "socketcan://can0?", "socketcan://can0?filter=", "socketcan://can0?filter=123",
      "socketcan://can0?filter=XYZ:7FF", "socketcan://can0?filter=123:FFF",
      "socketcan://can0?filter=20000000:1FFFFFFF", "socketcan://can0?filter=123:7FF,",
      "socketcan://can0?bitrate=500000", "socketcan://can0?filter=1:7FF&filter=2:7FF",
      "socketcand://host/can0", "socketcand://host:0/can0", "socketcand://host:65536/can0",
      "socketcand://host:12x/can0", "socketcand://:29536/can0", "socketcand://host:29536",
      "socketcand://host:29536/", "socketcand://host:29536/can<0>", "socketcand://h:1/a_bus_name_of_17c",
      "socketcand://::1:29536/can0", "socketcand://[::1:29536/can0", "socketcand://h:1/can0?settle_ms=5",
      "socketcand+listen://h:0/can0?settle_ms=abc", "socketcand+listen://h:0/can0?settle_ms=99999",
      "mem://", "mem://a b", "mem://x?y=1");
  CAPTURE(url);
  try {
    parse_can_url(url);
    FAIL("accepted");
  } catch (const std::invalid_argument& e) {
    CHECK_THAT(e.what(), Catch::Contains("'" + url + "'"));
  }
  CHECK_THROWS_AS(open_can_bus(url), std::invalid_argument);
}

TEST_CASE("socketcand URLs reject the ports HOST:PORT parsing rejects, naming the port", "[hil_io]") {
  const std::string port = GENERATE(as<std::string>{}, "abc", "99999", "80x", "-1", "65536", "", " 1");
  for (const std::string scheme : {"socketcand", "socketcand+listen"}) {
    const std::string url = scheme + "://127.0.0.1:" + port + "/can0";
    CAPTURE(url);
    CHECK_THROWS_WITH(parse_can_url(url), Catch::Contains("'" + url + "': port '" + port + "' is not a number"));
  }
  SECTION("port 0 is any free port for a server only") {
    CHECK(std::get<SocketcandAddress>(parse_can_url("socketcand+listen://127.0.0.1:0/can0")).port == 0);
    CHECK_THROWS_WITH(parse_can_url("socketcand://127.0.0.1:0/can0"),
                      Catch::Contains("port '0' is not a number 1..65535"));
  }
}

TEST_CASE("every IoStatus has a name", "[hil_io]") {
  CHECK(std::string(to_string(IoStatus::Ok)) == "ok");
  CHECK(std::string(to_string(IoStatus::Timeout)) == "timeout");
  CHECK(std::string(to_string(IoStatus::Disconnected)) == "disconnected");
  CHECK(std::string(to_string(IoStatus::Invalid)) == "invalid");
  CHECK(std::string(to_string(IoStatus::Error)) == "error");
}
