#include "hil/bridge.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <optional>
#include <string>
#include <utility>

#include "firmware_protocol/console_modbus.hpp"
#include "firmware_protocol/hid_report.hpp"
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

int64_t monotonic_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

Bridge::Bridge(panels::PanelDefinition definition, std::vector<std::unique_ptr<io::CanBus>> buses,
               PublishFn publish, BridgeSettings settings)
    : mapper_(std::move(definition)),
      buses_(std::move(buses)),
      publish_(std::move(publish)),
      settings_(settings) {
  modbus_links_.resize(buses_.size());
  hid_devices_.resize(buses_.size());
}

Bridge::Bridge(panels::PanelDefinition definition, std::vector<SourceTransport> transports, PublishFn publish,
               BridgeSettings settings)
    : mapper_(std::move(definition)), publish_(std::move(publish)), settings_(settings) {
  for (auto& t : transports) {
    buses_.push_back(std::move(t.can));
    modbus_links_.push_back(std::move(t.modbus));
    hid_devices_.push_back(std::move(t.hid));
  }
}

Bridge::~Bridge() { stop(); }

void Bridge::start() {
  if (running_.exchange(true)) return;
  for (std::size_t i = 0; i < buses_.size(); ++i) {
    if (modbus_links_[i])
      threads_.emplace_back([this, i] { modbus_source_loop(i); });
    else if (hid_devices_[i])
      threads_.emplace_back([this, i] { hid_source_loop(i); });
    else if (buses_[i])
      threads_.emplace_back([this, i] { source_loop(i); });
  }
  threads_.emplace_back([this] { publish_loop(); });
}

void Bridge::stop() {
  if (!running_.exchange(false)) return;
  wake_.notify_all();
  for (auto& t : threads_) t.join();
  threads_.clear();
}

void Bridge::set_feedback(FeedbackRequest request) {
  std::lock_guard lock(mutex_);
  feedback_ = std::move(request);
  ++feedback_version_;
}

PanelSnapshot Bridge::snapshot() const {
  std::lock_guard lock(mutex_);
  return mapper_.evaluate(monotonic_us());
}

std::string Bridge::inject_input_fault(InputFault fault) {
  std::string error;
  {
    std::lock_guard lock(mutex_);
    error = mapper_.inject_input_fault(std::move(fault));
    changed_ = true;
  }
  wake_.notify_all();
  return error;
}

std::size_t Bridge::clear_input_faults(const std::string& id) {
  std::size_t n;
  {
    std::lock_guard lock(mutex_);
    n = mapper_.clear_input_faults(id, monotonic_us());
    changed_ = true;
  }
  wake_.notify_all();
  return n;
}

std::vector<std::string> Bridge::take_notes() {
  std::lock_guard lock(mutex_);
  return std::exchange(notes_, {});
}

Bridge::FeedbackState Bridge::feedback_state(int64_t now_us) {
  std::lock_guard lock(mutex_);
  return {mapper_.evaluate(now_us), feedback_, feedback_version_};
}

void Bridge::note(std::string text) {
  std::lock_guard lock(mutex_);
  if (std::find(notes_seen_.begin(), notes_seen_.end(), text) != notes_seen_.end()) return;
  notes_seen_.push_back(text);
  notes_.push_back(std::move(text));
}

