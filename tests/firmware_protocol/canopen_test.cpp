#include "firmware_protocol/canopen.hpp"

#include <catch2/catch.hpp>

#include <vector>

namespace co = rise::firmware_protocol::canopen;

namespace {
std::vector<uint8_t> bytes(const co::Frame& f) { return {f.data.begin(), f.data.begin() + f.len}; }
}  // namespace

TEST_CASE("NMT, SYNC and heartbeat frames carry the bytes of CiA 301", "[firmware_protocol][canopen]") {
  // CiA 301 §7.2.8.3.1: COB-ID 0, byte 0 the command specifier, byte 1 the node id.
  const co::Frame start = co::nmt_frame(co::NmtCommand::Start, 5);
  CHECK(start.cob_id == 0x000);
  CHECK(bytes(start) == std::vector<uint8_t>{0x01, 0x05});
  CHECK(bytes(co::nmt_frame(co::NmtCommand::ResetCommunication, 0x7F)) == std::vector<uint8_t>{0x82, 0x7F});
  CHECK(bytes(co::nmt_frame(co::NmtCommand::EnterPreOperational, 0)) == std::vector<uint8_t>{0x80, 0x00});
  // §7.2.5: SYNC without a counter is an empty frame on 0x080.
  CHECK(co::sync_frame().cob_id == 0x080);
  CHECK(co::sync_frame().len == 0);
  // §7.2.8.3.2.3: heartbeat 0x700 + node id, one byte: the state.
  const co::Frame hb = co::heartbeat_frame(5, co::NmtState::PreOperational);
  CHECK(hb.cob_id == 0x705);
  CHECK(bytes(hb) == std::vector<uint8_t>{0x7F});
  CHECK(co::default_tpdo_cob_id(1, 5) == 0x185);
  CHECK(co::default_tpdo_cob_id(4, 5) == 0x485);
  CHECK(co::default_rpdo_cob_id(1, 5) == 0x205);
  CHECK(co::default_tpdo_cob_id(5, 5) == 0);
}

TEST_CASE("a heartbeat is read for its node only, one byte of a known state", "[firmware_protocol][canopen]") {
  const uint8_t op[] = {0x05}, boot[] = {0x00}, preop[] = {0x7F}, stopped[] = {0x04};
  CHECK(co::read_heartbeat(5, 0x705, op).read == co::HeartbeatRead::Ok);
  CHECK(co::read_heartbeat(5, 0x705, op).state == co::NmtState::Operational);
  CHECK(co::read_heartbeat(5, 0x705, boot).state == co::NmtState::BootUp);
  CHECK(co::read_heartbeat(5, 0x705, preop).state == co::NmtState::PreOperational);
  CHECK(co::read_heartbeat(5, 0x705, stopped).state == co::NmtState::Stopped);
  SECTION("another node's heartbeat is not this node's") {
    CHECK(co::read_heartbeat(5, 0x706, op).read == co::HeartbeatRead::NotHeartbeat);
    CHECK(co::read_heartbeat(5, 0x185, op).read == co::HeartbeatRead::NotHeartbeat);
  }
  SECTION("a wrong length or an unknown state is refused") {
    const uint8_t two[] = {0x05, 0x00}, toggled[] = {0x85}, unknown[] = {0x01};
    CHECK(co::read_heartbeat(5, 0x705, two).read == co::HeartbeatRead::BadLength);
    CHECK(co::read_heartbeat(5, 0x705, {}).read == co::HeartbeatRead::BadLength);
    CHECK(co::read_heartbeat(5, 0x705, toggled).read == co::HeartbeatRead::BadState);
    CHECK(co::read_heartbeat(5, 0x705, unknown).read == co::HeartbeatRead::BadState);
  }
}

