#include "hil/io/evdev_device.hpp"
#include "hil/io/hid_device.hpp"

#include <fcntl.h>
#include <libevdev/libevdev.h>
#include <linux/input.h>
#include <poll.h>
#include <sys/inotify.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <filesystem>
#include <stdexcept>
#include <utility>
#include <vector>

namespace rise::hil::io {
namespace {

constexpr std::string_view kScheme = "evdev://";
constexpr const char* kInputDir = "/dev/input";

// %XX decoded; nullopt for a bad escape.
std::optional<std::string> percent_decode(std::string_view text) {
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '%') {
      out.push_back(text[i]);
      continue;
    }
    unsigned byte = 0;
    if (i + 2 >= text.size()) return std::nullopt;
    const auto [end, ec] = std::from_chars(text.data() + i + 1, text.data() + i + 3, byte, 16);
    if (ec != std::errc() || end != text.data() + i + 3) return std::nullopt;
    out.push_back(static_cast<char>(byte));
    i += 2;
  }
  return out;
}

// /dev/input/eventN nodes, in N's order.
std::vector<std::string> event_nodes() {
  std::vector<std::pair<int, std::string>> found;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(kInputDir, ec)) {
    const std::string name = entry.path().filename().string();
    int n = 0;
    if (name.rfind("event", 0) != 0) continue;
    const auto [end, err] = std::from_chars(name.data() + 5, name.data() + name.size(), n);
    if (err == std::errc() && end == name.data() + name.size()) found.emplace_back(n, entry.path().string());
  }
  std::sort(found.begin(), found.end());
  std::vector<std::string> nodes;
  for (auto& f : found) nodes.push_back(std::move(f.second));
  return nodes;
}

bool node_matches(const std::string& node, const EvdevUrl& url) {
  const int fd = ::open(node.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return false;
  std::array<char, 256> name{};
  input_id id{};
  const bool named = ::ioctl(fd, EVIOCGNAME(name.size() - 1), name.data()) >= 0;
  const bool ided = ::ioctl(fd, EVIOCGID, &id) >= 0;
  ::close(fd);
  if (url.by == EvdevUrl::By::Name) return named && url.name == name.data();
  return ided && id.vendor == url.vendor_id && id.product == url.product_id;
}

uint16_t magnitude(double level) {
  return static_cast<uint16_t>(std::clamp(level, 0.0, 1.0) * 65535.0 + 0.5);
}

}  // namespace

bool is_evdev_url(std::string_view url) { return url.starts_with(kScheme); }

std::optional<EvdevUrl> parse_evdev_url(std::string_view url, std::string* error) {
  auto fail = [&](const std::string& message) -> std::optional<EvdevUrl> {
    if (error) *error = "'" + std::string(url) + "': " + message;
    return std::nullopt;
  };
  constexpr const char* grammar =
      "expected evdev:///dev/input/eventN, evdev://by-id/NAME, evdev://by-path/NAME, evdev://name/DEVICE NAME or "
      "evdev://VID:PID";
  if (!is_evdev_url(url)) return fail(grammar);
  const std::string_view rest = url.substr(kScheme.size());
  EvdevUrl out;
  if (rest.starts_with("/") && rest.size() > 1) {
    out.path = rest;
  } else if ((rest.starts_with("by-id/") || rest.starts_with("by-path/")) && rest.find('/') + 1 < rest.size()) {
    out.path = std::string(kInputDir) + "/" + std::string(rest);
  } else if (rest.starts_with("name/") && rest.size() > 5) {
    const auto name = percent_decode(rest.substr(5));
    if (!name) return fail("bad %XX escape in the name");
    out.by = EvdevUrl::By::Name;
    out.name = *name;
  } else if (const auto colon = rest.find(':'); colon != std::string_view::npos) {
    const auto vid = parse_hex16(rest.substr(0, colon)), pid = parse_hex16(rest.substr(colon + 1));
    if (!vid || !pid) return fail("VID and PID must be 1..4 hex digits");
    out.by = EvdevUrl::By::Ids;
    out.vendor_id = *vid;
    out.product_id = *pid;
  } else {
    return fail(grammar);
  }
  return out;
}