void Bridge::source_loop(std::size_t source) {
  const bool is_dbc = mapper_.definition().sources[source].is_dbc();
  io::CanBus& bus = *buses_[source];
  // Each source has its own encoder: our feedback frames carry their own
  // alive counters, as the console's do.
  fp::Encoder encoder(mapper_.definition().sources[source].node);
  int64_t retry_ms = settings_.reopen_min_ms;
  int64_t next_retry_us = 0;
  int64_t next_feedback_us = 0;
  uint64_t sent_version = ~0ull;
  FeedbackFrames last_sent;
  bool have_sent = false;
  io::CanFrame frame;

  std::string down_reason;  // the transport's error, read when it fails (not every loop)

  while (running_) {
    const int64_t now = monotonic_us();
    if (!bus.is_open()) {
      {
        std::lock_guard lock(mutex_);
        mapper_.on_connection(source, false, now, down_reason);
      }
      wake_.notify_all();
      if (now >= next_retry_us) {
        if (bus.reopen() == io::IoStatus::Ok) {
          retry_ms = settings_.reopen_min_ms;
          have_sent = false;
        } else {
          down_reason = bus.last_error();
          next_retry_us = now + retry_ms * 1000;
          retry_ms = std::min(retry_ms * 2, settings_.reopen_max_ms);
        }
      }
      if (!bus.is_open()) {
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
        continue;
      }
    }
    {
      std::lock_guard lock(mutex_);
      mapper_.on_connection(source, true, now);
    }

    // Feedback: repeated at its period, sent at once when it changes. A DBC
    // device gets none: our feedback frames are not in its database.
    if (!is_dbc && (now >= next_feedback_us || !have_sent)) {
      PanelSnapshot snap;
      FeedbackRequest request;
      uint64_t version;
      {
        std::lock_guard lock(mutex_);
        snap = mapper_.evaluate(now);
        request = feedback_;
        version = feedback_version_;
      }
      FeedbackFrames frames = build_feedback(mapper_.definition(), source, request, snap);
      const bool due = now >= next_feedback_us;
      if (due || !have_sent || version != sent_version || !same_frames(frames, last_sent)) {
        bus.send(to_can(encoder.next(frames.indicators)));
        for (const auto& d : frames.displays) bus.send(to_can(encoder.next(d)));
        last_sent = std::move(frames);
        sent_version = version;
        have_sent = true;
        if (due) next_feedback_us = now + settings_.feedback_period_ms * 1000;
      }
    }

    const io::IoStatus st = bus.receive(frame, 5);
    if (st == io::IoStatus::Ok) {
      bool changed;
      {
        std::lock_guard lock(mutex_);
        changed = apply_can_frame(mapper_, source, frame, monotonic_us());  // bus-off is published at once too
        changed_ = changed_ || changed;
      }
      if (changed) wake_.notify_all();
    } else if (st == io::IoStatus::Disconnected) {
      down_reason = bus.last_error();
      std::lock_guard lock(mutex_);
      mapper_.on_connection(source, false, monotonic_us(), down_reason);
    }
  }
}

// Counts a failed Modbus request; false when the link was closed. Caller holds mutex_.
bool Bridge::report_modbus(std::size_t source, const io::ModbusResult& result) {
  const io::ModbusLink& link = *modbus_links_[source];
  const int64_t now = monotonic_us();
  if (apply_modbus_result(mapper_, source, result, link.is_open(), now)) return true;
  // Closed: say why. A timeout that closed a TCP link is judged by the
  // source's age (apply_modbus_result leaves it connected), so not here.
  if (result.status != io::ModbusStatus::Timeout) mapper_.on_connection(source, false, now, link.last_error());
  return false;
}

