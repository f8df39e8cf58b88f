// libFuzzer target: the J1939 wire logic a bridge runs on whatever the bus
// brings (firmware_protocol/j1939.hpp): identifier decoding, the transport
// protocol's reassembly (BAM and RTS/CTS) and address claim. Input layout:
//   byte 0: our address (the TP receiver's and the claimer's preferred one)
//   then records: 4 bytes id LE (29 bits used), a byte whose low nibble is
//   the length (> 8: clamped to 8) and high nibble the time step (x 100 ms,
//   so timeouts fire), then the data.
// Checks beyond "no crash, no UB": identifiers round-trip, a reassembled
// message has 9..1785 bytes, replies go from our address to the sender, the
// claimer holds a valid address, and the counters only grow.
#include <array>
#include <cstddef>
#include <cstdint>

#include "firmware_protocol/j1939.hpp"
#include "tests/fuzz/fuzz_check.hpp"

namespace j = rise::firmware_protocol::j1939;

namespace {

uint64_t total(const j::TpCounters& c) {
  uint64_t sum = c.messages + c.duplicates + c.out_of_order + c.stray;
  for (uint64_t d : c.dropped) sum += d;
  return sum;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const uint8_t own = data[0] >= j::kNullAddress ? 0x80 : data[0];
  j::TpReceiver rx;
  rx.set_own_address(own);
  j::AddressClaimer claimer(0x8000000000001939ull, own);
  const j::Frame first = claimer.start(0);
  fuzz_check(first.id.sa == own);
  int64_t now_ms = 0;
  std::size_t at = 1;
  while (at + 5 <= size) {
    const uint32_t id = (static_cast<uint32_t>(data[at]) | static_cast<uint32_t>(data[at + 1]) << 8 |
                         static_cast<uint32_t>(data[at + 2]) << 16 | static_cast<uint32_t>(data[at + 3]) << 24) &
                        0x1FFFFFFF;
    const uint8_t length = static_cast<uint8_t>(data[at + 4] & 0x0F) > 8 ? 8 : data[at + 4] & 0x0F;
    now_ms += 100 * (data[at + 4] >> 4);
    at += 5;
    j::Frame f;
    f.id = j::decode_id(id);
    fuzz_check(j::encode_id(f.id) == id);
    fuzz_check(!j::is_pdu1(f.id.pgn) || (f.id.pgn & 0xFF) == 0);
    f.len = length;
    for (std::size_t i = 0; i < length && at < size; ++i) f.data[i] = data[at++];

    const uint64_t before = total(rx.counters());
    std::array<j::Frame, j::TpReceiver::kSessions> aborts;
    const std::size_t n = rx.expire(now_ms, aborts);
    fuzz_check(n <= aborts.size());
    for (std::size_t i = 0; i < n; ++i) fuzz_check(aborts[i].id.sa == own && aborts[i].data[0] == 255);
    const j::TpResult r = rx.on_frame(f, now_ms);
    fuzz_check(total(rx.counters()) >= before);
    if (r.message) {
      fuzz_check(r.message->data.size() >= 9 && r.message->data.size() <= j::kMaxTpBytes);
      fuzz_check(r.message->sa == f.id.sa);
    }
    if (r.reply) {
      fuzz_check(r.reply->id.pgn == j::kPgnTpCm);
      fuzz_check(r.reply->id.sa == own && r.reply->id.da == f.id.sa);
      if (r.reply->data[0] == 17) fuzz_check(r.reply->data[2] >= 1 && r.reply->data[1] >= 1);
    }

    j::Frame reply;
    if (claimer.on_frame(f, now_ms, reply)) fuzz_check(reply.id.pgn == j::kPgnAddressClaimed);
    claimer.tick(now_ms);
    const uint8_t address = claimer.address();
    fuzz_check(address == j::kNullAddress || address == own || (address >= 128 && address <= 247));
    if (address != j::kNullAddress) fuzz_check(claimer.state() == j::AddressClaimer::State::Claimed);
  }
  return 0;
}
