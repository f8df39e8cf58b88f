#include <catch2/catch.hpp>

#include <atomic>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "hil/io/can_bus.hpp"
#include "hil/io/socketcand_client.hpp"
#include "hil/io/socketcand_server.hpp"
#include "test_support.hpp"

using namespace rise::hil::io;
using rise::hil::io::test::make_fd_frame;
using rise::hil::io::test::make_frame;
using rise::hil::io::test::wait_until;

namespace {

std::string client_url(uint16_t port, const char* bus = "can0") {
  return "socketcand://127.0.0.1:" + std::to_string(port) + "/" + bus;
}

std::unique_ptr<CanBus> open_server(uint16_t port = 0) {
  return open_can_bus("socketcand+listen://127.0.0.1:" + std::to_string(port) + "/can0?settle_ms=0");
}

size_t clients_of(const CanBus& server) {
  return dynamic_cast<const SocketcandServer&>(server).client_count();
}

std::vector<CanFrame> sample_frames() {
  CanFrame rtr;
  rtr.id = 0x321;
  rtr.remote = true;
  rtr.len = 2;
  return {make_frame(0x123, {1, 2, 3}), make_frame(0x1ABCDEF0, {0xDE, 0xAD}, true),
          make_frame(0x7FF, {}), make_frame(0x5, {1, 2, 3, 4, 5, 6, 7, 8}, true), rtr,
          make_fd_frame(0x42, 64, true)};
}

}  // namespace

TEST_CASE("a socketcand client and a listen server exchange identical frames", "[hil_io]") {
  auto server = open_server();
  REQUIRE(server->is_open());
  const uint16_t port = listening_port(*server);
  REQUIRE(port != 0);
  auto client = open_can_bus(client_url(port));
  REQUIRE(client->is_open());
  CHECK(listening_port(*client) == 0);
  REQUIRE(wait_until([&] { return clients_of(*server) == 1; }));

  SECTION("client to server") {
    for (const CanFrame& f : sample_frames()) REQUIRE(client->send(f) == IoStatus::Ok);
    for (const CanFrame& f : sample_frames()) {
      CanFrame got;
      REQUIRE(server->receive(got, 2000) == IoStatus::Ok);
      CHECK(same_content(got, f));
      CHECK(got.timestamp_us > 0);
    }
  }
  SECTION("server to client, keeping the sender's timestamps") {
    int64_t stamp = 1'700'000'000'000'000;
    for (CanFrame f : sample_frames()) {
      f.timestamp_us = ++stamp;
      REQUIRE(server->send(f) == IoStatus::Ok);
    }
    stamp = 1'700'000'000'000'000;
    for (const CanFrame& f : sample_frames()) {
      CanFrame got;
      REQUIRE(client->receive(got, 2000) == IoStatus::Ok);
      CHECK(same_content(got, f));
      CHECK(got.timestamp_us == ++stamp);
    }
  }
  SECTION("server error frames reach the client as error frames") {
    CanFrame error;
    error.error = true;
    error.id = 0x4;  // CAN_ERR_CRTL
    REQUIRE(server->send(error) == IoStatus::Ok);
    CanFrame got;
    REQUIRE(client->receive(got, 2000) == IoStatus::Ok);
    CHECK(got.error);
    CHECK(got.id == 0x4);
    CHECK(client->send(error) == IoStatus::Invalid);
  }
  SECTION("nothing sent is a Timeout") {
    CanFrame got;
    CHECK(client->receive(got, 0) == IoStatus::Timeout);
    CHECK(server->receive(got, 0) == IoStatus::Timeout);
  }
}

TEST_CASE("a socketcand listen server broadcasts to every client and receives from all", "[hil_io]") {
  auto server = open_server();
  const uint16_t port = listening_port(*server);
  auto first = open_can_bus(client_url(port));
  auto second = open_can_bus(client_url(port));
  REQUIRE(wait_until([&] { return clients_of(*server) == 2; }));

  const CanFrame beacon = make_frame(0x100, {0x55});
  REQUIRE(server->send(beacon) == IoStatus::Ok);
  CanFrame got;
  REQUIRE(first->receive(got, 2000) == IoStatus::Ok);
  CHECK(same_content(got, beacon));
  REQUIRE(second->receive(got, 2000) == IoStatus::Ok);
  CHECK(same_content(got, beacon));
  CHECK(first->receive(got, 0) == IoStatus::Timeout);  // a client does not hear the other

  REQUIRE(second->send(make_frame(0x200, {2})) == IoStatus::Ok);
  REQUIRE(server->receive(got, 2000) == IoStatus::Ok);
  CHECK(got.id == 0x200);

  first.reset();
  REQUIRE(wait_until([&] { return clients_of(*server) == 1; }));
  REQUIRE(server->send(beacon) == IoStatus::Ok);
  REQUIRE(second->receive(got, 2000) == IoStatus::Ok);
  CHECK(same_content(got, beacon));
}