EvdevDevice::EvdevDevice(std::string url) : url_text_(std::move(url)) {
  std::string error;
  const auto parsed = parse_evdev_url(url_text_, &error);
  if (!parsed) throw std::invalid_argument(error);
  url_ = *parsed;
  inotify_fd_ = ::inotify_init1(IN_NONBLOCK | IN_CLOEXEC);
  if (inotify_fd_ < 0) hotplug_error_ = std::string("inotify: ") + detail::errno_text(errno);
  else watch_input_dir();
}

EvdevDevice::~EvdevDevice() {
  close();
  detail::close_fd(inotify_fd_);
}

// /dev/input appears with the first input device (devtmpfs): until then /dev
// is watched for it. by-id and by-path links are made by udev after the node.
void EvdevDevice::watch_input_dir() {
  constexpr uint32_t mask = IN_CREATE | IN_ATTRIB | IN_MOVED_TO;
  if (::inotify_add_watch(inotify_fd_, kInputDir, mask) < 0) {
    ::inotify_add_watch(inotify_fd_, "/dev", IN_CREATE);
    return;
  }
  for (const char* links : {"/dev/input/by-id", "/dev/input/by-path"}) ::inotify_add_watch(inotify_fd_, links, mask);
}

std::string EvdevDevice::find_node() {
  if (url_.by == EvdevUrl::By::Path) {
    std::error_code ec;
    const auto target = std::filesystem::canonical(url_.path, ec);
    return ec ? std::string() : target.string();
  }
  for (const std::string& node : event_nodes())
    if (node_matches(node, url_)) return node;
  return {};
}

void EvdevDevice::close() {
  if (dev_) libevdev_free(dev_);
  dev_ = nullptr;
  detail::close_fd(fd_);
  effect_id_ = -1;
  path_.clear();
}

