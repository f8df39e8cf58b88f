#include "firmware_protocol/j1939.hpp"

#include <catch2/catch.hpp>

#include <array>
#include <numeric>
#include <vector>

namespace j = rise::firmware_protocol::j1939;

namespace {

constexpr uint8_t kConsole = 0x21;
constexpr uint8_t kBridge = 0x80;

j::Frame cm(uint8_t sa, uint8_t da, std::array<uint8_t, 8> data) {
  j::Frame f;
  f.id = {7, j::kPgnTpCm, sa, da};
  f.data = data;
  return f;
}

// TP.CM_BAM / TP.CM_RTS announcing `size` bytes of PGN 0xFF10.
j::Frame bam(uint8_t sa, uint16_t size, uint8_t packets) {
  return cm(sa, j::kGlobalAddress, {32, static_cast<uint8_t>(size), static_cast<uint8_t>(size >> 8), packets, 0xFF,
                                    0x10, 0xFF, 0x00});
}
j::Frame rts(uint8_t sa, uint8_t da, uint16_t size, uint8_t packets, uint8_t max_per_cts = 0xFF) {
  return cm(sa, da, {16, static_cast<uint8_t>(size), static_cast<uint8_t>(size >> 8), packets, max_per_cts, 0x00,
                     0xEF, 0x00});
}

// Packet `seq` of `payload` (7 bytes from (seq-1)*7, padded with 0xFF).
j::Frame dt(uint8_t sa, uint8_t da, uint8_t seq, const std::vector<uint8_t>& payload) {
  j::Frame f;
  f.id = {7, j::kPgnTpDt, sa, da};
  f.data.fill(0xFF);
  f.data[0] = seq;
  for (std::size_t i = 0; i < 7 && (seq - 1u) * 7u + i < payload.size(); ++i) f.data[1 + i] = payload[(seq - 1u) * 7u + i];
  return f;
}

std::vector<uint8_t> bytes(std::size_t n) {
  std::vector<uint8_t> v(n);
  std::iota(v.begin(), v.end(), uint8_t{1});
  return v;
}

}  // namespace

TEST_CASE("a J1939 identifier splits into priority, PGN, destination and source", "[firmware_protocol]") {
  SECTION("PDU2 (PF >= 240) is a broadcast: PS is the group extension") {
    const j::Id id = j::decode_id(0x18FEF121);
    CHECK(id.priority == 6);
    CHECK(id.pgn == 0xFEF1);
    CHECK(id.sa == 0x21);
    CHECK(id.da == j::kGlobalAddress);
    CHECK_FALSE(j::is_pdu1(id.pgn));
    CHECK(j::encode_id(id) == 0x18FEF121);
  }
  SECTION("PDU1 (PF < 240): PS is the destination and not part of the PGN") {
    const j::Id id = j::decode_id(0x18EA2521);
    CHECK(id.pgn == 0xEA00);
    CHECK(id.da == 0x25);
    CHECK(id.sa == 0x21);
    CHECK(j::is_pdu1(id.pgn));
    CHECK(j::encode_id(id) == 0x18EA2521);
    CHECK(j::pgn_of(0x18EA2521) == j::pgn_of(0x18EAFF00));
  }
  SECTION("the data page bit is part of the PGN; a PDU2 id ignores the destination") {
    CHECK(j::decode_id(0x0DFF1000).pgn == 0x1FF10);
    CHECK(j::decode_id(0x0DFF1000).priority == 3);
    CHECK(j::encode_id({3, 0xFF10, 0x05, 0x33}) == 0x0CFF1005);
  }
  SECTION("a J1939 DBC's BO_ id (bit 31 = extended) has its PGN in bits 8..25") {
    const uint32_t dbc_id = 0x98FEF1FEu & 0x1FFFFFFF;  // BO_ 2566844926: bit 31 set
    CHECK(j::pgn_of(dbc_id) == 0xFEF1);
    CHECK(j::decode_id(dbc_id).sa == 0xFE);
  }
}

TEST_CASE("a J1939 NAME packs its fields as J1939-81 places them", "[firmware_protocol]") {
  j::Name n;
  n.identity = 0x12345;
  n.manufacturer = 0x7FF;
  n.ecu_instance = 1;
  n.function_instance = 2;
  n.function = 0x81;
  n.vehicle_system = 0x3C;
  n.vehicle_system_instance = 3;
  n.industry_group = 2;
  n.arbitrary_address_capable = true;
  const uint64_t raw = n.pack();
  CHECK(raw == 0xA3788111FFE12345ull);
  CHECK((raw >> 63) == 1);
  const j::Name back = j::Name::unpack(raw);
  CHECK(back.identity == n.identity);
  CHECK(back.manufacturer == n.manufacturer);
  CHECK(back.function == n.function);
  CHECK(back.vehicle_system == n.vehicle_system);
  CHECK(back.industry_group == n.industry_group);
  CHECK(back.arbitrary_address_capable);
  const auto wire = j::name_to_bytes(raw);
  CHECK(wire[0] == 0x45);  // least significant byte first
  CHECK(wire[7] == 0xA3);
  CHECK(j::name_from_bytes(std::span<const uint8_t, 8>(wire.data(), 8)) == raw);
}

