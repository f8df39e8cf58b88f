#include "hil/j1939_source.hpp"

#include <sstream>
#include <utility>

namespace rise::hil {
namespace {
namespace j1939 = rise::firmware_protocol::j1939;

std::string hex_address(uint8_t address) {
  std::ostringstream out;
  out << "0x" << std::hex << static_cast<int>(address);
  return out.str();
}

}  // namespace

J1939Source::J1939Source(std::unique_ptr<io::CanBus> bus, const panels::PanelDefinition& definition,
                         std::size_t source)
    : bus_(std::move(bus)), name_(definition.sources[source].name), input_(definition.sources[source]) {}

io::IoStatus J1939Source::reopen(SourcePanel&) {
  const io::IoStatus status = bus_->reopen();
  if (status == io::IoStatus::Ok) claim_started_ = false;
  return status;
}

io::IoStatus J1939Source::receive(SourcePanel& panel, int timeout_ms) {
  const io::IoStatus status = claim_started_ ? bus_->receive(frame_, timeout_ms) : io::IoStatus::Timeout;
  replies_.count = 0;
  // The timers run at every call (the loop calls every few ms), frame or not.
  panel.update([&](PanelMapper& mapper, int64_t now_us) {
    if (!claim_started_) input_.start(now_us / 1000, replies_);
    claim_started_ = true;
    input_.tick(now_us / 1000, replies_);
    const bool changed = status == io::IoStatus::Ok && input_.on_frame(mapper, panel.source(), frame_, now_us, replies_);
    // Before a change is published: whoever sees the state sees these too.
    store_counters();
    return changed;
  });
  // Fire and forget, as every J1939 node: a lost claim or CTS is sent again
  // (the peer repeats its request, the sender's timeout aborts and retries).
  for (std::size_t i = 0; i < replies_.count; ++i) bus_->send(to_can_frame(replies_.frames[i]));
  note_changes(panel);
  return status;
}

void J1939Source::store_counters() {
  seen_own_ = input_.own_address();
  seen_console_ = input_.console_address();
  seen_tp_messages_ = input_.transport_counters().messages;
  seen_foreign_ = input_.foreign_messages();
}

// Address changes are rare and worth a line in the log (allocates only then).
void J1939Source::note_changes(SourcePanel& panel) {
  const uint8_t own = input_.own_address();
  const uint8_t console = input_.console_address();
  if (own != noted_own_) {
    noted_own_ = own;
    if (own != j1939::kNullAddress)
      panel.note("source '" + name_ + "': J1939 address " + hex_address(own) + " claimed");
    else if (input_.claim_state() == j1939::AddressClaimer::State::CannotClaim)
      panel.note("source '" + name_ + "': J1939 address lost to a lower NAME, none free (Cannot Claim)");
  }
  if (console != noted_console_) {
    noted_console_ = console;
    if (console != j1939::kNullAddress)
      panel.note("source '" + name_ + "': console at J1939 address " + hex_address(console));
  }
}

}  // namespace rise::hil