TEST_CASE("a socketcand server sends while its receive blocks in another thread", "[hil_io]") {
  auto server = open_server();
  auto client = open_can_bus(client_url(listening_port(*server)));
  REQUIRE(client->is_open());
  std::atomic<bool> started{false};
  IoStatus status = IoStatus::Error;
  CanFrame inbound;
  std::thread receiver([&] {
    started = true;
    status = server->receive(inbound, 10'000);
  });
  REQUIRE(wait_until([&] { return started.load(); }));
  REQUIRE(server->send(make_frame(0x11, {1})) == IoStatus::Ok);
  CanFrame got;
  const IoStatus client_status = client->receive(got, 5000);
  REQUIRE(client->send(make_frame(0x22, {2})) == IoStatus::Ok);
  receiver.join();
  CHECK(client_status == IoStatus::Ok);
  CHECK(got.id == 0x11);
  CHECK(status == IoStatus::Ok);
  CHECK(inbound.id == 0x22);
}

TEST_CASE("a socketcand client reports Disconnected when the server goes and reopens when it is back",
          "[hil_io]") {
  auto server = open_server();
  const uint16_t port = listening_port(*server);
  auto client = open_can_bus(client_url(port));
  REQUIRE(client->is_open());

  server.reset();
  CanFrame got;
  CHECK(client->receive(got, 5000) == IoStatus::Disconnected);
  CHECK_FALSE(client->is_open());
  CHECK_THAT(client->last_error(), Catch::Contains("closed"));
  CHECK(client->send(make_frame(0x1, {})) == IoStatus::Disconnected);
  CHECK(client->reopen() == IoStatus::Disconnected);

  server = open_server(port);
  REQUIRE(listening_port(*server) == port);
  REQUIRE(client->reopen() == IoStatus::Ok);
  CHECK(client->is_open());
  CHECK(client->last_error().empty());
  REQUIRE(client->send(make_frame(0x2A, {42})) == IoStatus::Ok);
  REQUIRE(server->receive(got, 2000) == IoStatus::Ok);
  CHECK(got.data[0] == 42);
}

TEST_CASE("a socketcand client of a server that is not up opens closed", "[hil_io]") {
  uint16_t port = 0;
  {
    auto gone = open_server();
    port = listening_port(*gone);
  }
  auto client = open_can_bus(client_url(port));
  CHECK_FALSE(client->is_open());
  CHECK_THAT(client->last_error(), Catch::Contains("connect"));
  CanFrame got;
  CHECK(client->receive(got, 0) == IoStatus::Disconnected);
  CHECK(client->send(make_frame(0x1, {})) == IoStatus::Disconnected);
}

TEST_CASE("a second socketcand listen server on a busy address fails with 'address in use' while the first serves",
          "[hil_io]") {
  auto first = open_server();
  const std::string address = "127.0.0.1:" + std::to_string(listening_port(*first));
  const std::string url = "socketcand+listen://" + address + "/can0";
  CHECK_THROWS_WITH(open_can_bus(url), address + ": address in use");
  // Opened by hand, reopen() says so too; it does not take another address of the host.
  SocketcandServer second(url, std::get<SocketcandAddress>(parse_can_url(url)));
  CHECK(second.reopen() == IoStatus::Error);
  CHECK_FALSE(second.is_open());
  CHECK(second.last_error() == address + ": address in use");

  auto client = open_can_bus(client_url(listening_port(*first)));
  REQUIRE(wait_until([&] { return clients_of(*first) == 1; }));
  const CanFrame beacon = make_frame(0x100, {0x55});
  REQUIRE(first->send(beacon) == IoStatus::Ok);
  CanFrame got;
  REQUIRE(client->receive(got, 2000) == IoStatus::Ok);
  CHECK(same_content(got, beacon));
}

TEST_CASE("a socketcand listen server refuses a bus it does not serve", "[hil_io]") {
  auto server = open_server();
  auto client = open_can_bus(client_url(listening_port(*server), "can1"));
  CHECK_FALSE(client->is_open());
  CHECK(client->reopen() == IoStatus::Error);
  CHECK_THAT(client->last_error(), Catch::Contains("no such bus can1"));
  CHECK(clients_of(*server) == 0);
}

TEST_CASE("a socketcand listen server answers the handshake byte-exact, one reply per request",
          "[hil_io]") {
  // python-can 4.1 reads `< hi >` and each `< ok >` with one recv() and compares exactly.
  auto server = open_can_bus("socketcand+listen://127.0.0.1:0/can0");  // default settle time
  const int fd = test::connect_loopback(listening_port(*server));
  REQUIRE(fd >= 0);
  CHECK(test::read_once(fd, 2000) == "< hi >");
  REQUIRE(test::write_text(fd, "< open can0 >"));
  CHECK(test::read_once(fd, 2000) == "< ok >");
  REQUIRE(test::write_text(fd, "< rawmode >"));
  CHECK(test::read_once(fd, 2000) == "< ok >");
  REQUIRE(test::write_text(fd, "< echo >"));
  CHECK(test::read_once(fd, 2000) == "< echo >");

  SECTION("sends, also glued together and among garbage, arrive as frames") {
    REQUIRE(test::write_text(fd, "< send 123 3 1 2 3 >junk< send 1ABCDEF0 2 de ad >< send 12 1 >"));
    CanFrame got;
    REQUIRE(server->receive(got, 2000) == IoStatus::Ok);
    CHECK(same_content(got, make_frame(0x123, {1, 2, 3})));
    REQUIRE(server->receive(got, 2000) == IoStatus::Ok);
    CHECK(same_content(got, make_frame(0x1ABCDEF0, {0xDE, 0xAD}, true)));
    CHECK(server->receive(got, 0) == IoStatus::Timeout);  // the malformed one is dropped
  }
  SECTION("frames arrive once the settle time after rawmode has passed") {
    std::string got;
    REQUIRE(wait_until([&] {
      server->send(make_frame(0x321, {1, 2}));
      got += test::read_once(fd, 10);
      return !got.empty();
    }));
    CHECK(got.rfind("< frame 321 ", 0) == 0);
    CHECK(got.find(" 0102 >") != std::string::npos);
  }
  SECTION("unknown commands get socketcand's error reply") {
    REQUIRE(test::write_text(fd, "< bcmmode >"));
    CHECK(test::read_once(fd, 2000) == "< error unknown command >");
  }
  ::close(fd);
}

TEST_CASE("a socketcand client decodes exactly the valid frames of a messy stream", "[hil_io]") {
  uint16_t port = 0;
  const int listener = test::listen_loopback(port);
  REQUIRE(listener >= 0);
  std::atomic<bool> split_done{false};
  std::atomic<bool> send_rest{false};
  std::atomic<bool> handshake_seen{false};

  // A hand-written server: the handshake, then valid messages split across
  // writes, glued together, and mixed with garbage and malformed ones.
  std::thread peer([&] {
    const int fd = ::accept(listener, nullptr, nullptr);
    if (fd < 0) return;
    test::write_text(fd, "< hi >");
    if (test::read_until(fd, "< open can0 >", 5000).find("< open can0 >") == std::string::npos) {
      ::close(fd);
      return;
    }
    test::write_text(fd, "< ok >");
    if (test::read_until(fd, "< rawmode >", 5000).find("< rawmode >") == std::string::npos) {
      ::close(fd);
      return;
    }
    handshake_seen = true;
    // The first frame glued to the last `< ok >`.
    test::write_text(fd, "< ok >< frame 111 1700000000.123456 0A1B2C >");
    test::write_text(fd,
                     "garbage>< frame XYZ 1.000000 00 ><< frame 0000001 1.5  >"
                     "< frame 7FF 2.000000 0102030405060708 >\r\n< stat 1 2 3 4 >"
                     "< frame 123 3.000000 ABC >< error 004 4.000000 >< fdframe 1ABCDEF0 01 5.000000 "
                     "000102030405060708090A0B >< rtr 10 6.000000 4 >< error unknown command >"
                     "< frame 00000010 7.000000 FF >< frame 222 8.0");
    split_done = true;
    wait_until([&] { return send_rest.load(); }, std::chrono::seconds(10));
    test::write_text(fd, "00000 EE >< frame 333 9.000000 01 >noise");
    ::close(fd);
  });

  auto client = open_can_bus(client_url(port));
  REQUIRE(client->is_open());
  CHECK(handshake_seen);

  std::vector<CanFrame> expected;
  expected.push_back(make_frame(0x111, {0x0A, 0x1B, 0x2C}));
  expected.push_back(make_frame(0x1, {}, false));
  expected.push_back(make_frame(0x7FF, {1, 2, 3, 4, 5, 6, 7, 8}));
  CanFrame error;
  error.error = true;
  error.id = 0x4;
  expected.push_back(error);
  CanFrame fd_frame = make_frame(0x1ABCDEF0, {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}, true);
  fd_frame.fd = true;
  fd_frame.brs = true;
  expected.push_back(fd_frame);
  CanFrame rtr;
  rtr.id = 0x10;
  rtr.remote = true;
  rtr.len = 4;
  expected.push_back(rtr);
  expected.push_back(make_frame(0x10, {0xFF}, true));
  expected.push_back(make_frame(0x222, {0xEE}));
  expected.push_back(make_frame(0x333, {0x01}));

  // "0000001" has 7 digits: an 11-bit id (socketcand: only 8 digits mark 29 bits).
  std::vector<CanFrame> received;
  const std::vector<int64_t> stamps{1'700'000'000'123'456, 1'500'000, 2'000'000, 4'000'000,
                                    5'000'000,             6'000'000, 7'000'000, 8'000'000,
                                    9'000'000};
  REQUIRE(wait_until([&] { return split_done.load(); }));
  for (size_t i = 0; i < expected.size(); ++i) {
    if (i == 7) send_rest = true;  // frame 222 is cut between two writes
    CanFrame got;
    REQUIRE(client->receive(got, 5000) == IoStatus::Ok);
    CAPTURE(i);
    CHECK(same_content(got, expected[i]));
    CHECK(got.timestamp_us == stamps[i]);
  }
  send_rest = true;
  CanFrame got;
  CHECK(client->receive(got, 5000) == IoStatus::Disconnected);
  CHECK(dynamic_cast<SocketcandClient&>(*client).protocol_errors() >= 3);
  peer.join();
  ::close(listener);
}
