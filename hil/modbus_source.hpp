#pragma once

// A Modbus source's transport (rise-modbus-v1, modbus) for the bridge's
// source loop: polled at the source's poll_hz (modbus_poll.hpp), each
// poll's answers to the panel (source_input.hpp), the feedback written
// after a poll: rise-modbus-v1's coils and holding registers when they
// change and every feedback period, a modbus device's own points when they
// change (ModbusFeedbackWriter). A request's failure is counted; a link
// left closed by a timeout is reopened at once (ConnectionPolicy), one closed
// by anything else is lost.

#include <cstdint>
#include <memory>
#include <optional>

#include "firmware_protocol/console_modbus.hpp"
#include "hil/io/modbus_link.hpp"
#include "hil/modbus_poll.hpp"
#include "hil/source_transport.hpp"

namespace rise::hil {

class ModbusSource final : public SourceTransport {
 public:
  /// `link` reaches source `source` of `definition`. Used from one thread
  /// only, as libmodbus contexts are.
  ModbusSource(std::unique_ptr<io::ModbusLink> link, const panels::PanelDefinition& definition, std::size_t source);

  bool is_open() const override { return link_->is_open(); }
  io::IoStatus reopen(SourcePanel& panel) override;
  std::string last_error() const override { return link_->last_error(); }
  ConnectionPolicy connection_policy() const override;
  /// Sleeps until the next poll is due (at most timeout_ms; Timeout), then polls.
  io::IoStatus receive(SourcePanel& panel, int timeout_ms) override;
  bool shows_feedback() const override { return true; }
  FeedbackPolicy feedback_policy() const override;
  io::IoStatus send_feedback(SourcePanel& panel, const FeedbackRequest& request, const PanelSnapshot& snapshot,
                             bool resend) override;
  void decorate(IoDecorator& decorator) override { link_ = decorator.wrap(std::move(link_)); }

 private:
  // A request's result, counted (apply_modbus_result, which says whether
  // the link is still `open`), as one status: Ok for an answer, Error for a
  // failure that left the link open, Timeout when a timeout closed it (a
  // clean restart), Disconnected when anything else did.
  io::IoStatus outcome(const io::ModbusResult& result, bool open) const;
  // rise-modbus-v1's feedback: coils 0.., then holding registers 0...
  io::ModbusResult write_block(const firmware_protocol::ModbusFeedbackBlock& block);

  std::unique_ptr<io::ModbusLink> link_;
  bool generic_;  // a third-party device ("modbus"), not rise-modbus-v1
  int64_t poll_period_us_;
  int64_t next_poll_us_ = 0;
  ModbusPoll poll_;
  std::optional<uint16_t> last_counter_;
  ModbusFeedbackWriter device_feedback_;  // a modbus device's LEDs and displays
  std::optional<firmware_protocol::ModbusFeedbackBlock> last_sent_;
};

}  // namespace rise::hil
