#include "hil/io/hid_device.hpp"

#include <hidapi/hidapi.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <mutex>
#include <stdexcept>
#include <utility>

#include "hil/io/posix_io.hpp"

namespace rise::hil::io {
namespace {

// hid_init() is not thread-safe and hid_exit() would pull the library from
// under other devices: initialise once per process, never exit.
bool hidapi_ready() {
  static const bool ok = hid_init() == 0;
  return ok;
}

// hidapi reports strings as wchar_t; URLs name them in ASCII.
std::string narrow(const wchar_t* text) {
  std::string out;
  if (!text) return out;
  for (; *text; ++text) out.push_back(*text > 0 && *text < 128 ? static_cast<char>(*text) : '?');
  return out;
}

bool matches(const HidUrl& url, const hid_device_info& info) {
  if (info.vendor_id != url.vendor_id || info.product_id != url.product_id) return false;
  if (!url.serial.empty() && narrow(info.serial_number) != url.serial) return false;
  if (!url.name.empty() && narrow(info.product_string).find(url.name) == std::string::npos) return false;
  return url.interface < 0 || info.interface_number == url.interface;
}

// The hidraw backend's path is the node, /dev/hidrawN; the kernel exports the
// descriptor it parsed next to the node's sysfs entry.
std::vector<uint8_t> read_sysfs_descriptor(const std::string& node) {
  const auto slash = node.rfind('/');
  const std::string name = slash == std::string::npos ? node : node.substr(slash + 1);
  std::ifstream in("/sys/class/hidraw/" + name + "/device/report_descriptor", std::ios::binary);
  if (!in) return {};
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// The kernel's uevent of the hidraw node's HID device names it as
// hid-recorder's ioctls do: "HID_ID=0005:00000428:00004001" (bus, vendor,
// product in hex), "HID_NAME=...", "HID_PHYS=..." (drivers/hid/hid-core.c,
// hid_uevent). Fields it lacks keep what `identity` holds.
void read_sysfs_identity(const std::string& node, HidIdentity& identity) {
  const auto slash = node.rfind('/');
  const std::string name = slash == std::string::npos ? node : node.substr(slash + 1);
  std::ifstream in("/sys/class/hidraw/" + name + "/device/uevent");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("HID_NAME=", 0) == 0) {
      identity.name = line.substr(9);
    } else if (line.rfind("HID_PHYS=", 0) == 0) {
      identity.phys = line.substr(9);
    } else if (line.rfind("HID_ID=", 0) == 0) {
      unsigned bus = 0, vendor = 0, product = 0;
      if (std::sscanf(line.c_str() + 7, "%x:%x:%x", &bus, &vendor, &product) == 3) {
        identity.bus = bus;
        identity.vendor_id = static_cast<uint16_t>(vendor);
        identity.product_id = static_cast<uint16_t>(product);
      }
    }
  }
}

}  // namespace

std::optional<uint16_t> parse_hex16(std::string_view text) {
  unsigned value = 0;
  if (text.empty() || text.size() > 4) return std::nullopt;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value, 16);
  if (ec != std::errc() || end != text.data() + text.size()) return std::nullopt;
  return static_cast<uint16_t>(value);
}

std::optional<HidUrl> parse_hid_url(std::string_view url, std::string* error) {
  auto fail = [&](const std::string& message) -> std::optional<HidUrl> {
    if (error) *error = "'" + std::string(url) + "': " + message;
    return std::nullopt;
  };
  constexpr std::string_view scheme = "hid://";
  if (url.substr(0, scheme.size()) != scheme) return fail("expected hid://VID:PID");
  std::string_view rest = url.substr(scheme.size());
  const auto q = rest.find('?');
  const std::string_view ids = rest.substr(0, q);
  const auto colon = ids.find(':');
  if (colon == std::string_view::npos) return fail("expected hid://VID:PID (hex)");
  const auto vid = parse_hex16(ids.substr(0, colon));
  const auto pid = parse_hex16(ids.substr(colon + 1));
  if (!vid || !pid) return fail("VID and PID must be 1..4 hex digits");
  HidUrl out;
  out.vendor_id = *vid;
  out.product_id = *pid;
  std::string_view query = q == std::string_view::npos ? std::string_view() : rest.substr(q + 1);
  while (!query.empty()) {
    const auto amp = query.find('&');
    const std::string_view item = query.substr(0, amp);
    query = amp == std::string_view::npos ? std::string_view() : query.substr(amp + 1);
    const auto eq = item.find('=');
    if (eq == std::string_view::npos) return fail("option '" + std::string(item) + "' needs a value");
    const std::string_view key = item.substr(0, eq), value = item.substr(eq + 1);
    if (key == "serial") {
      out.serial = value;
    } else if (key == "name") {
      out.name = value;
    } else if (key == "interface") {
      int n = -1;
      const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), n);
      if (ec != std::errc() || end != value.data() + value.size() || n < 0 || n > 255)
        return fail("interface must be 0..255");
      out.interface = n;
    } else {
      return fail("unknown option '" + std::string(key) + "' (serial, name, interface)");
    }
  }
  return out;
}

