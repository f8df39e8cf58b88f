#pragma once

// A J1939 console's transport (protocol j1939) for the bridge's source loop,
// over any raw CAN bus (socketcan, slcan, socketcand, replay): the bridge
// claims its own address with its NAME and defends it (J1939-81), learns the
// console's address from the console's claim by NAME (so a console that
// moves is followed), reassembles BAM and RTS/CTS transfers
// (firmware_protocol/j1939.hpp) and hands each whole message from the
// console's address to the panel, matched by PGN against the J1939 DBC.
// Messages from other addresses share the bus and are only counted. No
// feedback: a J1939 DBC of a console's inputs has no frames of ours.

#include <atomic>
#include <cstdint>
#include <memory>

#include "firmware_protocol/j1939.hpp"
#include "hil/io/can_bus.hpp"
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
  /// Our address while claimed, else kNullAddress (254).
  uint8_t own_address() const { return seen_own_; }
  /// Where the console's messages are taken from now; 254 while unknown.
  uint8_t console_address() const { return seen_console_; }
  /// Messages the transport protocol reassembled.
  uint64_t transport_messages() const { return seen_tp_messages_; }
  /// Whole messages from addresses other than the console's (dropped).
  uint64_t foreign_messages() const { return foreign_; }

 private:
  void start_claim(int64_t now_ms);
  void send(const firmware_protocol::j1939::Frame& frame);
  void on_frame(SourcePanel& panel, const firmware_protocol::j1939::Frame& frame, int64_t now_ms);
  void deliver(SourcePanel& panel, const firmware_protocol::j1939::Id& id, std::span<const uint8_t> data);
  void note_changes(SourcePanel& panel);
  uint8_t current_console_address() const;

  std::unique_ptr<io::CanBus> bus_;
  const panels::SourceDefinition definition_;  // a copy: the transport may outlive the caller's definition
  firmware_protocol::j1939::AddressClaimer claimer_;
  firmware_protocol::j1939::TpReceiver tp_;
  bool claim_started_ = false;
  uint8_t noted_own_ = firmware_protocol::j1939::kNullAddress;
  uint8_t noted_console_ = firmware_protocol::j1939::kNullAddress;
  std::atomic<uint64_t> foreign_{0};
  std::atomic<uint8_t> seen_own_{firmware_protocol::j1939::kNullAddress};
  std::atomic<uint8_t> seen_console_{firmware_protocol::j1939::kNullAddress};
  std::atomic<uint64_t> seen_tp_messages_{0};
  io::CanFrame frame_;
};

}  // namespace rise::hil
