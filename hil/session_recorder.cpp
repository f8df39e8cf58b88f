#include "hil/session_recorder.hpp"

#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <system_error>

namespace rise::hil {
namespace {
std::string make_dir(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir))
    throw std::runtime_error(dir + ": cannot create the recording directory" + (ec ? " (" + ec.message() + ")" : ""));
  return dir;
}
}  // namespace

SessionRecorder::SessionRecorder(std::string dir)
    : dir_(make_dir(dir)), log_(dir_ + "/panel_state.lcmlog", "w"), last_flush_(std::chrono::steady_clock::now()) {
  if (!log_.good()) throw std::runtime_error(dir_ + "/panel_state.lcmlog: cannot create the LCM log");
  files_.push_back(dir_ + "/panel_state.lcmlog");
}

// Puts the recorder of a source's kind around its io object.
class SessionRecorder::SourceRecorder final : public IoDecorator {
 public:
  SourceRecorder(SessionRecorder& recorder, const std::string& name, int modbus_unit)
      : recorder_(recorder), name_(name), modbus_unit_(modbus_unit) {}
  bool recorded() const { return recorded_; }

  std::unique_ptr<io::CanBus> wrap(std::unique_ptr<io::CanBus> bus) override {
    const std::string path = path_of(".log");
    // Stamped when read: the time the bridge decoded the frame at, which is
    // what a verified replay must reproduce (the kernel's stamp is earlier
    // by the queueing; a plain candump beside the daemon records that).
    auto recording = std::make_unique<io::RecordingBus>(std::move(bus), path, name_, io::RecordingBus::Stamp::Receive);
    recorder_.buses_.push_back(recording.get());
    listed(path);
    return recording;
  }
  std::unique_ptr<io::ModbusLink> wrap(std::unique_ptr<io::ModbusLink> link) override {
    const std::string path = path_of(".modbus.log");
    auto recording = std::make_unique<io::RecordingModbusLink>(std::move(link), path, name_, modbus_unit_);
    recorder_.links_.push_back(recording.get());
    listed(path);
    return recording;
  }
  std::unique_ptr<io::InputDevice> wrap(std::unique_ptr<io::InputDevice> device) override {
    const std::string path = path_of(".hid");
    auto recording = std::make_unique<io::RecordingInputDevice>(std::move(device), path, name_);
    recorder_.hid_devices_.push_back(recording.get());
    listed(path);
    return recording;
  }

 private:
  std::string path_of(const char* suffix) const { return recorder_.dir_ + "/" + name_ + suffix; }
  void listed(const std::string& path) {
    recorder_.files_.push_back(path);
    recorded_ = true;
  }
  SessionRecorder& recorder_;
  const std::string& name_;
  int modbus_unit_;
  bool recorded_ = false;
};

bool SessionRecorder::record_source(const std::string& name, SourceTransport& transport, int modbus_unit) {
  SourceRecorder recorder(*this, name, modbus_unit);
  transport.decorate(recorder);
  return recorder.recorded();
}

void SessionRecorder::record_message(const std::string& channel, const rise_msgs::PanelState& message) {
  const int size = message.getEncodedSize();
  if (buffer_.size() < static_cast<std::size_t>(size)) buffer_.resize(static_cast<std::size_t>(size));
  if (message.encode(buffer_.data(), 0, size) != size) {
    ++lcm_errors_;
    return;
  }
  if (event_.channel != channel) event_.channel = channel;
  event_.eventnum = lcm_events_.load();
  event_.timestamp = message.utime;
  event_.datalen = size;
  event_.data = buffer_.data();
  if (log_.writeEvent(&event_) != 0) {
    ++lcm_errors_;
    return;
  }
  // Flushed at least every 100 ms, like the other recorders.
  const auto now = std::chrono::steady_clock::now();
  if (now - last_flush_ >= std::chrono::milliseconds(100)) {
    if (std::fflush(log_.getFilePtr()) != 0) ++lcm_errors_;
    last_flush_ = now;
  }
  ++lcm_events_;
}

SessionRecorder::Counts SessionRecorder::counts() const {
  Counts c;
  for (const auto* b : buses_) {
    c.can_frames += b->frames_recorded();
    c.write_errors += b->write_errors();
  }
  for (const auto* l : links_) {
    c.modbus_lines += l->lines_recorded();
    c.write_errors += l->write_errors();
  }
  for (const auto* h : hid_devices_) {
    c.hid_reports += h->reports_recorded();
    c.write_errors += h->write_errors();
  }
  c.lcm_events = lcm_events_;
  c.write_errors += lcm_errors_;
  return c;
}

}  // namespace rise::hil