TEST_CASE("the TP receiver reassembles a BAM broadcast and drops what does not fit", "[firmware_protocol]") {
  j::TpReceiver rx;
  rx.set_own_address(kBridge);
  const auto payload = bytes(20);  // 3 packets: 7 + 7 + 6
  REQUIRE_FALSE(rx.on_frame(bam(kConsole, 20, 3), 0).reply);

  SECTION("in order: one message, no reply (BAM is never answered)") {
    CHECK_FALSE(rx.on_frame(dt(kConsole, 255, 1, payload), 50).message);
    CHECK_FALSE(rx.on_frame(dt(kConsole, 255, 2, payload), 100).message);
    const j::TpResult r = rx.on_frame(dt(kConsole, 255, 3, payload), 150);
    REQUIRE(r.message);
    CHECK_FALSE(r.reply);
    CHECK(r.message->pgn == 0xFF10);
    CHECK(r.message->sa == kConsole);
    CHECK(r.message->da == j::kGlobalAddress);
    CHECK(std::vector<uint8_t>(r.message->data.begin(), r.message->data.end()) == payload);
    CHECK(rx.counters().messages == 1);
  }
  SECTION("a duplicate packet is counted and dropped; the message still completes") {
    rx.on_frame(dt(kConsole, 255, 1, payload), 50);
    rx.on_frame(dt(kConsole, 255, 1, payload), 60);
    rx.on_frame(dt(kConsole, 255, 2, payload), 100);
    CHECK(rx.on_frame(dt(kConsole, 255, 3, payload), 150).message);
    CHECK(rx.counters().duplicates == 1);
  }
  SECTION("a skipped packet loses the broadcast: counted, the rest is stray") {
    rx.on_frame(dt(kConsole, 255, 1, payload), 50);
    CHECK_FALSE(rx.on_frame(dt(kConsole, 255, 3, payload), 100).message);
    CHECK(rx.counters().out_of_order == 1);
    CHECK(rx.counters().dropped[static_cast<std::size_t>(j::TpDrop::OutOfOrder)] == 1);
    rx.on_frame(dt(kConsole, 255, 2, payload), 150);
    CHECK(rx.counters().stray == 1);
    CHECK(rx.counters().messages == 0);
  }
  SECTION("T1 (750 ms) without the next packet ends the session") {
    rx.on_frame(dt(kConsole, 255, 1, payload), 50);
    std::array<j::Frame, 4> aborts;
    CHECK(rx.expire(800, aborts) == 0);
    CHECK(rx.expire(801, aborts) == 0);  // no abort is sent for BAM
    CHECK(rx.counters().dropped[static_cast<std::size_t>(j::TpDrop::Timeout)] == 1);
    CHECK_FALSE(rx.on_frame(dt(kConsole, 255, 2, payload), 810).message);
  }
  SECTION("a new announcement from the same sender replaces the unfinished one") {
    rx.on_frame(dt(kConsole, 255, 1, payload), 50);
    rx.on_frame(bam(kConsole, 20, 3), 60);
    CHECK(rx.counters().dropped[static_cast<std::size_t>(j::TpDrop::Replaced)] == 1);
    for (uint8_t seq = 1; seq <= 3; ++seq) rx.on_frame(dt(kConsole, 255, seq, payload), 100 + seq);
    CHECK(rx.counters().messages == 1);
  }
}

TEST_CASE("the TP receiver rejects announcements whose size and packets disagree", "[firmware_protocol]") {
  j::TpReceiver rx;
  rx.set_own_address(kBridge);
  auto bad = GENERATE(std::array<int, 2>{8, 2}, std::array<int, 2>{20, 4}, std::array<int, 2>{1786, 255},
                      std::array<int, 2>{0, 0});
  rx.on_frame(bam(kConsole, static_cast<uint16_t>(bad[0]), static_cast<uint8_t>(bad[1])), 0);
  const j::TpResult r = rx.on_frame(rts(kConsole, kBridge, static_cast<uint16_t>(bad[0]), static_cast<uint8_t>(bad[1])), 0);
  REQUIRE(r.reply);
  CHECK(r.reply->data[0] == 255);  // RTS answered with an abort
  CHECK(rx.counters().dropped[static_cast<std::size_t>(j::TpDrop::BadAnnouncement)] == 2);
}

