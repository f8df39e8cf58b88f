#include "hil/io/uhid_device.hpp"

#include <fcntl.h>
#include <linux/uhid.h>
#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstddef>
#include <cstring>
#include <memory>
#include <stdexcept>

namespace rise::hil::io {
namespace {

// uhid's report types are ours in the same order (UHID_FEATURE_REPORT = 0,
// UHID_OUTPUT_REPORT = 1, UHID_INPUT_REPORT = 2).
UhidReportType report_type(uint8_t rtype) {
  switch (rtype) {
    case UHID_FEATURE_REPORT: return UhidReportType::Feature;
    case UHID_INPUT_REPORT: return UhidReportType::Input;
    default: return UhidReportType::Output;
  }
}

void copy_text(const std::string& text, uint8_t* out, std::size_t capacity) {
  std::memcpy(out, text.data(), std::min(text.size(), capacity - 1));
}

}  // namespace

UhidDevice::UhidDevice(UhidSettings settings) : settings_(std::move(settings)) {
  uhid_event ev{};
  auto check = [](const std::string& text, std::size_t capacity, const char* what) {
    if (text.size() >= capacity)
      throw std::invalid_argument(std::string("uhid: ") + what + " longer than " + std::to_string(capacity - 1) +
                                  " bytes");
  };
  check(settings_.name, sizeof ev.u.create2.name, "name");
  check(settings_.uniq, sizeof ev.u.create2.uniq, "uniq");
  check(settings_.phys, sizeof ev.u.create2.phys, "phys");
  if (settings_.descriptor.empty() || settings_.descriptor.size() > sizeof ev.u.create2.rd_data)
    throw std::invalid_argument("uhid: the report descriptor must be 1.." +
                                std::to_string(sizeof ev.u.create2.rd_data) + " bytes");
  event_buffer_.resize(sizeof(uhid_event));
}

UhidDevice::~UhidDevice() { destroy(); }

bool UhidDevice::write_event(const void* event, std::size_t size) {
  // /dev/uhid takes one whole event per write(); a short event is padded
  // with zeros by the kernel.
  const ssize_t n = ::write(fd_, event, size);
  if (n == static_cast<ssize_t>(size)) return true;
  error_.set("/dev/uhid: write failed: %s", n < 0 ? detail::errno_text(errno) : "short write");
  return false;
}

IoStatus UhidDevice::create() {
  destroy();
  fd_ = ::open("/dev/uhid", O_RDWR | O_CLOEXEC | O_NONBLOCK);
  if (fd_ < 0) {
    error_.set("/dev/uhid: %s", detail::errno_text(errno));
    return IoStatus::Error;
  }
  auto ev = std::make_unique<uhid_event>();
  std::memset(ev.get(), 0, sizeof(uhid_event));
  ev->type = UHID_CREATE2;
  copy_text(settings_.name, ev->u.create2.name, sizeof ev->u.create2.name);
  copy_text(settings_.uniq, ev->u.create2.uniq, sizeof ev->u.create2.uniq);
  copy_text(settings_.phys, ev->u.create2.phys, sizeof ev->u.create2.phys);
  ev->u.create2.rd_size = static_cast<uint16_t>(settings_.descriptor.size());
  ev->u.create2.bus = settings_.bus;
  ev->u.create2.vendor = settings_.vendor_id;
  ev->u.create2.product = settings_.product_id;
  ev->u.create2.version = settings_.version;
  ev->u.create2.country = settings_.country;
  std::memcpy(ev->u.create2.rd_data, settings_.descriptor.data(), settings_.descriptor.size());
  if (!write_event(ev.get(), sizeof(uhid_event))) {
    detail::close_fd(fd_);
    return IoStatus::Error;
  }
  error_.clear();
  return IoStatus::Ok;
}

void UhidDevice::destroy() {
  if (fd_ < 0) return;
  uint32_t type = UHID_DESTROY;
  (void)::write(fd_, &type, sizeof type);  // closing /dev/uhid destroys it as well
  detail::close_fd(fd_);
  started_ = false;
  open_count_ = 0;
  dev_flags_ = 0;
}

UhidDevice::StoredReport* UhidDevice::find_stored(UhidReportType type, uint8_t id) {
  for (StoredReport& r : stored_)
    if (r.type == type && r.id == id) return &r;
  return nullptr;
}

void UhidDevice::set_report(UhidReportType type, uint8_t report_id, std::span<const uint8_t> report) {
  std::lock_guard lock(stored_mutex_);
  if (StoredReport* r = find_stored(type, report_id)) {
    r->bytes.assign(report.begin(), report.end());
    return;
  }
  stored_.push_back({type, report_id, std::vector<uint8_t>(report.begin(), report.end())});
}

IoStatus UhidDevice::send_input(std::span<const uint8_t> report) {
  if (fd_ < 0) {
    error_.set("uhid: not created");
    return IoStatus::Error;
  }
  uhid_event ev;
  if (report.empty() || report.size() > sizeof ev.u.input2.data) {
    error_.set("uhid: an input report must be 1..%zu bytes", sizeof ev.u.input2.data);
    return IoStatus::Error;
  }
  ev.type = UHID_INPUT2;
  ev.u.input2.size = static_cast<uint16_t>(report.size());
  std::memcpy(ev.u.input2.data, report.data(), report.size());
  if (!write_event(&ev, offsetof(uhid_event, u.input2.data) + report.size())) return IoStatus::Error;
  const uint8_t id = (dev_flags_ & UHID_DEV_NUMBERED_INPUT_REPORTS) != 0 ? report[0] : 0;
  std::lock_guard lock(stored_mutex_);
  if (StoredReport* r = find_stored(UhidReportType::Input, id); r && r->bytes.size() == report.size())
    std::copy(report.begin(), report.end(), r->bytes.begin());
  return IoStatus::Ok;
}

IoStatus UhidDevice::poll(UhidEvent& event, int timeout_ms) {
  if (fd_ < 0) return IoStatus::Disconnected;
  const IoStatus ready = detail::wait_fd(fd_, POLLIN, timeout_ms);
  if (ready == IoStatus::Timeout) return IoStatus::Timeout;
  if (ready != IoStatus::Ok) {
    error_.set("/dev/uhid: poll failed: %s", detail::errno_text(errno));
    return IoStatus::Disconnected;
  }
  auto* ev = reinterpret_cast<uhid_event*>(event_buffer_.data());
  std::fill(event_buffer_.begin(), event_buffer_.end(), uint8_t{0});  // a short event reads as zero-padded
  const ssize_t n = ::read(fd_, ev, sizeof(uhid_event));
  if (n < 0) {
    if (errno == EAGAIN || errno == EINTR) return IoStatus::Timeout;
    error_.set("/dev/uhid: read failed: %s", detail::errno_text(errno));
    return IoStatus::Disconnected;
  }
  if (n < static_cast<ssize_t>(sizeof ev->type)) return IoStatus::Timeout;

  event = UhidEvent{};
  switch (ev->type) {
    case UHID_START:
      started_ = true;
      dev_flags_ = ev->u.start.dev_flags;
      event.kind = UhidEvent::Kind::Start;
      return IoStatus::Ok;
    case UHID_STOP:
      started_ = false;
      event.kind = UhidEvent::Kind::Stop;
      return IoStatus::Ok;
    case UHID_OPEN:
      ++open_count_;
      event.kind = UhidEvent::Kind::Open;
      return IoStatus::Ok;
    case UHID_CLOSE:
      if (open_count_ > 0) --open_count_;
      event.kind = UhidEvent::Kind::Close;
      return IoStatus::Ok;
    case UHID_OUTPUT:
      event.kind = UhidEvent::Kind::Output;
      event.report_type = report_type(ev->u.output.rtype);
      event.data = std::span<const uint8_t>(ev->u.output.data,
                                            std::min<std::size_t>(ev->u.output.size, UHID_DATA_MAX));
      event.report_id = event.data.empty() ? 0 : event.data[0];
      return IoStatus::Ok;
    case UHID_GET_REPORT: {
      // Answer at once: the kernel holds the host's request until a reply
      // with this id arrives, or for 5 s.
      event.kind = UhidEvent::Kind::GetReport;
      event.report_type = report_type(ev->u.get_report.rtype);
      event.report_id = ev->u.get_report.rnum;
      uhid_event reply;
      std::memset(&reply, 0, offsetof(uhid_event, u.get_report_reply.data));
      reply.type = UHID_GET_REPORT_REPLY;
      reply.u.get_report_reply.id = ev->u.get_report.id;
      std::size_t size = 0;
      {
        std::lock_guard lock(stored_mutex_);
        if (const StoredReport* r = find_stored(event.report_type, event.report_id)) {
          size = std::min(r->bytes.size(), sizeof reply.u.get_report_reply.data);
          std::copy_n(r->bytes.begin(), size, reply.u.get_report_reply.data);
          event.answered = true;
        }
      }
      reply.u.get_report_reply.err = event.answered ? 0 : EIO;
      reply.u.get_report_reply.size = static_cast<uint16_t>(size);
      if (!write_event(&reply, offsetof(uhid_event, u.get_report_reply.data) + size)) return IoStatus::Disconnected;
      return IoStatus::Ok;
    }
    case UHID_SET_REPORT: {
      event.kind = UhidEvent::Kind::SetReport;
      event.report_type = report_type(ev->u.set_report.rtype);
      event.report_id = ev->u.set_report.rnum;
      event.data = std::span<const uint8_t>(ev->u.set_report.data,
                                            std::min<std::size_t>(ev->u.set_report.size, UHID_DATA_MAX));
      {
        std::lock_guard lock(stored_mutex_);
        if (StoredReport* r = find_stored(event.report_type, event.report_id); r && r->bytes.size() == event.data.size())
          std::copy(event.data.begin(), event.data.end(), r->bytes.begin());
      }
      uhid_event reply;
      std::memset(&reply, 0, sizeof reply.type + sizeof reply.u.set_report_reply);
      reply.type = UHID_SET_REPORT_REPLY;
      reply.u.set_report_reply.id = ev->u.set_report.id;
      reply.u.set_report_reply.err = 0;
      if (!write_event(&reply, sizeof reply.type + sizeof reply.u.set_report_reply)) return IoStatus::Disconnected;
      return IoStatus::Ok;
    }
    default:
      return IoStatus::Timeout;  // a legacy or unknown event: nothing to report
  }
}

}  // namespace rise::hil::io
