#pragma once

// A CAN source's transport (rise-can-v1, dbc) for the bridge's source loop:
// each received frame goes to the panel (source_input.hpp), the feedback
// goes out as rise-can-v1 frames with their own alive counters, as the
// console's do, repeated every feedback period. A dbc device gets none: our
// feedback frames are not in its database.

#include <memory>
#include <optional>

#include "firmware_protocol/console_can.hpp"
#include "hil/io/can_bus.hpp"
#include "hil/source_transport.hpp"

namespace rise::hil {

class CanSource final : public SourceTransport {
 public:
  /// `bus` carries source `source` of `definition`.
  CanSource(std::unique_ptr<io::CanBus> bus, const panels::PanelDefinition& definition, std::size_t source);

  bool is_open() const override { return bus_->is_open(); }
  io::IoStatus reopen(SourcePanel&) override { return bus_->reopen(); }
  std::string last_error() const override { return bus_->last_error(); }
  io::IoStatus receive(SourcePanel& panel, int timeout_ms) override;
  bool shows_feedback() const override { return !dbc_; }
  /// CAN is fire and forget: a frame the bus did not take goes out again at
  /// the next period, so this is always Ok.
  io::IoStatus send_feedback(SourcePanel& panel, const FeedbackRequest& request, const PanelSnapshot& snapshot,
                             bool resend) override;
  void decorate(IoDecorator& decorator) override { bus_ = decorator.wrap(std::move(bus_)); }

 private:
  std::unique_ptr<io::CanBus> bus_;
  bool dbc_;
  firmware_protocol::Encoder encoder_;  // the alive counters of our feedback frames
  std::optional<FeedbackFrames> last_sent_;
  io::CanFrame frame_;
};

}  // namespace rise::hil
