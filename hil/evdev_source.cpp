#include "hil/evdev_source.hpp"

#include <span>
#include <utility>

#include "firmware_protocol/sdl_mapping.hpp"

namespace rise::hil {
namespace fp = rise::firmware_protocol;

namespace {
constexpr const char* kRumbleSignal = "ff_rumble";
}  // namespace

EvdevSource::EvdevSource(std::unique_ptr<io::EvdevDevice> device) : device_(std::move(device)) {}

ConnectionPolicy EvdevSource::connection_policy() const {
  ConnectionPolicy policy;
  policy.enumerate = true;
  if (!device_->hotplug_active())
    policy.unseen_arrivals = "no watch on /dev/input (" + device_->hotplug_error() + ")";
  return policy;
}

FeedbackPolicy EvdevSource::feedback_policy() const {
  FeedbackPolicy policy;
  policy.repeat = false;
  return policy;
}

// The SDL names of the device's line: "" when bound, else why there are none.
std::string EvdevSource::bind_sdl(SourcePanel& panel) {
  const panels::SourceDefinition& def = panel.definition().sources[panel.source()];
  if (def.mapping != "sdl" || !def.sdl_db) return {};
  for (const std::string& problem : def.sdl_db->problems()) panel.note(problem + " (line skipped)");
  const io::EvdevIdentity& id = device_->identity();
  const fp::SdlMapping* mapping = def.sdl_db->find_linux(id.bus, id.vendor_id, id.product_id, id.version);
  if (!mapping)
    return " (no platform:Linux line for SDL GUID " +
           fp::to_string(fp::sdl_linux_guid(id.bus, id.vendor_id, id.product_id, id.version)) + " in " +
           def.sdl_db_file + ")";
  panel.note(def.name + ": SDL mapping '" + mapping->name + "' (" + def.sdl_db_file + ":" +
             std::to_string(mapping->line) + ")");
  for (std::string& problem : signals_->add_sdl(*device_, *mapping))
    panel.note(def.name + ": " + std::move(problem) + " (" + def.sdl_db_file + ":" + std::to_string(mapping->line) +
               "): not mapped");
  return {};
}

// The rumble bound to this source plays through FF_RUMBLE; LEDs are not shown.
void EvdevSource::check_feedback(SourcePanel& panel) {
  const panels::PanelDefinition& def = panel.definition();
  rumble_ = false;
  for (const auto& led : def.leds)
    if (led.source == panel.source()) panel.note("LED '" + led.name + "': an evdev device shows no LED: not shown");
  for (const auto& r : def.rumbles) {
    if (r.source != panel.source()) continue;
    if (r.hid_signal != kRumbleSignal)
      panel.note("rumble '" + r.name + "': an evdev device's rumble is signal ff_rumble, not '" + r.hid_signal +
                 "': not shown");
    else if (!device_->has_rumble())
      panel.note("rumble '" + r.name + "': " + device_->path() + " has no FF_RUMBLE it lets us write: not shown");
    else
      rumble_ = true;
  }
}

io::IoStatus EvdevSource::reopen(SourcePanel& panel) {
  const io::IoStatus status = device_->reopen();
  if (status != io::IoStatus::Ok) return status;
  signals_.emplace(*device_);
  const std::string missing = bind_sdl(panel);
  values_.assign(signals_->names().size(), 0.0);
  panel.update([&](PanelMapper& mapper, int64_t) {
    mapper.attach_named(panel.source(), signals_->names(), nullptr, missing);
    return false;
  });
  opened_ = true;  // the state read at open goes to the panel with the first receive()
  check_feedback(panel);
  last_rumble_.reset();
  return status;
}

io::IoStatus EvdevSource::receive(SourcePanel& panel, int timeout_ms) {
  const bool first = std::exchange(opened_, false);
  io::IoStatus status = device_->read(first ? 0 : timeout_ms);
  if (first && status == io::IoStatus::Timeout) status = io::IoStatus::Ok;
  if (status == io::IoStatus::Ok) {
    signals_->read(*device_, values_);
    panel.update([&](PanelMapper& mapper, int64_t now_us) {
      return mapper.on_named_values(panel.source(), values_, now_us);
    });
  } else if (status == io::IoStatus::Timeout) {
    panel.update([&](PanelMapper& mapper, int64_t now_us) {
      mapper.on_named_alive(panel.source(), now_us);
      return false;
    });
  }
  return status;
}

io::IoStatus EvdevSource::send_feedback(SourcePanel&, const FeedbackRequest& request, const PanelSnapshot&,
                                        bool resend) {
  if (!resend && last_rumble_ == request.rumble) return io::IoStatus::Ok;
  const io::IoStatus status = device_->rumble(request.rumble, request.rumble);
  if (status == io::IoStatus::Ok) last_rumble_ = request.rumble;
  return status;
}

}  // namespace rise::hil
