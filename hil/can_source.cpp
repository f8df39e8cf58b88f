#include "hil/can_source.hpp"

#include <algorithm>
#include <utility>

#include "hil/source_input.hpp"

namespace rise::hil {
namespace {
namespace fp = rise::firmware_protocol;

bool same_frames(const FeedbackFrames& a, const FeedbackFrames& b) {
  if (a.indicators.leds_on != b.indicators.leds_on || a.indicators.buzzer != b.indicators.buzzer ||
      a.displays.size() != b.displays.size())
    return false;
  for (std::size_t i = 0; i < a.displays.size(); ++i)
    if (a.displays[i].raw != b.displays[i].raw || a.displays[i].index != b.displays[i].index)
      return false;
  return true;
}

io::CanFrame to_can(const fp::WireFrame& w) {
  io::CanFrame f;
  f.id = w.can_id;
  f.len = static_cast<uint8_t>(w.data.size());
  std::copy(w.data.begin(), w.data.end(), f.data.begin());
  return f;
}
}  // namespace

CanSource::CanSource(std::unique_ptr<io::CanBus> bus, const panels::PanelDefinition& definition,
                     std::size_t source)
    : bus_(std::move(bus)),
      dbc_(definition.sources[source].is_dbc()),
      encoder_(definition.sources[source].node) {}

io::IoStatus CanSource::receive(SourcePanel& panel, int timeout_ms) {
  const io::IoStatus status = bus_->receive(frame_, timeout_ms);
  // Bus-off is published at once too.
  if (status == io::IoStatus::Ok)
    panel.update([&](PanelMapper& mapper, int64_t now_us) {
      return apply_can_frame(mapper, panel.source(), frame_, now_us);
    });
  return status;
}

io::IoStatus CanSource::send_feedback(SourcePanel& panel, const FeedbackRequest& request,
                                      const PanelSnapshot& snapshot, bool resend) {
  FeedbackFrames frames = build_feedback(panel.definition(), panel.source(), request, snapshot);
  if (!resend && last_sent_ && same_frames(frames, *last_sent_)) return io::IoStatus::Ok;
  bus_->send(to_can(encoder_.next(frames.indicators)));
  for (const auto& d : frames.displays) bus_->send(to_can(encoder_.next(d)));
  last_sent_ = std::move(frames);
  return io::IoStatus::Ok;
}

}  // namespace rise::hil
