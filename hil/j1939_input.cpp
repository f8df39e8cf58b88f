#include "hil/j1939_input.hpp"

#include <algorithm>

#include "hil/source_input.hpp"

namespace rise::hil {
namespace {
namespace j1939 = rise::firmware_protocol::j1939;

// Request (PGN 59904) for Address Claimed to everyone, from the null address
// (J1939-81 allows it before a claim): every node answers with its claim.
j1939::Frame request_address_claimed() {
  j1939::Frame f;
  f.id = {6, j1939::kPgnRequest, j1939::kNullAddress, j1939::kGlobalAddress};
  f.data = {0x00, 0xEE, 0x00, 0, 0, 0, 0, 0};
  f.len = 3;
  return f;
}

}  // namespace

io::CanFrame to_can_frame(const j1939::Frame& frame) {
  io::CanFrame f;
  f.id = j1939::encode_id(frame.id);
  f.extended = true;
  f.len = frame.len;
  std::copy_n(frame.data.begin(), frame.len, f.data.begin());
  return f;
}

J1939Input::J1939Input(const panels::SourceDefinition& source)
    : console_name_(source.console_name.value_or(0)),
      has_console_name_(source.console_name.has_value()),
      fixed_console_address_(source.console_address),
      claimer_(source.j1939_name, source.j1939_address) {}

uint8_t J1939Input::console_address() const {
  if (has_console_name_) {
    const uint8_t claimed = claimer_.address_of(console_name_);
    if (claimed != j1939::kNullAddress) return claimed;
  }
  return fixed_console_address_;
}

void J1939Input::start(int64_t now_ms, J1939Replies& out) {
  out.push(claimer_.start(now_ms));
  out.push(request_address_claimed());
  tp_.set_own_address(claimer_.address());
}

void J1939Input::tick(int64_t now_ms, J1939Replies& out) {
  claimer_.tick(now_ms);
  tp_.set_own_address(claimer_.address());
  std::array<j1939::Frame, j1939::TpReceiver::kSessions> aborts;
  const std::size_t n = tp_.expire(now_ms, aborts);
  for (std::size_t i = 0; i < n; ++i) out.push(aborts[i]);
}

bool J1939Input::on_frame(PanelMapper& mapper, std::size_t source, const io::CanFrame& frame, int64_t now_us,
                          J1939Replies& out) {
  if (frame.error) return apply_can_frame(mapper, source, frame, now_us);
  // J1939 is 29-bit classic CAN; 11-bit frames of other protocols share the bus.
  if (!frame.extended || frame.remote || frame.fd || frame.len > 8) return false;
  j1939::Frame f;
  f.id = j1939::decode_id(frame.id);
  f.len = frame.len;
  std::copy_n(frame.data.begin(), frame.len, f.data.begin());
  const int64_t now_ms = now_us / 1000;
  j1939::Frame reply;
  if (claimer_.on_frame(f, now_ms, reply)) out.push(reply);
  tp_.set_own_address(claimer_.address());
  if (f.id.pgn == j1939::kPgnTpCm || f.id.pgn == j1939::kPgnTpDt) {
    const j1939::TpResult r = tp_.on_frame(f, now_ms);
    if (r.reply) out.push(*r.reply);
    return r.message && deliver(mapper, source, {f.id.priority, r.message->pgn, r.message->sa, r.message->da},
                                r.message->data, now_us);
  }
  if (f.id.pgn == j1939::kPgnAddressClaimed || f.id.pgn == j1939::kPgnRequest) return false;
  // A PDU1 message to another node is not for us.
  if (j1939::is_pdu1(f.id.pgn) && f.id.da != j1939::kGlobalAddress && f.id.da != claimer_.address()) return false;
  return deliver(mapper, source, f.id, std::span<const uint8_t>(f.data.data(), f.len), now_us);
}

bool J1939Input::deliver(PanelMapper& mapper, std::size_t source, const j1939::Id& id, std::span<const uint8_t> data,
                         int64_t now_us) {
  if (id.sa != console_address()) {
    foreign_++;
    return false;
  }
  return mapper.on_frame(source, j1939::encode_id(id), data, now_us, true);
}

}  // namespace rise::hil
