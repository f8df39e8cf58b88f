#include "hil/io/input_device.hpp"

#include <stdexcept>

#include "hil/io/hid_device.hpp"
#include "hil/io/hid_replay_device.hpp"

namespace rise::hil::io {

bool is_input_device_url(std::string_view url) {
  return url.starts_with("hid://") || url.starts_with("replay://");
}

std::unique_ptr<InputDevice> open_input_device(const std::string& url) {
  if (url.starts_with("hid://")) return std::make_unique<HidDevice>(url);
  if (url.starts_with("replay://")) return std::make_unique<HidReplayDevice>(url);
  throw std::invalid_argument("'" + url + "': a HID source takes hid://VID:PID or replay://FILE.hid");
}

}  // namespace rise::hil::io
