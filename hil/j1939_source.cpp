#include "hil/j1939_source.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <sstream>
#include <utility>

#include "hil/source_input.hpp"

namespace rise::hil {
namespace {
namespace j1939 = rise::firmware_protocol::j1939;

int64_t monotonic_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

std::string hex_address(uint8_t address) {
  std::ostringstream out;
  out << "0x" << std::hex << static_cast<int>(address);
  return out.str();
}

// Request (PGN 59904) for Address Claimed to everyone: each node answers with
// its claim, so the console's address is known without waiting for it.
j1939::Frame request_address_claimed(uint8_t sa) {
  j1939::Frame f;
  f.id = {6, j1939::kPgnRequest, sa, j1939::kGlobalAddress};
  f.data = {0x00, 0xEE, 0x00, 0, 0, 0, 0, 0};
  f.len = 3;
  return f;
}

}  // namespace

J1939Source::J1939Source(std::unique_ptr<io::CanBus> bus, const panels::PanelDefinition& definition,
                         std::size_t source)
    : bus_(std::move(bus)),
      definition_(definition.sources[source]),
      claimer_(definition_.j1939_name, definition_.j1939_address) {}

io::IoStatus J1939Source::reopen(SourcePanel&) {
  const io::IoStatus status = bus_->reopen();
  if (status == io::IoStatus::Ok) claim_started_ = false;
  return status;
}

uint8_t J1939Source::current_console_address() const {
  if (definition_.console_name) {
    const uint8_t claimed = claimer_.address_of(*definition_.console_name);
    if (claimed != j1939::kNullAddress) return claimed;
  }
  return definition_.console_address;
}

void J1939Source::send(const j1939::Frame& frame) {
  io::CanFrame f;
  f.id = j1939::encode_id(frame.id);
  f.extended = true;
  f.len = frame.len;
  std::copy_n(frame.data.begin(), frame.len, f.data.begin());
  bus_->send(f);  // fire and forget, as every J1939 node: a lost frame is a lost claim or CTS, both retried
}

void J1939Source::start_claim(int64_t now_ms) {
  send(claimer_.start(now_ms));
  // The request goes out from 254 (J1939-81 allows it before a claim) so the
  // console's answer reaches us even if our address is contested.
  send(request_address_claimed(j1939::kNullAddress));
  claim_started_ = true;
}

io::IoStatus J1939Source::receive(SourcePanel& panel, int timeout_ms) {
  const int64_t start_ms = monotonic_ms();
  if (!claim_started_) start_claim(start_ms);
  const io::IoStatus status = bus_->receive(frame_, timeout_ms);
  const int64_t now_ms = monotonic_ms();
  claimer_.tick(now_ms);
  tp_.set_own_address(claimer_.address());
  std::array<j1939::Frame, j1939::TpReceiver::kSessions> aborts;
  const std::size_t n = tp_.expire(now_ms, aborts);
  for (std::size_t i = 0; i < n; ++i) send(aborts[i]);
  if (status == io::IoStatus::Ok) {
    if (frame_.error) {
      panel.update([&](PanelMapper& mapper, int64_t now_us) {
        return apply_can_frame(mapper, panel.source(), frame_, now_us);
      });
    } else if (frame_.extended && !frame_.remote && !frame_.fd && frame_.len <= 8) {
      // J1939 is 29-bit classic CAN; 11-bit frames of other protocols share the bus.
      j1939::Frame f;
      f.id = j1939::decode_id(frame_.id);
      f.len = frame_.len;
      std::copy_n(frame_.data.begin(), frame_.len, f.data.begin());
      on_frame(panel, f, now_ms);
    }
  }
  note_changes(panel);
  return status;
}

void J1939Source::on_frame(SourcePanel& panel, const j1939::Frame& frame, int64_t now_ms) {
  j1939::Frame reply;
  if (claimer_.on_frame(frame, now_ms, reply)) send(reply);
  tp_.set_own_address(claimer_.address());
  if (frame.id.pgn == j1939::kPgnTpCm || frame.id.pgn == j1939::kPgnTpDt) {
    const j1939::TpResult r = tp_.on_frame(frame, now_ms);
    if (r.reply) send(*r.reply);
    if (r.message) deliver(panel, {frame.id.priority, r.message->pgn, r.message->sa, r.message->da}, r.message->data);
    return;
  }
  if (frame.id.pgn == j1939::kPgnAddressClaimed || frame.id.pgn == j1939::kPgnRequest) return;
  // A PDU1 message to another node is not for us.
  if (j1939::is_pdu1(frame.id.pgn) && frame.id.da != j1939::kGlobalAddress && frame.id.da != claimer_.address())
    return;
  deliver(panel, frame.id, std::span<const uint8_t>(frame.data.data(), frame.len));
}

void J1939Source::deliver(SourcePanel& panel, const j1939::Id& id, std::span<const uint8_t> data) {
  if (id.sa != current_console_address()) {
    foreign_++;
    return;
  }
  const uint32_t can_id = j1939::encode_id(id);
  panel.update([&](PanelMapper& mapper, int64_t now_us) {
    return mapper.on_frame(panel.source(), can_id, data, now_us, true);
  });
}

// Address changes are rare and worth a line in the log (allocates only then).
void J1939Source::note_changes(SourcePanel& panel) {
  const uint8_t own = claimer_.address();
  if (own != noted_own_) {
    noted_own_ = own;
    if (own != j1939::kNullAddress)
      panel.note("source '" + definition_.name + "': J1939 address " + hex_address(own) + " claimed");
    else if (claimer_.state() == j1939::AddressClaimer::State::CannotClaim)
      panel.note("source '" + definition_.name + "': J1939 address lost to a lower NAME, none free (Cannot Claim)");
  }
  const uint8_t console = current_console_address();
  seen_own_ = own;
  seen_console_ = console;
  seen_tp_messages_ = tp_.counters().messages;
  if (console != noted_console_) {
    noted_console_ = console;
    if (console != j1939::kNullAddress)
      panel.note("source '" + definition_.name + "': console at J1939 address " + hex_address(console));
  }
}

}  // namespace rise::hil
