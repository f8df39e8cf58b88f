#include "hil/modbus_source.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <thread>
#include <utility>

#include "hil/bridge.hpp"
#include "hil/source_input.hpp"
#include "msgs/clock.hpp"

namespace rise::hil {
namespace fp = rise::firmware_protocol;

ModbusSource::ModbusSource(std::unique_ptr<io::ModbusLink> link, const panels::PanelDefinition& definition,
                           std::size_t source)
    : link_(std::move(link)),
      generic_(definition.sources[source].is_generic_modbus()),
      poll_period_us_(static_cast<int64_t>(1e6 / definition.sources[source].poll_hz)),
      poll_(modbus_poll_reads(definition, source)) {}

ConnectionPolicy ModbusSource::connection_policy() const {
  ConnectionPolicy policy;
  policy.up_while_open = false;
  policy.closed_is_down = false;
  return policy;
}

FeedbackPolicy ModbusSource::feedback_policy() const {
  FeedbackPolicy policy;
  policy.after_each_poll = true;
  policy.repeat = !generic_;
  return policy;
}

io::IoStatus ModbusSource::reopen(SourcePanel&) {
  // The console may have restarted: its alive counter, and what it shows.
  last_counter_.reset();
  device_feedback_.forget();
  last_sent_.reset();
  return link_->reopen() == io::ModbusStatus::Ok ? io::IoStatus::Ok : io::IoStatus::Disconnected;
}

io::IoStatus ModbusSource::outcome(const io::ModbusResult& result, bool open) const {
  if (result.ok()) return io::IoStatus::Ok;
  if (open) return io::IoStatus::Error;
  // A timeout that closed a TCP link is judged by the source's age
  // (apply_modbus_result leaves it connected), so it is no loss.
  return result.status == io::ModbusStatus::Timeout ? io::IoStatus::Timeout : io::IoStatus::Disconnected;
}

io::IoStatus ModbusSource::receive(SourcePanel& panel, int timeout_ms) {
  const int64_t now = msgs::monotonic_us();
  if (now < next_poll_us_) {
    std::this_thread::sleep_for(std::chrono::microseconds(std::min<int64_t>(next_poll_us_ - now, timeout_ms * 1000)));
    return io::IoStatus::Timeout;
  }
  next_poll_us_ += poll_period_us_;
  if (next_poll_us_ <= now) next_poll_us_ = now + poll_period_us_;

  // Inputs: rise-modbus-v1's register block (under the map's CRC), then
  // the buttons; a modbus device's tables (modbus_poll.hpp).
  const io::ModbusResult r = poll_.read(*link_);
  bool open = true;
  panel.update([&](PanelMapper& mapper, int64_t now_us) {
    open = apply_modbus_result(mapper, panel.source(), r, link_->is_open(), now_us);
    if (!open) return false;
    mapper.on_connection(panel.source(), true, now_us);
    return r.ok() && apply_modbus_poll(mapper, panel.source(), poll_, last_counter_, now_us);
  });
  const io::IoStatus status = outcome(r, open);
  return status == io::IoStatus::Error ? io::IoStatus::Ok : status;  // a failed poll is counted: go on
}

io::IoStatus ModbusSource::send_feedback(SourcePanel& panel, const FeedbackRequest& request,
                                         const PanelSnapshot& snapshot, bool resend) {
  io::ModbusResult w;
  if (generic_) {
    // A device's own coils and registers: written when they change.
    w = device_feedback_.write(*link_, build_modbus_feedback(panel.definition(), panel.source(), request, snapshot));
  } else {
    const FeedbackFrames frames = build_feedback(panel.definition(), panel.source(), request, snapshot);
    const fp::ModbusFeedbackBlock block = fp::encode_feedback(frames.indicators, frames.displays);
    if (!resend && last_sent_ && block.coil_bits == last_sent_->coil_bits && block.holding == last_sent_->holding)
      return io::IoStatus::Ok;
    w = write_block(block);
    if (w.ok()) last_sent_ = block;
  }
  bool open = true;
  panel.update([&](PanelMapper& mapper, int64_t now_us) {
    open = apply_modbus_result(mapper, panel.source(), w, link_->is_open(), now_us);
    return false;
  });
  return outcome(w, open);
}

io::ModbusResult ModbusSource::write_block(const fp::ModbusFeedbackBlock& block) {
  std::array<uint8_t, fp::kModbusCoils> coils{};
  for (std::size_t i = 0; i < coils.size(); ++i) coils[i] = static_cast<uint8_t>((block.coil_bits >> i) & 1u);
  io::ModbusResult w = link_->write_coils(0, coils);
  if (w.ok()) w = link_->write_registers(0, block.holding);
  return w;
}

}  // namespace rise::hil
