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

bool SessionRecorder::record_source(const std::string& name, SourceTransport& transport, int modbus_unit) {
  if (transport.can) {
    const std::string path = dir_ + "/" + name + ".log";
    // Stamped when read: the time the bridge decoded the frame at, which is
    // what a verified replay must reproduce (the kernel's stamp is earlier
    // by the queueing; a plain candump beside the daemon records that).
    auto bus = std::make_unique<io::RecordingBus>(std::move(transport.can), path, name, io::RecordingBus::Stamp::Receive);
    buses_.push_back(bus.get());
    transport.can = std::move(bus);
    files_.push_back(path);
    return true;
  }
  if (transport.modbus) {
    const std::string path = dir_ + "/" + name + ".modbus.log";
    auto link = std::make_unique<io::RecordingModbusLink>(std::move(transport.modbus), path, name, modbus_unit);
    links_.push_back(link.get());
    transport.modbus = std::move(link);
    files_.push_back(path);
    return true;
  }
  if (transport.hid) {
    const std::string path = dir_ + "/" + name + ".hid";
    auto device = std::make_unique<io::RecordingInputDevice>(std::move(transport.hid), path, name);
    hid_devices_.push_back(device.get());
    transport.hid = std::move(device);
    files_.push_back(path);
    return true;
  }
  return false;
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
