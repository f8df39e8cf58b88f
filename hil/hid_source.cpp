#include "hil/hid_source.hpp"

#include <span>
#include <utility>

namespace rise::hil {
namespace fp = rise::firmware_protocol;

HidSource::HidSource(std::unique_ptr<io::InputDevice> device, const panels::PanelDefinition& definition,
                     std::size_t source)
    : device_(std::move(device)) {
  for (const auto& led : definition.leds) has_outputs_ = has_outputs_ || led.source == source;
  for (const auto& rumble : definition.rumbles) has_outputs_ = has_outputs_ || rumble.source == source;
}

ConnectionPolicy HidSource::connection_policy() const {
  ConnectionPolicy policy;
  policy.enumerate = true;
  if (!device_->hotplug_active()) policy.unseen_arrivals = "no USB hot-plug (" + device_->hotplug_error() + ")";
  return policy;
}

FeedbackPolicy HidSource::feedback_policy() const {
  FeedbackPolicy policy;
  policy.repeat = false;
  return policy;
}

io::IoStatus HidSource::reopen(SourcePanel& panel) {
  const io::IoStatus status = device_->reopen();
  if (status != io::IoStatus::Ok) return status;
  panel.update([&](PanelMapper& mapper, int64_t) {
    mapper.attach_hid(panel.source(), device_->report_descriptor());
    return false;
  });
  encoder_.reset();
  const fp::HidParseResult parsed = fp::parse_hid_descriptor(device_->report_descriptor());
  if (has_outputs_ && parsed) {
    encoder_.emplace(parsed.descriptor);
    for (std::string& problem : hid_feedback_problems(panel.definition(), panel.source(), *encoder_))
      panel.note(std::move(problem) + ": not shown");
  }
  return status;
}

io::IoStatus HidSource::receive(SourcePanel& panel, int timeout_ms) {
  std::size_t length = 0;
  const io::IoStatus status = device_->read(report_, length, timeout_ms);
  if (status == io::IoStatus::Ok)
    panel.update([&](PanelMapper& mapper, int64_t now_us) {
      return mapper.on_hid_report(panel.source(), std::span<const uint8_t>(report_.data(), length), now_us);
    });
  return status;
}

io::IoStatus HidSource::send_feedback(SourcePanel& panel, const FeedbackRequest& request,
                                      const PanelSnapshot& snapshot, bool resend) {
  std::vector<std::vector<uint8_t>> reports =
      build_hid_feedback(panel.definition(), panel.source(), request, snapshot, *encoder_);
  if (!resend && reports == last_written_) return io::IoStatus::Ok;
  io::IoStatus status = io::IoStatus::Ok;
  for (const auto& r : reports)
    if (const io::IoStatus s = device_->write(r); s != io::IoStatus::Ok) status = s;
  last_written_ = std::move(reports);
  return status;
}

}  // namespace rise::hil