void Bridge::modbus_source_loop(std::size_t source) {
  io::ModbusLink& link = *modbus_links_[source];
  const panels::SourceDefinition& def = mapper_.definition().sources[source];
  const auto poll_period_us = static_cast<int64_t>(1e6 / def.poll_hz);
  ModbusPoll poll(modbus_poll_reads(mapper_.definition(), source));
  ModbusFeedbackWriter device_feedback;  // a modbus device's LEDs and displays
  int64_t retry_ms = settings_.reopen_min_ms;
  int64_t next_retry_us = 0;
  int64_t next_poll_us = 0;
  int64_t next_feedback_us = 0;
  std::optional<uint16_t> last_counter;
  fp::ModbusFeedbackBlock last_sent;
  bool have_sent = false;
  std::array<uint8_t, fp::kModbusCoils> coils{};
  std::string down_reason;  // the link's error, read when it fails (not every loop)

  while (running_) {
    int64_t now = monotonic_us();
    if (!link.is_open()) {
      // Closed after a timeout (a late TCP answer must not be taken for the
      // next one) or lost. Reconnect at once when due; the source is marked
      // disconnected only when that fails, so one lost answer is judged by
      // the source's age (timeout_ms), not by this reconnect.
      last_counter.reset();
      have_sent = false;
      device_feedback.forget();
      bool reopened = false;
      if (now >= next_retry_us) {
        if (link.reopen() == io::ModbusStatus::Ok) {
          retry_ms = settings_.reopen_min_ms;
          reopened = true;
        } else {
          down_reason = link.last_error();
          next_retry_us = now + retry_ms * 1000;
          retry_ms = std::min(retry_ms * 2, settings_.reopen_max_ms);
        }
      }
      if (!reopened) {
        {
          std::lock_guard lock(mutex_);
          mapper_.on_connection(source, false, now, down_reason);
        }
        wake_.notify_all();
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
        continue;
      }
      std::lock_guard lock(mutex_);
      mapper_.on_connection(source, true, monotonic_us());
    }
    if (now < next_poll_us) {
      std::this_thread::sleep_for(std::chrono::microseconds(std::min<int64_t>(next_poll_us - now, 5000)));
      continue;
    }
    next_poll_us += poll_period_us;
    if (next_poll_us <= now) next_poll_us = now + poll_period_us;

    // Inputs: rise-modbus-v1's register block (under the map's CRC), then
    // the buttons; a modbus device's tables (modbus_poll.hpp).
    const io::ModbusResult r = poll.read(link);
    bool changed = false;
    {
      std::lock_guard lock(mutex_);
      now = monotonic_us();
      if (!report_modbus(source, r)) continue;
      mapper_.on_connection(source, true, now);
      if (r.ok()) {
        changed = apply_modbus_poll(mapper_, source, poll, last_counter, now);
        changed_ = changed_ || changed;
      }
    }
    if (changed) wake_.notify_all();

    // Feedback: written when it changes and repeated every feedback period.
    PanelSnapshot snap;
    FeedbackRequest request;
    {
      std::lock_guard lock(mutex_);
      snap = mapper_.evaluate(now);
      request = feedback_;
    }
    if (def.is_generic_modbus()) {
      // A device's own coils and registers: written when they change.
      const io::ModbusResult w =
          device_feedback.write(link, build_modbus_feedback(mapper_.definition(), source, request, snap));
      std::lock_guard lock(mutex_);
      report_modbus(source, w);
      continue;
    }
    const FeedbackFrames frames = build_feedback(mapper_.definition(), source, request, snap);
    const fp::ModbusFeedbackBlock block = fp::encode_feedback(frames.indicators, frames.displays);
    const bool due = now >= next_feedback_us;
    if (due || !have_sent || block.coil_bits != last_sent.coil_bits || block.holding != last_sent.holding) {
      for (std::size_t i = 0; i < coils.size(); ++i) coils[i] = static_cast<uint8_t>((block.coil_bits >> i) & 1u);
      io::ModbusResult w = link.write_coils(0, coils);
      if (w.ok()) w = link.write_registers(0, block.holding);
      std::lock_guard lock(mutex_);
      if (!report_modbus(source, w)) continue;
      if (w.ok()) {
        last_sent = block;
        have_sent = true;
        next_feedback_us = now + settings_.feedback_period_ms * 1000;
      }
    }
  }
}

