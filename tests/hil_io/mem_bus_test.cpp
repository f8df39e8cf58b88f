#include <catch2/catch.hpp>

#include <atomic>
#include <thread>

#include "hil/io/can_bus.hpp"
#include "hil/io/mem_bus.hpp"
#include "test_support.hpp"

using namespace rise::hil::io;
using rise::hil::io::test::make_fd_frame;
using rise::hil::io::test::make_frame;

TEST_CASE("mem buses of one name see each other's frames but not their own", "[hil_io]") {
  auto a = open_can_bus("mem://wire1");
  auto b = open_can_bus("mem://wire1");
  auto c = open_can_bus("mem://wire1");
  auto other = open_can_bus("mem://wire2");
  REQUIRE(a->is_open());
  CHECK(listening_port(*a) == 0);

  const CanFrame sent = make_frame(0x123, {1, 2, 3});
  REQUIRE(a->send(sent) == IoStatus::Ok);
  CanFrame got;
  REQUIRE(b->receive(got, 1000) == IoStatus::Ok);
  CHECK(same_content(got, sent));
  CHECK(got.timestamp_us > 0);
  REQUIRE(c->receive(got, 1000) == IoStatus::Ok);
  CHECK(same_content(got, sent));
  CHECK(a->receive(got, 0) == IoStatus::Timeout);
  CHECK(other->receive(got, 0) == IoStatus::Timeout);

  const CanFrame reply = make_frame(0x1ABCDEF0, {0xDE, 0xAD}, true);
  REQUIRE(b->send(reply) == IoStatus::Ok);
  REQUIRE(a->receive(got, 1000) == IoStatus::Ok);
  CHECK(same_content(got, reply));
  CHECK(b->receive(got, 0) == IoStatus::Timeout);
}

TEST_CASE("a mem bus receive with nothing sent returns Timeout", "[hil_io]") {
  auto a = open_can_bus("mem://quiet");
  CanFrame got;
  CHECK(a->receive(got, 0) == IoStatus::Timeout);
  CHECK(a->receive(got, 10) == IoStatus::Timeout);
}

TEST_CASE("a mem bus carries CAN FD frames and rejects frames no bus can carry", "[hil_io]") {
  auto a = open_can_bus("mem://fd");
  auto b = open_can_bus("mem://fd");
  SECTION("a 64-byte FD frame with bit-rate switch arrives whole") {
    const CanFrame sent = make_fd_frame(0x456, 64, true);
    REQUIRE(a->send(sent) == IoStatus::Ok);
    CanFrame got;
    REQUIRE(b->receive(got, 1000) == IoStatus::Ok);
    CHECK(same_content(got, sent));
    CHECK(got.data[63] == sent.data[63]);
  }
  SECTION("bad frames are Invalid") {
    CanFrame nine = make_frame(0x1, {1, 2, 3, 4, 5, 6, 7, 8});
    nine.len = 9;
    CHECK(a->send(nine) == IoStatus::Invalid);
    CHECK(a->send(make_frame(0x800, {})) == IoStatus::Invalid);
    CHECK(a->send(make_fd_frame(0x1, 13, false)) == IoStatus::Invalid);
    CanFrame got;
    CHECK(b->receive(got, 0) == IoStatus::Timeout);
  }
}

TEST_CASE("a mem bus that does not read drops the frames its queue cannot hold", "[hil_io]") {
  MemBus sender("mem://small", "small");
  MemBus reader("mem://small", "small", 4);
  for (uint8_t i = 0; i < 6; ++i) REQUIRE(sender.send(make_frame(0x10, {i})) == IoStatus::Ok);
  CHECK(reader.dropped() == 2);
  CanFrame got;
  for (uint8_t i = 0; i < 4; ++i) {
    REQUIRE(reader.receive(got, 0) == IoStatus::Ok);
    CHECK(got.data[0] == i);  // oldest kept, newest dropped
  }
  CHECK(reader.receive(got, 0) == IoStatus::Timeout);
}

TEST_CASE("a mem bus wakes a receiver blocked in another thread", "[hil_io]") {
  auto a = open_can_bus("mem://threads");
  auto b = open_can_bus("mem://threads");
  std::atomic<bool> started{false};
  IoStatus status = IoStatus::Error;
  CanFrame got;
  std::thread receiver([&] {
    started = true;
    status = b->receive(got, 10'000);
  });
  REQUIRE(rise::hil::io::test::wait_until([&] { return started.load(); }));
  REQUIRE(a->send(make_frame(0x77, {7})) == IoStatus::Ok);
  receiver.join();
  CHECK(status == IoStatus::Ok);
  CHECK(got.id == 0x77);
}
