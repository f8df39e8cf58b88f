#pragma once

// A gamepad or joystick the Linux kernel already drives (xpad, hid-generic,
// hid-sony...), read through its evdev node with libevdev (Debian
// libevdev-dev), opened from a URL:
//
//   evdev:///dev/input/event5               the node itself
//   evdev://by-id/usb-045e_028e-event-joystick   /dev/input/by-id/NAME (udev's stable links; by-path/NAME too)
//   evdev://name/Microsoft%20X-Box%20360%20pad  the first node whose EVIOCGNAME is exactly NAME (%XX decoded)
//   evdev://045e:028e                       the first node with this vendor:product (hex, EVIOCGID)
//
// "First" is in event-node order (event2 before event10). libevdev keeps
// the device's state (every key's and axis's value, absinfo ranges) and
// resynchronises it after the kernel dropped events (SYN_DROPPED), so the
// reader takes values, not events. A read that fails with ENODEV (the device
// was unplugged) closes it; while it is away, wait_for_arrival() watches
// /dev/input with inotify and says when a node appears or changes (udev
// setting its permissions), and the bridge also enumerates periodically.
// Rumble: FF_RUMBLE uploaded once (EVIOCSFF) and played through EV_FF.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "hil/io/can_bus.hpp"
#include "hil/io/posix_io.hpp"

struct libevdev;
struct input_absinfo;

namespace rise::hil::io {

struct EvdevUrl {
  enum class By { Path, Name, Ids } by = By::Path;
  std::string path;  ///< By::Path: the node or link (by-id/by-path resolved under /dev/input)
  std::string name;  ///< By::Name: the device name, decoded
  uint16_t vendor_id = 0;
  uint16_t product_id = 0;
};

/// Parses an evdev:// URL; nullopt (and `error` set when given) if malformed.
std::optional<EvdevUrl> parse_evdev_url(std::string_view url, std::string* error = nullptr);
bool is_evdev_url(std::string_view url);

/// Who the device says it is (EVIOCGNAME, EVIOCGID).
struct EvdevIdentity {
  std::string name;
  uint16_t bus = 0;
  uint16_t vendor_id = 0;
  uint16_t product_id = 0;
  uint16_t version = 0;
};

class EvdevDevice {
 public:
  /// Does not open: call reopen(). Throws std::invalid_argument for a bad URL.
  explicit EvdevDevice(std::string url);
  ~EvdevDevice();
  EvdevDevice(const EvdevDevice&) = delete;
  EvdevDevice& operator=(const EvdevDevice&) = delete;

  /// Finds the URL's node and opens it (read-write for rumble, read-only
  /// when writing is refused). Ok; Disconnected when no node matches; Error
  /// when it does but cannot be opened. Allocates: not for the cyclic path.
  IoStatus reopen();
  void close();
  bool is_open() const { return dev_ != nullptr; }

  /// Waits up to timeout_ms, then takes every pending event into the state:
  /// Ok when at least one frame ended (SYN_REPORT) or the state was
  /// resynchronised, Timeout when none, Disconnected when the device went
  /// away (closed). No allocation, no throw.
  IoStatus read(int timeout_ms);

  /// The current value of an event code (libevdev's state); 0 when the
  /// device has no such code. Cyclic-path safe.
  int value(unsigned type, unsigned code) const;
  bool has(unsigned type, unsigned code) const;
  /// An absolute axis's range, flat and fuzz; nullptr when the device has none.
  const input_absinfo* absinfo(unsigned code) const;

  /// Plays FF_RUMBLE at strong / weak (0..1; both 0 stops it, without an
  /// upload). Ok when played, Error when the device has no rumble or refused
  /// it. EVIOCSFF waits for the driver (a uinput device's own process
  /// answers it): call from the source's thread.
  IoStatus rumble(double strong, double weak);
  bool has_rumble() const;

  /// While closed: waits up to timeout_ms for a node under /dev/input to
  /// appear or change; true when one did (reopen now). No allocation.
  bool wait_for_arrival(int timeout_ms);
  bool hotplug_active() const { return inotify_fd_ >= 0; }
  const std::string& hotplug_error() const { return hotplug_error_; }

  const EvdevIdentity& identity() const { return identity_; }
  /// The node opened ("/dev/input/event5"); empty when closed.
  const std::string& path() const { return path_; }
  const std::string& url() const { return url_text_; }
  std::string last_error() const { return error_.get(); }

 private:
  std::string find_node();
  IoStatus play(bool on);
  void watch_input_dir();

  std::string url_text_;
  EvdevUrl url_;
  int fd_ = -1;
  libevdev* dev_ = nullptr;
  bool writable_ = false;
  int effect_id_ = -1;
  EvdevIdentity identity_;
  std::string path_;
  int inotify_fd_ = -1;
  std::string hotplug_error_;
  detail::ErrorText error_;
};

}  // namespace rise::hil::io