void Bridge::hid_source_loop(std::size_t source) {
  io::InputDevice& device = *hid_devices_[source];
  const panels::PanelDefinition& definition = mapper_.definition();
  bool has_outputs = false;
  for (const auto& led : definition.leds) has_outputs = has_outputs || led.source == source;
  for (const auto& rumble : definition.rumbles) has_outputs = has_outputs || rumble.source == source;
  std::array<uint8_t, io::max_hid_report_bytes> report{};
  int64_t next_enumerate_us = 0;
  int64_t fast_until_us = 0;
  if (!device.hotplug_active())
    note(definition.sources[source].name + ": no USB hot-plug (" + device.hotplug_error() + "): enumerating every " +
         std::to_string(settings_.hid_enumerate_ms) + " ms");
  // Feedback: the LEDs' output reports, written on (re)open, when the
  // request changes and, checked every feedback period, when the panel's
  // own LEDs (fault, estop) change.
  std::optional<fp::HidOutputEncoder> encoder;
  std::vector<std::vector<uint8_t>> last_written;
  bool have_written = false;
  uint64_t written_version = ~0ull;
  int64_t next_feedback_us = 0;
  std::string down_reason;  // the device's error, read when it fails (not every loop)
  while (running_) {
    const int64_t now = monotonic_us();
    if (!device.is_open()) {
      {
        std::lock_guard lock(mutex_);
        mapper_.on_connection(source, false, now, down_reason);
      }
      wake_.notify_all();
      // Hot-plug by enumeration: cheap (a sysfs walk), so a fixed period
      // rather than the CAN back-off; after a USB arrival every 20 ms for a
      // second, as the hidraw node appears only once the kernel's HID driver
      // has bound the new device's interface.
      if (now >= next_enumerate_us) {
        next_enumerate_us = now + (now < fast_until_us ? 20'000 : settings_.hid_enumerate_ms * 1000);
        if (device.reopen() != io::IoStatus::Ok) {
          down_reason = device.last_error();
        } else {
          {
            std::lock_guard lock(mutex_);
            // A descriptor without a bound name keeps the source failsafe
            // with the mapper's reason; it is checked again on the next plug.
            mapper_.attach_hid(source, device.report_descriptor());
            mapper_.on_connection(source, true, monotonic_us());
          }
          encoder.reset();
          have_written = false;
          const fp::HidParseResult parsed = fp::parse_hid_descriptor(device.report_descriptor());
          if (has_outputs && parsed) {
            encoder.emplace(parsed.descriptor);
            for (std::string& problem : hid_feedback_problems(definition, source, *encoder))
              note(std::move(problem) + ": not shown");
          }
        }
      }
      if (!device.is_open()) {
        if (device.wait_for_arrival(5)) {
          next_enumerate_us = 0;
          fast_until_us = monotonic_us() + 1'000'000;
        }
        continue;
      }
    }
    bool feedback_due = false;
    if (encoder) {
      std::lock_guard lock(mutex_);
      feedback_due = !have_written || now >= next_feedback_us || written_version != feedback_version_;
    }
    if (feedback_due) {
      const FeedbackState state = feedback_state(now);
      next_feedback_us = now + settings_.feedback_period_ms * 1000;
      std::vector<std::vector<uint8_t>> reports =
          build_hid_feedback(definition, source, state.request, state.snapshot, *encoder);
      if (!have_written || reports != last_written) {
        bool ok = true;
        for (const auto& r : reports) ok = device.write(r) == io::IoStatus::Ok && ok;
        have_written = ok;  // a failed write is tried again at the next check
        last_written = std::move(reports);
      }
      written_version = state.version;
    }
    std::size_t length = 0;
    const io::IoStatus st = device.read(report, length, 5);
    if (st == io::IoStatus::Ok) {
      bool changed;
      {
        std::lock_guard lock(mutex_);
        changed = mapper_.on_hid_report(source, std::span<const uint8_t>(report.data(), length), monotonic_us());
        changed_ = changed_ || changed;
      }
      if (changed) wake_.notify_all();
    } else if (st == io::IoStatus::Disconnected) {
      down_reason = device.last_error();
      {
        std::lock_guard lock(mutex_);
        mapper_.on_connection(source, false, monotonic_us(), down_reason);
        changed_ = true;  // publish the loss now, not at the next tick
      }
      wake_.notify_all();
    }
  }
}

void Bridge::publish_loop() {
  using Clock = std::chrono::steady_clock;
  const auto period = std::chrono::microseconds(mapper_.definition().publish_period_us());
  const auto gap = std::chrono::microseconds(settings_.min_change_gap_us);
  auto next_tick = Clock::now();
  auto last_publish = Clock::now() - gap;
  while (running_) {
    PanelSnapshot snap;
    {
      std::unique_lock lock(mutex_);
      // Publish on the tick, or as soon as a control changed — but not
      // sooner than `gap` after the last message, so a chattering console
      // cannot flood the network. A change inside the gap is published when
      // the gap ends, not at the next tick.
      while (running_) {
        const auto now = Clock::now();
        if (now >= next_tick || (changed_ && now - last_publish >= gap)) break;
        const auto deadline = changed_ ? std::min(next_tick, last_publish + gap) : next_tick;
        wake_.wait_until(lock, deadline);
      }
      if (!running_) break;
      changed_ = false;
      snap = mapper_.evaluate(monotonic_us());
    }
    const auto now = Clock::now();
    if (now >= next_tick) {
      next_tick += period;
      if (next_tick < now) next_tick = now + period;  // overrun: skip, do not burst
    }
    last_publish = now;
    publish_(snap);
  }
}
}  // namespace rise::hil
