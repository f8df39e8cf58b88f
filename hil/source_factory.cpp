#include "hil/source_factory.hpp"

#include <stdexcept>
#include <utility>

#include "hil/can_source.hpp"
#include "hil/canopen_source.hpp"
#include "hil/evdev_source.hpp"
#include "hil/io/evdev_device.hpp"
#include "hil/hid_source.hpp"
#include "hil/io/modbus_url.hpp"
#include "hil/io/replay_modbus_link.hpp"
#include "hil/j1939_source.hpp"
#include "hil/modbus_source.hpp"

namespace rise::hil {
namespace {

// The definition's unit unless a modbus+tcp:// or modbus+rtu:// URL names one.
int modbus_unit(const panels::SourceDefinition& source, const std::string& url) {
  if (io::is_modbus_url(url) && url.find("unit=") != std::string::npos) return io::parse_modbus_url(url).unit;
  return source.unit;
}

std::string resolved_url(const panels::SourceDefinition& source, const std::string& url) {
  return source.is_hid() && url == "-" ? source.device : url;
}

std::runtime_error wrong_url(const panels::SourceDefinition& source, const std::string& url, const std::string& is) {
  return std::runtime_error("source '" + source.name + "' speaks " + source.protocol + ": '" + url + "' is " + is);
}

std::unique_ptr<io::ModbusLink> open_link(const panels::SourceDefinition& source, const std::string& url) {
  // replay://FILE.modbus.log: a recorded trace answers as the slave did.
  const bool replay = io::is_replay_url(url);
  if (!replay && !io::is_modbus_url(url))
    throw wrong_url(source, url, "not a modbus+tcp://, modbus+rtu:// or replay://FILE.modbus.log URL");
  if (replay) return io::open_modbus_link(url);
  auto address = io::parse_modbus_url(url);
  address.unit = modbus_unit(source, url);
  return io::open_modbus_link(address);
}

// Wire faults right on each CAN bus and Modbus link; none on a HID device.
class WireFaults final : public IoDecorator {
 public:
  io::WireFaultSet* set() const { return set_; }
  std::unique_ptr<io::CanBus> wrap(std::unique_ptr<io::CanBus> bus) override { return faulty<io::FaultyCanBus>(std::move(bus)); }
  std::unique_ptr<io::ModbusLink> wrap(std::unique_ptr<io::ModbusLink> link) override {
    return faulty<io::FaultyModbusLink>(std::move(link));
  }
  std::unique_ptr<io::InputDevice> wrap(std::unique_ptr<io::InputDevice> device) override { return device; }

 private:
  template <class Faulty, class Inner>
  std::unique_ptr<Faulty> faulty(std::unique_ptr<Inner> inner) {
    auto wrapped = std::make_unique<Faulty>(std::move(inner));
    set_ = wrapped.get();
    return wrapped;
  }
  io::WireFaultSet* set_ = nullptr;
};

}  // namespace

std::unique_ptr<SourceTransport> open_source(const panels::PanelDefinition& definition, std::size_t source,
                                             const std::string& given_url) {
  const panels::SourceDefinition& def = definition.sources[source];
  const std::string url = resolved_url(def, given_url);
  const bool evdev = io::is_evdev_url(url);
  const bool hid_url = url.rfind("hid://", 0) == 0 || evdev;
  if (def.is_hid() ? !io::is_input_device_url(url) && !evdev : hid_url)
    throw wrong_url(def, url,
                    def.is_hid() ? "not a hid://VID:PID or evdev:// URL (or - for its device:) or a replay://FILE.hid"
                                 : "a HID device URL");
  if (def.is_hid() && !def.mapping.empty() && !evdev)
    throw wrong_url(def, url, "not an evdev:// URL, which mapping: " + def.mapping + " needs");
  if (evdev) return std::make_unique<EvdevSource>(std::make_unique<io::EvdevDevice>(url));
  if (def.is_hid()) return std::make_unique<HidSource>(io::open_input_device(url), definition, source);
  if (def.is_modbus()) return std::make_unique<ModbusSource>(open_link(def, url), definition, source);
  if (io::is_modbus_url(url)) throw wrong_url(def, url, "not a CAN URL");
  if (def.is_canopen()) return std::make_unique<CanopenSource>(io::open_can_bus(url), definition, source);
  if (def.is_j1939()) return std::make_unique<J1939Source>(io::open_can_bus(url), definition, source);
  return std::make_unique<CanSource>(io::open_can_bus(url), definition, source);
}

PanelSources open_panel_sources(const panels::PanelDefinition& definition, std::vector<std::string> urls,
                                const std::string& record_dir) {
  if (urls.size() != definition.sources.size())
    throw std::runtime_error(definition.file + ": the panel has " + std::to_string(definition.sources.size()) +
                             " source(s) but " + std::to_string(urls.size()) + " --source URL(s) were given");
  PanelSources opened;
  for (std::size_t i = 0; i < urls.size(); ++i) {
    const panels::SourceDefinition& source = definition.sources[i];
    urls[i] = resolved_url(source, urls[i]);
    opened.transports.push_back(open_source(definition, i, urls[i]));
    if (!source.is_hid()) continue;
    // Without hot-plug the bridge notes it once (Bridge::take_notes).
    const auto* hid = dynamic_cast<const HidSource*>(opened.transports.back().get());
    if (!hid) opened.notes.push_back("source '" + source.name + "': evdev device, /dev/input watched for its return");
    else if (urls[i].rfind("hid://", 0) != 0) opened.notes.push_back("source '" + source.name + "': replaying " + urls[i]);
    else if (hid->device().hotplug_active())
      opened.notes.push_back("source '" + source.name + "': USB hot-plug through libusb");
  }
  for (auto& transport : opened.transports) {
    WireFaults faults;
    transport->decorate(faults);
    opened.wires.push_back(faults.set());
  }
  if (!record_dir.empty()) {
    opened.recorder = std::make_unique<SessionRecorder>(record_dir);
    for (std::size_t i = 0; i < urls.size(); ++i)
      opened.recorder->record_source(definition.sources[i].name, *opened.transports[i],
                                     modbus_unit(definition.sources[i], urls[i]));
  }
  opened.urls = std::move(urls);
  return opened;
}

}  // namespace rise::hil
