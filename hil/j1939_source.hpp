#pragma once

// A J1939 console's transport (protocol j1939) for the bridge's source loop,
// over any raw CAN bus (socketcan, slcan, socketcand, replay): what a frame
// does is J1939Input's (j1939_input.hpp: our address claim, the transport
// protocol, the console followed by its NAME); this sends the frames it
// answers with and notes address changes. No feedback: a J1939 DBC of a
// console's inputs has no frames of ours.

#include <atomic>
#include <cstdint>
#include <memory>

#include "hil/io/can_bus.hpp"
#include "hil/j1939_input.hpp"
#include "hil/source_transport.hpp"

namespace rise::hil {

class J1939Source final : public SourceTransport {
 public:
  /// `bus` carries source `source` of `definition` (protocol j1939).
  J1939Source(std::unique_ptr<io::CanBus> bus, const panels::PanelDefinition& definition, std::size_t source);

  bool is_open() const override { return bus_->is_open(); }
  /// Reopens the bus and claims the address again (the bus may have been
  /// someone else's while we were away).
  io::IoStatus reopen(SourcePanel& panel) override;
  std::string last_error() const override { return bus_->last_error(); }
  io::IoStatus receive(SourcePanel& panel, int timeout_ms) override;
  bool shows_feedback() const override { return false; }
  io::IoStatus send_feedback(SourcePanel&, const FeedbackRequest&, const PanelSnapshot&, bool) override {
    return io::IoStatus::Ok;
  }
  void decorate(IoDecorator& decorator) override { bus_ = decorator.wrap(std::move(bus_)); }

  // What the source's thread last saw, readable from any thread.
  /// Our address while claimed, else 254.
  uint8_t own_address() const { return seen_own_; }
  /// Where the console's messages are taken from now; 254 while unknown.
  uint8_t console_address() const { return seen_console_; }
  /// Messages the transport protocol reassembled.
  uint64_t transport_messages() const { return seen_tp_messages_; }
  /// Whole messages from addresses other than the console's (dropped).
  uint64_t foreign_messages() const { return seen_foreign_; }

 private:
  // The counters and addresses the accessors read (atomics), from the input.
  void store_counters();
  void note_changes(SourcePanel& panel);

  std::unique_ptr<io::CanBus> bus_;
  std::string name_;
  J1939Input input_;
  J1939Replies replies_;
  bool claim_started_ = false;
  uint8_t noted_own_ = firmware_protocol::j1939::kNullAddress;
  uint8_t noted_console_ = firmware_protocol::j1939::kNullAddress;
  io::CanFrame frame_;
  std::atomic<uint8_t> seen_own_{firmware_protocol::j1939::kNullAddress};
  std::atomic<uint8_t> seen_console_{firmware_protocol::j1939::kNullAddress};
  std::atomic<uint64_t> seen_tp_messages_{0};
  std::atomic<uint64_t> seen_foreign_{0};
};

}  // namespace rise::hil