HidDevice::HidDevice(const std::string& url) : url_text_(url) {
  std::string error;
  const auto parsed = parse_hid_url(url, &error);
  if (!parsed) throw std::invalid_argument(error);
  url_ = *parsed;
  hotplug_ = std::make_unique<UsbHotplug>(url_.vendor_id, url_.product_id);
}

HidDevice::~HidDevice() { close(); }

void HidDevice::close() {
  if (device_) hid_close(device_);
  device_ = nullptr;
}

IoStatus HidDevice::reopen() {
  close();
  descriptor_.clear();
  identity_ = {};
  path_.clear();
  if (!hidapi_ready()) {
    error_.set("hid_init failed");
    return IoStatus::Error;
  }
  hid_device_info* list = hid_enumerate(url_.vendor_id, url_.product_id);
  std::string found;
  HidIdentity identity;
  for (const hid_device_info* it = list; it; it = it->next)
    if (matches(url_, *it) && it->path) {
      found = it->path;
      identity.name = narrow(it->product_string);
      identity.vendor_id = it->vendor_id;
      identity.product_id = it->product_id;
      break;
    }
  hid_free_enumeration(list);
  if (found.empty()) {
    error_.set("no HID device %04x:%04x present", url_.vendor_id, url_.product_id);
    return IoStatus::Disconnected;
  }
  device_ = hid_open_path(found.c_str());
  if (!device_) {
    // hidapi says nothing of why; the node itself does (EACCES: the user is
    // not in the group the udev rule gives the console's devices to).
    const int err = ::access(found.c_str(), R_OK | W_OK) != 0 ? errno : 0;
    if (err == EACCES)
      error_.set("%s: permission denied: this user may not read and write it (the udev rule in packaging/udev gives "
                 "a console's devices to group rise)", found.c_str());
    else
      error_.set("%s: cannot open: %s", found.c_str(), err != 0 ? detail::errno_text(err) : "hidapi refused it");
    return IoStatus::Error;
  }
  descriptor_ = read_sysfs_descriptor(found);
  if (descriptor_.empty()) {
    error_.set("%s: no report descriptor in sysfs", found.c_str());
    close();
    return IoStatus::Error;
  }
  read_sysfs_identity(found, identity);
  identity_ = std::move(identity);
  path_ = found;
  error_.clear();
  return IoStatus::Ok;
}

IoStatus HidDevice::read(std::span<uint8_t> report, std::size_t& length, int timeout_ms) {
  length = 0;
  if (!device_) return IoStatus::Disconnected;
  const int n = hid_read_timeout(device_, report.data(), report.size(), timeout_ms);
  if (n < 0) {
    // hidraw reports an unplugged device as a failed read (POLLHUP/ENODEV).
    error_.set("%s: read failed (device gone)", path_.c_str());
    close();
    return IoStatus::Disconnected;
  }
  if (n == 0) return IoStatus::Timeout;
  length = static_cast<std::size_t>(n);
  return IoStatus::Ok;
}

IoStatus HidDevice::write(std::span<const uint8_t> report) {
  if (!device_) return IoStatus::Disconnected;
  if (hid_write(device_, report.data(), report.size()) < 0) {
    error_.set("%s: write failed", path_.c_str());
    return IoStatus::Error;
  }
  return IoStatus::Ok;
}

}  // namespace rise::hil::io