TEST_CASE("a node reads NMT commands addressed to it or to all", "[firmware_protocol][canopen]") {
  const uint8_t start5[] = {0x01, 0x05}, start_all[] = {0x01, 0x00}, bad[] = {0x03, 0x05}, short_[] = {0x01};
  CHECK(co::read_nmt(0, start5).addresses(5));
  CHECK_FALSE(co::read_nmt(0, start5).addresses(6));
  CHECK(co::read_nmt(0, start_all).addresses(6));
  CHECK_FALSE(co::read_nmt(0, bad).ok);
  CHECK_FALSE(co::read_nmt(0, short_).ok);
  CHECK_FALSE(co::read_nmt(0x80, start5).ok);
  CHECK(co::next_state(co::NmtState::PreOperational, co::NmtCommand::Start) == co::NmtState::Operational);
  CHECK(co::next_state(co::NmtState::Operational, co::NmtCommand::Stop) == co::NmtState::Stopped);
  CHECK(co::next_state(co::NmtState::Operational, co::NmtCommand::ResetNode) == co::NmtState::BootUp);
  CHECK(co::next_state(co::NmtState::Stopped, co::NmtCommand::EnterPreOperational) == co::NmtState::PreOperational);
}

TEST_CASE("the NMT master resets the node at open and starts it on boot-up", "[firmware_protocol][canopen]") {
  co::NmtMaster master(5, 150000, 0);
  master.opened(1000);
  auto first = master.next(1000);
  REQUIRE(first);
  CHECK(bytes(*first) == std::vector<uint8_t>{0x82, 0x05});  // reset communication
  CHECK_FALSE(master.next(1000));
  const uint8_t boot[] = {0x00}, op[] = {0x05}, preop[] = {0x7F};
  master.on_frame(0x705, boot, 2000);
  auto start = master.next(2000);
  REQUIRE(start);
  CHECK(bytes(*start) == std::vector<uint8_t>{0x01, 0x05});
  CHECK(master.starts_sent() == 1);
  master.on_frame(0x705, op, 3000);
  CHECK(master.state() == co::NmtState::Operational);
  CHECK_FALSE(master.next(3000));

  SECTION("a node that leaves Operational on its own is not started while it is heard") {
    master.on_frame(0x705, preop, 100000);
    CHECK(master.state() == co::NmtState::PreOperational);
    CHECK_FALSE(master.next(100000));
    master.on_frame(0x705, preop, 200000);
    CHECK_FALSE(master.next(200000));
  }
  SECTION("a node whose heartbeat returns after the consumer time, not Operational, is started") {
    master.on_frame(0x705, preop, 3000 + 150001);
    const auto again = master.next(3000 + 150001);
    REQUIRE(again);
    CHECK(bytes(*again) == std::vector<uint8_t>{0x01, 0x05});
  }
  SECTION("a node that returns Operational needs nothing") {
    master.on_frame(0x705, op, 3000 + 500000);
    CHECK_FALSE(master.next(3000 + 500000));
  }
  SECTION("another node's boot-up starts nothing") {
    master.on_frame(0x706, boot, 4000);
    CHECK_FALSE(master.next(4000));
  }
}

TEST_CASE("the NMT master sends SYNC every period without bursts after a stall", "[firmware_protocol][canopen]") {
  co::NmtMaster master(5, 150000, 10000);
  master.opened(0);
  CHECK(master.next(0)->cob_id == 0x000);  // the reset first
  auto sync = master.next(0);
  REQUIRE(sync);
  CHECK(sync->cob_id == 0x080);
  CHECK(sync->len == 0);
  CHECK_FALSE(master.next(5000));
  CHECK(master.next_due_us() == 10000);
  CHECK(master.next(10000));
  // Stalled for 55 ms: one SYNC now, the next a period later.
  CHECK(master.next(65000));
  CHECK_FALSE(master.next(65000));
  CHECK(master.next_due_us() == 75000);
  CHECK(master.syncs_sent() == 3);
  co::NmtMaster without(5, 150000, 0);
  without.opened(0);
  (void)without.next(0);
  CHECK_FALSE(without.next(1000000));
}