TEST_CASE("the TP receiver answers RTS/CTS addressed to it, window by window", "[firmware_protocol]") {
  j::TpReceiver rx;
  rx.set_own_address(kBridge);
  const auto payload = bytes(30);  // 5 packets

  SECTION("an RTS to another address is not ours") {
    CHECK_FALSE(rx.on_frame(rts(kConsole, 0x90, 30, 5), 0).reply);
    CHECK_FALSE(rx.on_frame(dt(kConsole, 0x90, 1, payload), 1).message);
    CHECK(rx.counters().stray == 0);
  }
  SECTION("a sender that takes 2 packets per CTS gets three CTS and an end-of-message ack") {
    j::TpResult r = rx.on_frame(rts(kConsole, kBridge, 30, 5, 2), 0);
    REQUIRE(r.reply);
    CHECK(r.reply->id.pgn == j::kPgnTpCm);
    CHECK(r.reply->id.sa == kBridge);
    CHECK(r.reply->id.da == kConsole);
    CHECK(r.reply->data[0] == 17);  // CTS
    CHECK(r.reply->data[1] == 2);   // packets
    CHECK(r.reply->data[2] == 1);   // next
    CHECK(r.reply->data[5] == 0x00);
    CHECK(r.reply->data[6] == 0xEF);
    CHECK_FALSE(rx.on_frame(dt(kConsole, kBridge, 1, payload), 1).reply);
    r = rx.on_frame(dt(kConsole, kBridge, 2, payload), 2);
    REQUIRE(r.reply);
    CHECK(r.reply->data[1] == 2);
    CHECK(r.reply->data[2] == 3);
    rx.on_frame(dt(kConsole, kBridge, 3, payload), 3);
    r = rx.on_frame(dt(kConsole, kBridge, 4, payload), 4);
    REQUIRE(r.reply);
    CHECK(r.reply->data[1] == 1);
    CHECK(r.reply->data[2] == 5);
    r = rx.on_frame(dt(kConsole, kBridge, 5, payload), 5);
    REQUIRE(r.message);
    CHECK(r.message->pgn == 0xEF00);
    CHECK(r.message->da == kBridge);
    CHECK(std::vector<uint8_t>(r.message->data.begin(), r.message->data.end()) == payload);
    REQUIRE(r.reply);
    CHECK(r.reply->data[0] == 19);  // end of message ack
    CHECK(r.reply->data[1] == 30);
    CHECK(r.reply->data[3] == 5);
  }
  SECTION("a gap at the end of a window is asked for again by CTS") {
    rx.on_frame(rts(kConsole, kBridge, 30, 5), 0);
    rx.on_frame(dt(kConsole, kBridge, 1, payload), 1);
    rx.on_frame(dt(kConsole, kBridge, 2, payload), 2);
    CHECK_FALSE(rx.on_frame(dt(kConsole, kBridge, 4, payload), 3).reply);  // dropped, window not over
    const j::TpResult r = rx.on_frame(dt(kConsole, kBridge, 5, payload), 4);
    REQUIRE(r.reply);
    CHECK(r.reply->data[0] == 17);
    CHECK(r.reply->data[2] == 3);
    CHECK(rx.counters().out_of_order == 2);
    for (uint8_t seq = 3; seq <= 5; ++seq) rx.on_frame(dt(kConsole, kBridge, seq, payload), 10 + seq);
    CHECK(rx.counters().messages == 1);
  }
  SECTION("the sender's abort ends the session") {
    rx.on_frame(rts(kConsole, kBridge, 30, 5), 0);
    rx.on_frame(cm(kConsole, kBridge, {255, 3, 0xFF, 0xFF, 0xFF, 0x00, 0xEF, 0x00}), 1);
    CHECK(rx.counters().dropped[static_cast<std::size_t>(j::TpDrop::AbortReceived)] == 1);
    rx.on_frame(dt(kConsole, kBridge, 1, payload), 2);
    CHECK(rx.counters().stray == 1);
  }
  SECTION("T2 (1250 ms) after a CTS without data: the receiver aborts with reason 3") {
    rx.on_frame(rts(kConsole, kBridge, 30, 5), 0);
    std::array<j::Frame, 4> aborts;
    CHECK(rx.expire(1250, aborts) == 0);
    REQUIRE(rx.expire(1251, aborts) == 1);
    CHECK(aborts[0].id.da == kConsole);
    CHECK(aborts[0].data[0] == 255);
    CHECK(aborts[0].data[1] == 3);
    CHECK(rx.counters().dropped[static_cast<std::size_t>(j::TpDrop::Timeout)] == 1);
  }
  SECTION("moving to another address drops the sessions addressed to the old one") {
    rx.on_frame(rts(kConsole, kBridge, 30, 5), 0);
    rx.set_own_address(0x81);
    rx.on_frame(dt(kConsole, kBridge, 1, payload), 1);
    CHECK(rx.counters().stray == 0);  // no longer ours at all
    CHECK(rx.counters().messages == 0);
  }
}

