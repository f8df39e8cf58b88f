#pragma once

// A canopen source's transport for the bridge's source loop: the bridge is
// the node's NMT master and SYNC producer (firmware_protocol::canopen::
// NmtMaster: reset communication at open, NMT Start on boot-up and on the
// node's return, SYNC every sync period when a TPDO is synchronous); every
// received frame goes to the panel (heartbeat → NMT state, TPDOs → the
// bound objects; source_input.hpp); the feedback goes out as RPDOs
// (build_canopen_feedback), repeated every feedback period.

#include <memory>
#include <optional>
#include <vector>

#include "firmware_protocol/canopen.hpp"
#include "hil/io/can_bus.hpp"
#include "hil/source_transport.hpp"

namespace rise::hil {

class CanopenSource final : public SourceTransport {
 public:
  /// `bus` carries source `source` (protocol canopen) of `definition`.
  CanopenSource(std::unique_ptr<io::CanBus> bus, const panels::PanelDefinition& definition, std::size_t source);

  bool is_open() const override { return bus_->is_open(); }
  io::IoStatus reopen(SourcePanel& panel) override;
  std::string last_error() const override { return bus_->last_error(); }
  /// Sends what the NMT master has due (NMT, SYNC), then waits for a frame
  /// up to timeout_ms but not past the next SYNC.
  io::IoStatus receive(SourcePanel& panel, int timeout_ms) override;
  bool shows_feedback() const override { return shows_feedback_; }
  /// CAN is fire and forget: a frame the bus did not take goes out again at
  /// the next period, so this is always Ok.
  io::IoStatus send_feedback(SourcePanel& panel, const FeedbackRequest& request, const PanelSnapshot& snapshot,
                             bool resend) override;
  void decorate(IoDecorator& decorator) override { bus_ = decorator.wrap(std::move(bus_)); }

  const firmware_protocol::canopen::NmtMaster& master() const { return master_; }

 private:
  void send_due(int64_t now_us);

  std::unique_ptr<io::CanBus> bus_;
  firmware_protocol::canopen::NmtMaster master_;
  bool shows_feedback_ = false;
  bool started_ = false;  // opened() told to the master since the bus opened
  std::optional<std::vector<firmware_protocol::canopen::Frame>> last_sent_;
  io::CanFrame frame_;
};

}  // namespace rise::hil
