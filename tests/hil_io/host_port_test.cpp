#include <catch2/catch.hpp>

#include <string>

#include "hil/io/host_port.hpp"

using rise::hil::io::format_host_port;
using rise::hil::io::HostPortRules;
using rise::hil::io::parse_host_port;

TEST_CASE("HOST:PORT parsing takes a host and a port 1..65535 written in digits", "[hil_io]") {
  struct Good {
    const char* text;
    const char* host;
    uint16_t port;
  };
  const auto good = GENERATE(values<Good>({{"127.0.0.1:18093", "127.0.0.1", 18093},
                                           {"host:1", "host", 1},
                                           {"console-1.lab:65535", "console-1.lab", 65535},
                                           {"[::1]:8080", "::1", 8080},
                                           {"[fe80::1]:502", "fe80::1", 502}}));
  CAPTURE(good.text);
  std::string error;
  const auto parsed = parse_host_port(good.text, &error);
  REQUIRE(parsed);
  CHECK(parsed->host == good.host);
  CHECK(parsed->port == good.port);
  CHECK(error.empty());
}

TEST_CASE("HOST:PORT parsing rejects a bad port or host with one line naming it", "[hil_io]") {
  struct Bad {
    const char* text;
    const char* why;
  };
  const auto bad = GENERATE(values<Bad>({{"127.0.0.1:abc", "port 'abc' is not a number 1..65535"},
                                         {"127.0.0.1:99999", "port '99999' is not a number 1..65535"},
                                         {"127.0.0.1:80x", "port '80x' is not a number 1..65535"},
                                         {"127.0.0.1:-1", "port '-1' is not a number 1..65535"},
                                         {"127.0.0.1:65536", "port '65536' is not a number 1..65535"},
                                         {"127.0.0.1:0", "port '0' is not a number 1..65535"},
                                         {"127.0.0.1: 80", "port ' 80' is not a number 1..65535"},
                                         {"127.0.0.1:+80", "port '+80' is not a number 1..65535"},
                                         {"127.0.0.1:", "port '' is not a number 1..65535"},
                                         {":8080", "missing host"},
                                         {"", "missing host"},
                                         {"127.0.0.1", "missing ':PORT'"},
                                         {"::1:8080", "an IPv6 host must be in brackets"},
                                         {"[::1:8080", "unterminated '['"},
                                         {"[::1]8080", "expected ':PORT' after ']'"},
                                         {"[]:8080", "missing host"},
                                         {"[::g]:8080", "host '::g' has an invalid character"},
                                         {"my host:8080", "host 'my host' has an invalid character"}}));
  CAPTURE(bad.text);
  std::string error;
  CHECK_FALSE(parse_host_port(bad.text, &error));
  CHECK_THAT(error, Catch::Contains(bad.why));
  CHECK(error.find('\n') == std::string::npos);
  CHECK_FALSE(parse_host_port(bad.text, nullptr));
}

TEST_CASE("HOST:PORT parsing takes port 0 and a left-out port only where the caller allows them", "[hil_io]") {
  std::string error;
  SECTION("port 0: any free port, for a server") {
    const auto any = parse_host_port("127.0.0.1:0", &error, {.any_port = true});
    REQUIRE(any);
    CHECK(any->port == 0);
    CHECK_FALSE(parse_host_port("127.0.0.1:65536", &error, {.any_port = true}));
    CHECK(error == "port '65536' is not a number 0..65535");
  }
  SECTION("a default port") {
    HostPortRules rules;
    rules.default_port = 502;
    CHECK(parse_host_port("10.0.0.5", &error, rules)->port == 502);
    CHECK(parse_host_port("[::1]", &error, rules)->port == 502);
    CHECK(parse_host_port("10.0.0.5:1502", &error, rules)->port == 1502);
    CHECK_FALSE(parse_host_port("10.0.0.5:", &error, rules));
  }
}

TEST_CASE("HOST:PORT is written back with an IPv6 host in brackets", "[hil_io]") {
  CHECK(format_host_port("127.0.0.1", 18093) == "127.0.0.1:18093");
  CHECK(format_host_port("::1", 8080) == "[::1]:8080");
  const auto round_trip = parse_host_port(format_host_port("fe80::2", 1), nullptr);
  REQUIRE(round_trip);
  CHECK(round_trip->host == "fe80::2");
}
