#include "hil/canopen_source.hpp"

#include <algorithm>
#include <utility>

#include "firmware_protocol/canopen_eds.hpp"
#include "hil/source_input.hpp"
#include "msgs/clock.hpp"

namespace rise::hil {
namespace {
namespace co = rise::firmware_protocol::canopen;

io::CanFrame to_can(const co::Frame& f) {
  io::CanFrame c;
  c.id = f.cob_id;
  c.extended = f.extended;
  c.len = f.len;
  std::copy(f.data.begin(), f.data.end(), c.data.begin());
  return c;
}

bool same_frames(const std::vector<co::Frame>& a, const std::vector<co::Frame>& b) {
  return std::equal(a.begin(), a.end(), b.begin(), b.end(), [](const co::Frame& x, const co::Frame& y) {
    return x.cob_id == y.cob_id && x.extended == y.extended && x.len == y.len && x.data == y.data;
  });
}

bool has_pdo_feedback(const panels::PanelDefinition& definition, std::size_t source) {
  return std::any_of(definition.leds.begin(), definition.leds.end(),
                     [&](const auto& l) { return l.source == source && l.pdo_signal; }) ||
         std::any_of(definition.displays.begin(), definition.displays.end(),
                     [&](const auto& d) { return d.source == source && d.pdo_signal; });
}
}  // namespace

CanopenSource::CanopenSource(std::unique_ptr<io::CanBus> bus, const panels::PanelDefinition& definition,
                             std::size_t source)
    : bus_(std::move(bus)),
      master_(definition.sources[source].node, 1000 * static_cast<int64_t>(definition.sources[source].timeout_ms),
              definition.sources[source].eds && definition.sources[source].eds->has_sync_tpdo()
                  ? static_cast<int64_t>(definition.sources[source].sync_period_us)
                  : 0),
      shows_feedback_(has_pdo_feedback(definition, source)) {}

io::IoStatus CanopenSource::reopen(SourcePanel&) {
  const io::IoStatus status = bus_->reopen();
  started_ = false;  // the node is reset at the first receive on the new bus
  last_sent_.reset();
  return status;
}

void CanopenSource::send_due(int64_t now_us) {
  while (const std::optional<co::Frame> frame = master_.next(now_us)) bus_->send(to_can(*frame));
}

io::IoStatus CanopenSource::receive(SourcePanel& panel, int timeout_ms) {
  int64_t now_us = msgs::monotonic_us();
  if (!started_) {
    master_.opened(now_us);
    started_ = true;
  }
  send_due(now_us);
  const int64_t until_sync_ms = (master_.next_due_us() - now_us + 999) / 1000;
  const int wait_ms = static_cast<int>(std::clamp<int64_t>(until_sync_ms, 0, timeout_ms));
  const io::IoStatus status = bus_->receive(frame_, wait_ms);
  if (status != io::IoStatus::Ok) return status;
  if (!frame_.error && !frame_.remote && !frame_.extended)
    master_.on_frame(frame_.id, std::span<const uint8_t>(frame_.data.data(), frame_.len), msgs::monotonic_us());
  panel.update([&](PanelMapper& mapper, int64_t now) { return apply_can_frame(mapper, panel.source(), frame_, now); });
  // A boot-up is answered at once, not at the next SYNC.
  now_us = msgs::monotonic_us();
  send_due(now_us);
  return status;
}

io::IoStatus CanopenSource::send_feedback(SourcePanel& panel, const FeedbackRequest& request,
                                          const PanelSnapshot& snapshot, bool resend) {
  std::vector<co::Frame> frames = build_canopen_feedback(panel.definition(), panel.source(), request, snapshot);
  if (!resend && last_sent_ && same_frames(frames, *last_sent_)) return io::IoStatus::Ok;
  for (const co::Frame& f : frames) bus_->send(to_can(f));
  last_sent_ = std::move(frames);
  return io::IoStatus::Ok;
}

}  // namespace rise::hil