TEST_CASE("a BAM sender's frames reassemble into what it sent", "[firmware_protocol]") {
  const std::size_t size = GENERATE(9, 14, 15, 20, 64, 1785);
  const auto payload = bytes(size);
  j::BamSender tx;
  REQUIRE(tx.start(0xFF10, kConsole, payload));
  j::TpReceiver rx;
  std::optional<std::vector<uint8_t>> got;
  int frames = 0;
  while (auto f = tx.next()) {
    ++frames;
    if (auto r = rx.on_frame(*f, frames); r.message) got.emplace(r.message->data.begin(), r.message->data.end());
  }
  CHECK(frames == 1 + static_cast<int>((size + 6) / 7));
  REQUIRE(got);
  CHECK(*got == payload);
  CHECK_FALSE(tx.start(0xFF10, kConsole, bytes(8)));
}

TEST_CASE("address claim: the lower NAME keeps the address, the other moves or gives up", "[firmware_protocol]") {
  const uint64_t low = 0x8000000000001000ull;   // arbitrary address capable
  const uint64_t high = 0x8000000000002000ull;  // arbitrary address capable
  const auto claim = [](uint8_t sa, uint64_t name) {
    j::Frame f;
    f.id = {6, j::kPgnAddressClaimed, sa, j::kGlobalAddress};
    f.data = j::name_to_bytes(name);
    return f;
  };
  j::Frame reply;

  SECTION("uncontested: claimed 250 ms after the claim went out") {
    j::AddressClaimer c(high, kBridge);
    const j::Frame f = c.start(0);
    CHECK(f.id.pgn == j::kPgnAddressClaimed);
    CHECK(f.id.sa == kBridge);
    CHECK(j::encode_id(f.id) == 0x18EEFF80);
    c.tick(249);
    CHECK(c.address() == j::kNullAddress);
    c.tick(250);
    CHECK(c.address() == kBridge);
  }
  SECTION("a higher NAME claiming our address is answered with our claim") {
    j::AddressClaimer c(low, kBridge);
    c.start(0);
    REQUIRE(c.on_frame(claim(kBridge, high), 10, reply));
    CHECK(reply.id.sa == kBridge);
    CHECK(c.contentions_lost() == 0);
  }
  SECTION("a lower NAME takes the address: an arbitrary-address node claims the next free one") {
    j::AddressClaimer c(high, kBridge);
    c.start(0);
    c.tick(300);
    c.on_frame(claim(0x81, 0x1234), 310, reply);  // someone else sits on 0x81
    REQUIRE(c.on_frame(claim(kBridge, low), 320, reply));
    CHECK(reply.id.sa == 0x82);
    CHECK(c.state() == j::AddressClaimer::State::Claiming);
    CHECK(c.contentions_lost() == 1);
    c.tick(570);
    CHECK(c.address() == 0x82);
  }
  SECTION("a lower NAME takes the address of a node that cannot move: Cannot Claim from 254") {
    j::AddressClaimer c(high & ~(1ull << 63), kBridge);
    c.start(0);
    REQUIRE(c.on_frame(claim(kBridge, 0x1000), 10, reply));  // lower still, not arbitrary-capable either
    CHECK(reply.id.sa == j::kNullAddress);
    CHECK(c.state() == j::AddressClaimer::State::CannotClaim);
    c.tick(1000);
    CHECK(c.address() == j::kNullAddress);
  }
  SECTION("a request for address claimed is answered; a request for another PGN is not") {
    j::AddressClaimer c(high, kBridge);
    j::Frame request;
    request.id = {6, j::kPgnRequest, 0x21, j::kGlobalAddress};
    request.data = {0x00, 0xEE, 0x00, 0, 0, 0, 0, 0};
    request.len = 3;
    CHECK_FALSE(c.on_frame(request, 0, reply));  // nothing claimed yet
    c.start(0);
    REQUIRE(c.on_frame(request, 1, reply));
    CHECK(reply.id.sa == kBridge);
    request.data[1] = 0xEF;
    CHECK_FALSE(c.on_frame(request, 2, reply));
  }
  SECTION("a peer is followed by NAME when it claims another address") {
    j::AddressClaimer c(high, kBridge);
    const uint64_t console = 0x00A0000000000042ull;
    CHECK(c.address_of(console) == j::kNullAddress);
    CHECK_FALSE(c.on_frame(claim(0x21, console), 0, reply));
    CHECK(c.address_of(console) == 0x21);
    c.on_frame(claim(0x95, console), 10, reply);
    CHECK(c.address_of(console) == 0x95);
    CHECK_FALSE(c.name_at(0x21));
    c.on_frame(claim(j::kNullAddress, console), 20, reply);  // it gave up its address
    CHECK(c.address_of(console) == j::kNullAddress);
  }
}