IoStatus EvdevDevice::reopen() {
  close();
  identity_ = {};
  const std::string node = find_node();
  if (node.empty()) {
    error_.set("%s: no such input device", url_text_.c_str());
    return IoStatus::Disconnected;
  }
  fd_ = ::open(node.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  writable_ = fd_ >= 0;
  if (fd_ < 0 && (errno == EACCES || errno == EROFS)) fd_ = ::open(node.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) {
    const int err = errno;
    error_.set("%s: %s%s", node.c_str(), detail::errno_text(err),
               err == EACCES ? " (the udev rule in packaging/udev gives a console's devices to group rise)" : "");
    return err == ENOENT || err == ENODEV ? IoStatus::Disconnected : IoStatus::Error;
  }
  if (const int rc = libevdev_new_from_fd(fd_, &dev_); rc < 0) {
    dev_ = nullptr;
    error_.set("%s: not an evdev device: %s", node.c_str(), detail::errno_text(-rc));
    detail::close_fd(fd_);
    return IoStatus::Error;
  }
  identity_ = {libevdev_get_name(dev_) ? libevdev_get_name(dev_) : "",
               static_cast<uint16_t>(libevdev_get_id_bustype(dev_)), static_cast<uint16_t>(libevdev_get_id_vendor(dev_)),
               static_cast<uint16_t>(libevdev_get_id_product(dev_)), static_cast<uint16_t>(libevdev_get_id_version(dev_))};
  path_ = node;
  error_.clear();
  return IoStatus::Ok;
}

IoStatus EvdevDevice::read(int timeout_ms) {
  if (!dev_) return IoStatus::Disconnected;
  pollfd p{fd_, POLLIN, 0};
  const int ready = ::poll(&p, 1, timeout_ms);
  if (ready == 0 || (ready < 0 && errno == EINTR)) return IoStatus::Timeout;
  bool frame = false;
  unsigned flags = LIBEVDEV_READ_FLAG_NORMAL;
  for (;;) {
    input_event ev{};
    const int rc = libevdev_next_event(dev_, flags, &ev);
    if (rc == LIBEVDEV_READ_STATUS_SYNC) {
      flags = LIBEVDEV_READ_FLAG_SYNC;  // dropped: libevdev replays the state's changes
      frame = true;
    } else if (rc == LIBEVDEV_READ_STATUS_SUCCESS) {
      frame = frame || (ev.type == EV_SYN && ev.code == SYN_REPORT);
    } else if (rc == -EAGAIN && flags == LIBEVDEV_READ_FLAG_SYNC) {
      flags = LIBEVDEV_READ_FLAG_NORMAL;
    } else if (rc == -EAGAIN) {
      return frame ? IoStatus::Ok : IoStatus::Timeout;
    } else {
      // ENODEV: unplugged (the kernel wakes the reader with POLLHUP|POLLERR).
      error_.set("%s: read failed: %s (device gone)", path_.c_str(), detail::errno_text(-rc));
      close();
      return IoStatus::Disconnected;
    }
  }
}

int EvdevDevice::value(unsigned type, unsigned code) const {
  return dev_ ? libevdev_get_event_value(dev_, type, code) : 0;
}

bool EvdevDevice::has(unsigned type, unsigned code) const {
  return dev_ && libevdev_has_event_code(dev_, type, code) == 1;
}

const input_absinfo* EvdevDevice::absinfo(unsigned code) const {
  return dev_ ? libevdev_get_abs_info(dev_, code) : nullptr;
}

bool EvdevDevice::has_rumble() const { return writable_ && has(EV_FF, FF_RUMBLE); }

IoStatus EvdevDevice::play(bool on) {
  input_event play{};
  play.type = EV_FF;
  play.code = static_cast<uint16_t>(effect_id_);
  play.value = on ? 1 : 0;
  if (::write(fd_, &play, sizeof play) == static_cast<ssize_t>(sizeof play)) return IoStatus::Ok;
  error_.set("%s: playing the rumble: %s", path_.c_str(), detail::errno_text(errno));
  return IoStatus::Error;
}

IoStatus EvdevDevice::rumble(double strong, double weak) {
  if (!dev_) return IoStatus::Disconnected;
  if (!has_rumble()) return IoStatus::Error;
  // Stopping needs no upload: nothing plays before the first one.
  if (strong <= 0.0 && weak <= 0.0) return effect_id_ < 0 ? IoStatus::Ok : play(false);
  ff_effect effect{};
  effect.type = FF_RUMBLE;
  effect.id = static_cast<int16_t>(effect_id_);
  effect.u.rumble.strong_magnitude = magnitude(strong);
  effect.u.rumble.weak_magnitude = magnitude(weak);
  effect.replay.length = 0;  // until stopped (ff-memless and uinput play a 0 length for ever)
  if (::ioctl(fd_, EVIOCSFF, &effect) < 0) {
    error_.set("%s: EVIOCSFF: %s", path_.c_str(), detail::errno_text(errno));
    return IoStatus::Error;
  }
  effect_id_ = effect.id;
  return play(true);
}

bool EvdevDevice::wait_for_arrival(int timeout_ms) {
  if (inotify_fd_ < 0) {
    ::poll(nullptr, 0, timeout_ms);
    return false;
  }
  pollfd p{inotify_fd_, POLLIN, 0};
  if (::poll(&p, 1, timeout_ms) <= 0) return false;
  alignas(inotify_event) std::array<char, 4096> buffer;
  bool seen = false;
  while (::read(inotify_fd_, buffer.data(), buffer.size()) > 0) seen = true;
  if (seen) watch_input_dir();  // /dev/input may have just appeared
  return seen;
}

}  // namespace rise::hil::io
