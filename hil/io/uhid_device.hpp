#pragma once

// The device side of HID: a virtual HID device made through Linux uhid
// (/dev/uhid, <linux/uhid.h>, the kernel's Documentation/hid/uhid.rst). The
// kernel's HID stack treats it as a plugged-in device: hid-generic binds it,
// hidraw and evdev nodes appear, and hidapi finds it like a real one. The
// HID emulator of panels/ sends its input reports through it; the reports
// the host writes (LEDs, rumble) come back as events.
//
//   create()      UHID_CREATE2 (name, uniq, bus, vendor, product, descriptor)
//   send_input()  UHID_INPUT2: one input report, id byte first when ids are used
//   poll()        UHID_START/STOP/OPEN/CLOSE, UHID_OUTPUT, UHID_GET_REPORT and
//                 UHID_SET_REPORT, each answered at once (the host waits up
//                 to 5 s for the reply otherwise)
//   destroy()     UHID_DESTROY: the device is unplugged
//
// Needs write access to /dev/uhid (root, or a udev rule).

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include "hil/io/can_bus.hpp"
#include "hil/io/posix_io.hpp"

namespace rise::hil::io {

struct UhidSettings {
  std::string name = "rise-panel HID emulator";  ///< product string, at most 127 bytes
  std::string uniq;  ///< serial number as hidapi reports it, at most 63 bytes
  std::string phys;  ///< physical path, at most 63 bytes
  /// BUS_BLUETOOTH (0x05). Not BUS_USB (0x03): hidapi's hidraw backend reads
  /// the strings of a BUS_USB device from its USB parent, which a uhid device
  /// lacks, and then skips it.
  uint16_t bus = 0x05;
  uint16_t vendor_id = 0;
  uint16_t product_id = 0;
  uint32_t version = 0;
  uint32_t country = 0;
  std::vector<uint8_t> descriptor;  ///< the report descriptor, 1..4096 bytes
};

enum class UhidReportType : uint8_t { Feature, Output, Input };

/// One thing the host did, as poll() read it.
struct UhidEvent {
  enum class Kind : uint8_t {
    Start,      ///< a HID driver bound the device
    Stop,       ///< the driver let go of it
    Open,       ///< the host opened it (a hidraw or evdev reader)
    Close,      ///< the last reader closed it
    Output,     ///< an output report (hid_write on hidraw): `data`
    GetReport,  ///< the host asked for a report; answered already (`answered`)
    SetReport,  ///< the host set a report (feature / output): `data`; acknowledged already
  };
  Kind kind = Kind::Start;
  UhidReportType report_type = UhidReportType::Output;
  uint8_t report_id = 0;  ///< GetReport / SetReport: the report number asked for
  /// Output / SetReport: the report as the host wrote it. hidraw passes it
  /// on whole: its first byte is the report id, 0 when the descriptor uses
  /// none. Valid until the next poll().
  std::span<const uint8_t> data;
  bool answered = false;  ///< GetReport: a stored report was sent (else the host got EIO)
};

class UhidDevice {
 public:
  /// Does not create the device: call create(). Throws std::invalid_argument
  /// when a string or the descriptor does not fit uhid's fixed fields.
  explicit UhidDevice(UhidSettings settings);
  ~UhidDevice();
  UhidDevice(const UhidDevice&) = delete;
  UhidDevice& operator=(const UhidDevice&) = delete;

  /// Opens /dev/uhid and creates (plugs in) the device. Ok, or Error with
  /// last_error() (no /dev/uhid, no permission). The kernel binds a driver
  /// asynchronously: reports sent before the Start event are refused.
  IoStatus create();
  /// Unplugs the device (UHID_DESTROY) and closes /dev/uhid. Safe to repeat.
  void destroy();
  bool is_created() const { return fd_ >= 0; }
  /// A driver has bound the device (Start seen, Stop not).
  bool is_started() const { return started_; }
  /// Some host reader has the device open (Open seen more often than Close).
  bool is_open_by_host() const { return open_count_ > 0; }

  /// Sends one input report (id byte first when the descriptor uses ids).
  /// Ok, or Error (not created, not yet started, too long, refused by the
  /// kernel). It also becomes the answer to a GetReport of that input report
  /// when one of the same length was stored with set_report(). No
  /// allocation, no throw: cyclic-path safe.
  IoStatus send_input(std::span<const uint8_t> report);

  /// Reads one event from the host, waiting up to timeout_ms. GetReport is
  /// answered with the report stored for its type and id, or with EIO;
  /// SetReport is acknowledged and overwrites a stored report of the same
  /// length. Ok with `event` set, Timeout, or Disconnected (not created, or
  /// /dev/uhid failed). No allocation, no throw: cyclic-path safe.
  IoStatus poll(UhidEvent& event, int timeout_ms);

  /// Stores `report` (as on the wire: id byte first when ids are used) as
  /// the answer to the host's GetReport of that type and id. Allocates: call
  /// at start-up.
  void set_report(UhidReportType type, uint8_t report_id, std::span<const uint8_t> report);

  const UhidSettings& settings() const { return settings_; }
  std::string last_error() const { return error_.get(); }

 private:
  struct StoredReport {
    UhidReportType type;
    uint8_t id;
    std::vector<uint8_t> bytes;
  };
  StoredReport* find_stored(UhidReportType type, uint8_t id);
  bool write_event(const void* event, std::size_t size);

  UhidSettings settings_;
  int fd_ = -1;
  // Written by poll(), read by send_input() and the accessors: send_input()
  // and poll() may run on different threads (create and destroy may not).
  std::atomic<bool> started_{false};
  std::atomic<int> open_count_{0};
  std::atomic<uint64_t> dev_flags_{0};
  std::mutex stored_mutex_;
  std::vector<StoredReport> stored_;
  std::vector<uint8_t> event_buffer_;  // one struct uhid_event, read by poll()
  detail::ErrorText error_;
};

}  // namespace rise::hil::io
