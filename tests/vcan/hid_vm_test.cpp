// hid:// against the real kernel HID stack: a gamepad created through uhid
// (/dev/uhid, the kernel's user-space HID transport, driven by
// io::UhidDevice) is found by hidapi's hidraw enumeration, opened by
// HidDevice, decoded by the bridge, unplugged (UHID_DESTROY) and plugged in
// again; the host's feature and output reports reach the device side; a
// session recorded as `rise-hild --record` records it verifies against its
// PanelState log. Runs only inside the VM of run_in_vcan_vm.sh (modules
// hid, uhid, hid-generic), as root.

#include <catch2/catch.hpp>

#include <fcntl.h>
#include <linux/hidraw.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <mutex>
#include <span>
#include <thread>

#include "process/child_process.hpp"
#include "firmware_protocol/hid_report.hpp"
#include "hil/bridge.hpp"
#include "hil/io/hid_device.hpp"
#include "hil/io/uhid_device.hpp"
#include "hil/replay_verify.hpp"
#include "hil/source_factory.hpp"
#include "panels/hid_emulator.hpp"
#include "panels/panel_definition.hpp"
#include "panels/timeline.hpp"
#include "tests/hid_test_devices.hpp"
#include "tests/hil/hid_session_support.hpp"

namespace io = rise::hil::io;
using rise::hil::Bridge;
using rise::hil::PanelSnapshot;
using rise::test::gravis_descriptor;
using rise::test::led_pad_descriptor;

namespace {

// The bus is UhidSettings' default, Bluetooth (see there).
io::UhidSettings uhid_settings(const char* name, const char* uniq, uint16_t vendor_id, uint16_t product_id,
                               std::span<const uint8_t> descriptor) {
  io::UhidSettings s;
  s.name = name;
  s.uniq = uniq;
  s.vendor_id = vendor_id;
  s.product_id = product_id;
  s.descriptor.assign(descriptor.begin(), descriptor.end());
  return s;
}

// One virtual Gravis pad on /dev/uhid, plugged in by the constructor and
// unplugged by destroy() or the destructor.
class UhidGamepad {
 public:
  UhidGamepad() : device_(settings()) { REQUIRE(device_.create() == io::IoStatus::Ok); }
  UhidGamepad(const UhidGamepad&) = delete;
  UhidGamepad& operator=(const UhidGamepad&) = delete;

  void send(std::initializer_list<uint8_t> report) {
    const std::vector<uint8_t> bytes(report);
    REQUIRE(device_.send_input(bytes) == io::IoStatus::Ok);
  }
  void destroy() { device_.destroy(); }

 private:
  static io::UhidSettings settings() {
    return uhid_settings("Gravis GamePad Pro (uhid)", "rise-uhid-1", 0x0428, 0x4001, gravis_descriptor);
  }
  io::UhidDevice device_;
};

io::UhidSettings led_pad_settings() {
  return uhid_settings("rise LED test pad (uhid)", "rise-led-pad", 0x1209, 0x0001, led_pad_descriptor);
}

// Polls `done` until it holds or `timeout` passes (the VM runs under TCG:
// generous deadlines, never fixed sleeps).
bool wait_for(const std::function<bool()>& done, std::chrono::milliseconds timeout = std::chrono::seconds(20)) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return done();
}

const char* definition_text =
    "panel: gravis\n"
    "sources:\n"
    "  - {name: pad, protocol: hid, device: 'hid://0428:4001', timeout_ms: 0}\n"
    "controls:\n"
    "  - {name: stick_x, kind: axis, signal: x, safe: 0}\n"
    "  - {name: stick_y, kind: axis, signal: y, safe: 0}\n"
    "  - {name: red, kind: button, signal: button_1, safe: false}\n"
    "  - {name: green, kind: button, signal: button_3, safe: false}\n"
    "  - {name: start, kind: button, signal: button_10, safe: false}\n";

}  // namespace

TEST_CASE("HidDevice finds a uhid gamepad by VID:PID and reads its descriptor and reports", "[vcan]") {
  UhidGamepad pad;
  io::HidDevice device("hid://0428:4001?name=GamePad");
  REQUIRE(wait_for([&] { return device.reopen() == io::IoStatus::Ok; }));
  CHECK(device.path().rfind("/dev/hidraw", 0) == 0);
  CHECK(device.report_descriptor() ==
        std::vector<uint8_t>(std::begin(gravis_descriptor), std::end(gravis_descriptor)));
  SECTION("a report sent by the device is read as sent") {
    pad.send({0x00, 0xff, 0x05, 0x02});
    std::array<uint8_t, 64> report{};
    std::size_t length = 0;
    REQUIRE(device.read(report, length, 5000) == io::IoStatus::Ok);
    CHECK(std::vector<uint8_t>(report.begin(), report.begin() + static_cast<std::ptrdiff_t>(length)) ==
          std::vector<uint8_t>{0x00, 0xff, 0x05, 0x02});
  }
  SECTION("unplugging reads as Disconnected") {
    pad.destroy();
    std::array<uint8_t, 64> report{};
    std::size_t length = 0;
    io::IoStatus st = io::IoStatus::Timeout;
    REQUIRE(wait_for([&] { return (st = device.read(report, length, 10)) != io::IoStatus::Timeout; }));
    CHECK(st == io::IoStatus::Disconnected);
    CHECK_FALSE(device.is_open());
    CHECK(device.reopen() == io::IoStatus::Disconnected);
  }
  SECTION("another VID:PID is not matched") {
    io::HidDevice other("hid://0428:4002");
    CHECK(other.reopen() == io::IoStatus::Disconnected);
    io::HidDevice other_serial("hid://0428:4001?serial=nope");
    CHECK(other_serial.reopen() == io::IoStatus::Disconnected);
  }
}

// Reads the device's events on a thread of its own, as an emulator does.
class UhidPoller {
 public:
  explicit UhidPoller(io::UhidDevice& device) : device_(device), thread_([this] { run(); }) {}
  ~UhidPoller() {
    stop_ = true;
    thread_.join();
  }
  UhidPoller(const UhidPoller&) = delete;
  UhidPoller& operator=(const UhidPoller&) = delete;

  struct Seen {
    io::UhidEvent::Kind kind;
    io::UhidReportType type;
    uint8_t report_id;
    std::vector<uint8_t> data;
    bool answered;
  };
  std::vector<Seen> events() const {
    std::lock_guard lock(mutex_);
    return events_;
  }
  bool saw(io::UhidEvent::Kind kind) const {
    for (const Seen& e : events())
      if (e.kind == kind) return true;
    return false;
  }

 private:
  void run() {
    io::UhidEvent event;
    while (!stop_) {
      if (device_.poll(event, 5) != io::IoStatus::Ok) continue;
      std::lock_guard lock(mutex_);
      events_.push_back({event.kind, event.report_type, event.report_id,
                         std::vector<uint8_t>(event.data.begin(), event.data.end()), event.answered});
    }
  }
  io::UhidDevice& device_;
  mutable std::mutex mutex_;
  std::vector<Seen> events_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

TEST_CASE("uhid device answers the host's feature requests at once and passes its output reports on", "[vcan]") {
  io::UhidDevice pad(led_pad_settings());
  const uint8_t feature[] = {0x03, 0x42};
  pad.set_report(io::UhidReportType::Feature, 3, feature);
  REQUIRE(pad.create() == io::IoStatus::Ok);
  UhidPoller poller(pad);
  REQUIRE(wait_for([&] { return pad.is_started(); }));
  io::HidDevice host("hid://1209:0001");
  REQUIRE(wait_for([&] { return host.reopen() == io::IoStatus::Ok; }));
  // Open: the kernel's own input-leds handler (CONFIG_INPUT_LEDS=y) opens
  // every input device with LEDs as soon as it appears, and holds it open,
  // so no Close follows our reader's.
  REQUIRE(wait_for([&] { return pad.is_open_by_host(); }));
  CHECK(host.report_descriptor() ==
        std::vector<uint8_t>(std::begin(led_pad_descriptor), std::end(led_pad_descriptor)));
  // The hidraw ioctls as any HID tool uses them (hidapi's feature reports are these).
  const int fd = ::open(host.path().c_str(), O_RDWR | O_CLOEXEC);
  REQUIRE(fd >= 0);
  using Clock = std::chrono::steady_clock;

  // GetReport: the stored feature report, without the kernel's 5 s wait.
  uint8_t buffer[2] = {0x03, 0x00};
  auto t0 = Clock::now();
  CHECK(::ioctl(fd, HIDIOCGFEATURE(sizeof buffer), buffer) == 2);
  const auto get_ms = std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - t0).count();
  WARN("feature GetReport answered in " << get_ms << " ms");
  CHECK(get_ms < 1000);
  CHECK(buffer[1] == 0x42);

  // SetReport: acknowledged, seen as an event, and read back by the next GetReport.
  uint8_t set[2] = {0x03, 0x99};
  CHECK(::ioctl(fd, HIDIOCSFEATURE(sizeof set), set) == 2);
  REQUIRE(wait_for([&] { return poller.saw(io::UhidEvent::Kind::SetReport); }));
  buffer[0] = 0x03;
  CHECK(::ioctl(fd, HIDIOCGFEATURE(sizeof buffer), buffer) == 2);
  CHECK(buffer[1] == 0x99);

  // A report nobody stored: an error at once, not a timeout.
  uint8_t unknown[2] = {0x07, 0x00};
  t0 = Clock::now();
  CHECK(::ioctl(fd, HIDIOCGFEATURE(sizeof unknown), unknown) < 0);
  CHECK(std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - t0).count() < 1000);
  ::close(fd);

  // An output report written through hidapi arrives whole, id byte first.
  const uint8_t leds[] = {0x02, 0x05};
  REQUIRE(host.write(leds) == io::IoStatus::Ok);
  REQUIRE(wait_for([&] { return poller.saw(io::UhidEvent::Kind::Output); }));
  for (const auto& e : poller.events()) {
    if (e.kind == io::UhidEvent::Kind::SetReport) {
      CHECK(e.type == io::UhidReportType::Feature);
      CHECK(e.report_id == 3);
      CHECK(e.data == std::vector<uint8_t>{0x03, 0x99});
    }
    if (e.kind == io::UhidEvent::Kind::GetReport) CHECK(e.answered == (e.report_id == 3));
    if (e.kind == io::UhidEvent::Kind::Output) {
      CHECK(e.type == io::UhidReportType::Output);
      CHECK(e.data == std::vector<uint8_t>{0x02, 0x05});
    }
  }
}

TEST_CASE("bridge decodes a uhid gamepad, goes failsafe when it is unplugged and reopens it", "[vcan]") {
  auto pad = std::make_unique<UhidGamepad>();
  const auto definition = rise::panels::parse_panel_definition(definition_text, "gravis.yaml");
  std::vector<std::unique_ptr<rise::hil::SourceTransport>> transports;
  transports.push_back(rise::hil::open_source(definition, 0, "hid://0428:4001"));
  rise::hil::BridgeSettings settings;
  Bridge bridge(definition, std::move(transports),
                [](const PanelSnapshot&) {}, settings);
  bridge.start();
  const auto control = [&](const char* name) { return *bridge.definition().find_control(name); };

  REQUIRE(wait_for([&] { return bridge.snapshot().sources[0].connected; }));
  CHECK(bridge.snapshot().failsafe_reason == "pad: no report yet");
  // Worked example of hid_report.hpp: x -1, y +1, buttons 1, 3 and 10.
  pad->send({0x00, 0xff, 0x05, 0x02});
  REQUIRE(wait_for([&] { return !bridge.snapshot().failsafe; }));
  PanelSnapshot snap = bridge.snapshot();
  CHECK(snap.controls[control("stick_x")].axis == Approx(-1.0).margin(1e-6));
  CHECK(snap.controls[control("stick_y")].axis == Approx(1.0).margin(1e-6));
  CHECK(snap.controls[control("red")].pressed);
  CHECK(snap.controls[control("green")].pressed);
  CHECK(snap.controls[control("start")].pressed);

  pad->send({0xff, 0x00, 0x00, 0x00});
  REQUIRE(wait_for([&] { return !bridge.snapshot().controls[control("red")].pressed; }));
  snap = bridge.snapshot();
  CHECK(snap.controls[control("stick_x")].axis == Approx(1.0).margin(1e-6));
  CHECK(snap.controls[control("stick_y")].axis == Approx(-1.0).margin(1e-6));
  CHECK_FALSE(snap.controls[control("start")].pressed);

  // Unplug: failsafe within a publish period (10 ms at 100 Hz) of the kernel
  // removing the node; measured here including the guest's scheduling.
  pad->send({0x7f, 0x7f, 0x04, 0x00});
  REQUIRE(wait_for([&] { return bridge.snapshot().controls[control("green")].pressed; }));
  const auto unplugged = std::chrono::steady_clock::now();
  pad.reset();
  REQUIRE(wait_for([&] { return bridge.snapshot().failsafe; }));
  const auto failsafe_ms =
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - unplugged).count();
  WARN("unplug -> failsafe: " << failsafe_ms << " ms");
  snap = bridge.snapshot();
  CHECK_FALSE(snap.sources[0].connected);
  CHECK(snap.failsafe_reason == "pad: disconnected");
  CHECK(snap.controls[control("green")].forced_safe);
  CHECK_FALSE(snap.controls[control("green")].pressed);

  // Plug in again: found by the next enumeration (every 500 ms).
  const auto plugged = std::chrono::steady_clock::now();
  pad = std::make_unique<UhidGamepad>();
  REQUIRE(wait_for([&] { return bridge.snapshot().sources[0].connected; }));
  const auto reopen_ms =
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - plugged).count();
  WARN("plug -> reopened: " << reopen_ms << " ms");
  pad->send({0x7f, 0x7f, 0x00, 0x02});
  REQUIRE(wait_for([&] { return !bridge.snapshot().failsafe; }));
  snap = bridge.snapshot();
  CHECK(snap.controls[control("start")].pressed);
  CHECK(snap.controls[control("stick_x")].axis == Approx(0.0).margin(0.01));
  CHECK(snap.sources[0].reconnects == 1);
  bridge.stop();
}

namespace {

// rise-panel emulate --hid in a thread: the HidEmulator plays a timeline
// over a real UhidDevice and takes the host's output reports, as the
// program's loop does.
class EmulatedPad {
 public:
  EmulatedPad(const rise::panels::PanelDefinition& definition, const std::string& script,
              rise::panels::HidEmulatorSettings settings = {})
      : timeline_(rise::panels::parse_timeline(script, "script.txt", definition)),
        emulator_(definition, 0, parsed_led_pad(), settings),
        device_(led_pad_settings()) {
    plug();
    thread_ = std::thread([this] { run(); });
  }
  ~EmulatedPad() {
    stop_ = true;
    thread_.join();
  }
  EmulatedPad(const EmulatedPad&) = delete;
  EmulatedPad& operator=(const EmulatedPad&) = delete;

  // The script's clock starts at the first call.
  void start_script() {
    std::lock_guard lock(mutex_);
    script_start_ = std::chrono::steady_clock::now();
    started_ = true;
  }
  bool script_done() const {
    std::lock_guard lock(mutex_);
    return next_ == timeline_.events.size();
  }
  void unplug() {
    std::lock_guard lock(mutex_);
    device_.destroy();
  }
  void plug() {
    std::lock_guard lock(mutex_);
    REQUIRE(device_.create() == io::IoStatus::Ok);
  }
  std::string feedback_text() const {
    std::lock_guard lock(mutex_);
    return emulator_.feedback_text();
  }
  int64_t outputs_received() const {
    std::lock_guard lock(mutex_);
    return emulator_.outputs_received();
  }
  int64_t reports_sent() const {
    std::lock_guard lock(mutex_);
    return emulator_.reports_sent();
  }

 private:
  static rise::firmware_protocol::HidDescriptor parsed_led_pad() {
    auto parsed = rise::firmware_protocol::parse_hid_descriptor(led_pad_descriptor);
    REQUIRE(parsed);
    return parsed.descriptor;
  }
  void run() {
    io::UhidEvent event;
    while (!stop_) {
      {
        std::lock_guard lock(mutex_);
        const auto now = std::chrono::steady_clock::now();
        const double t = std::chrono::duration<double>(now - script_start_).count();
        while (started_ && next_ < timeline_.events.size() && timeline_.events[next_].time_s <= t)
          emulator_.apply(timeline_.events[next_++]);
        if (device_.is_created())
          emulator_.tick(device_, std::chrono::duration_cast<std::chrono::microseconds>(now.time_since_epoch()).count());
        while (device_.poll(event, 0) == io::IoStatus::Ok)
          if (event.kind == io::UhidEvent::Kind::Output) emulator_.on_output(event.data);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }

  rise::panels::Timeline timeline_;
  rise::panels::HidEmulator emulator_;
  io::UhidDevice device_;
  mutable std::mutex mutex_;
  std::chrono::steady_clock::time_point script_start_;
  bool started_ = false;
  std::size_t next_ = 0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

const char* led_pad_panel =
    "panel: led-pad\n"
    "sources:\n"
    "  - {name: pad, protocol: hid, device: 'hid://1209:0001', timeout_ms: 200}\n"
    "controls:\n"
    "  - {name: drive_x, kind: axis, signal: x, safe: 0}\n"
    "  - {name: drive_y, kind: axis, signal: y, safe: 0}\n"
    "  - {name: deadman, kind: button, signal: button_1, role: deadman, safe: false}\n"
    "  - {name: horn, kind: button, signal: button_8, safe: false}\n"
    "feedback:\n"
    "  leds: [{name: power, signal: usage_0008_0001}, {name: fault, signal: usage_0008_0002},\n"
    "         {name: lamp, signal: usage_0008_0004}]\n";

std::string fmt_hex(uint8_t b) {
  const char* digits = "0123456789abcdef";
  return {digits[b >> 4], digits[b & 15]};
}

int64_t ms_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace

TEST_CASE("the HID emulator's timeline reaches the bridge through uhid, and the bridge's LEDs come back", "[vcan]") {
  const auto definition = rise::panels::parse_panel_definition(led_pad_panel, "led_pad.yaml");
  EmulatedPad pad(definition,
                  "0.0 drive_x 0.5\n0.0 drive_y -1\n0.0 deadman pressed\n"
                  "0.3 horn pressed\n0.3 drive_x -0.25\n");
  std::vector<std::unique_ptr<rise::hil::SourceTransport>> transports;
  transports.push_back(rise::hil::open_source(definition, 0, "hid://1209:0001"));
  Bridge bridge(definition, std::move(transports), [](const PanelSnapshot&) {});
  bridge.start();
  const auto control = [&](const char* name) { return *bridge.definition().find_control(name); };

  // The emulator sends its resting state every 8 ms: the panel is healthy
  // before the script starts, sticks centred.
  REQUIRE(wait_for([&] { return !bridge.snapshot().failsafe; }));
  PanelSnapshot snap = bridge.snapshot();
  CHECK(snap.controls[control("drive_x")].axis == Approx(0.0).margin(0.005));
  CHECK_FALSE(snap.controls[control("deadman")].pressed);
  // On open the bridge wrote the LEDs' output report; once the panel is ok
  // the fault LED goes dark (checked every feedback period, 100 ms).
  REQUIRE(wait_for([&] { return pad.feedback_text() == "leds power=on fault=off lamp=off; outputs usage_0008_0003=0"; }));

  const auto script_started = std::chrono::steady_clock::now();
  pad.start_script();
  REQUIRE(wait_for([&] { return bridge.snapshot().controls[control("deadman")].pressed; }));
  WARN("emulator timeline -> bridge snapshot (first event): " << ms_since(script_started) << " ms");
  snap = bridge.snapshot();
  CHECK(snap.controls[control("drive_x")].axis == Approx(0.5).margin(1.0 / 255));
  CHECK(snap.controls[control("drive_y")].axis == Approx(-1.0).margin(1e-6));
  REQUIRE(wait_for([&] { return pad.script_done() && bridge.snapshot().controls[control("horn")].pressed; }));
  snap = bridge.snapshot();
  CHECK(snap.controls[control("drive_x")].axis == Approx(-0.25).margin(1.0 / 255));
  CHECK(snap.controls[control("drive_y")].axis == Approx(-1.0).margin(1e-6));
  CHECK(snap.controls[control("deadman")].pressed);
  CHECK_FALSE(snap.failsafe);

  // A feedback request: the lamp's bit arrives in the next output report.
  const auto requested = std::chrono::steady_clock::now();
  rise::hil::FeedbackRequest request;
  request.leds = {{"lamp", true}};
  bridge.set_feedback(request);
  REQUIRE(wait_for([&] { return pad.feedback_text() == "leds power=on fault=off lamp=on; outputs usage_0008_0003=0"; }));
  WARN("feedback request -> output report at the device: " << ms_since(requested) << " ms");
  CHECK(bridge.take_notes().empty());  // every LED has its output signal

  // Unplug: failsafe, the fault LED cannot be shown any more (the device is
  // gone). Plug again: reopened by enumeration, the LEDs written at once.
  const auto unplugged = std::chrono::steady_clock::now();
  pad.unplug();
  REQUIRE(wait_for([&] { return bridge.snapshot().failsafe; }));
  WARN("emulator unplugged -> failsafe: " << ms_since(unplugged) << " ms");
  snap = bridge.snapshot();
  CHECK(snap.failsafe_reason == "pad: disconnected");
  CHECK(snap.controls[control("horn")].forced_safe);
  CHECK_FALSE(snap.controls[control("deadman")].pressed);
  const int64_t outputs_before = pad.outputs_received();
  const auto plugged = std::chrono::steady_clock::now();
  pad.plug();
  REQUIRE(wait_for([&] { return !bridge.snapshot().failsafe; }));
  WARN("emulator plugged -> bridge ok again: " << ms_since(plugged) << " ms");
  snap = bridge.snapshot();
  CHECK(snap.sources[0].reconnects == 1);
  CHECK(snap.controls[control("horn")].pressed);  // the emulator kept its state, as a pad's firmware would
  CHECK(snap.controls[control("drive_x")].axis == Approx(-0.25).margin(1.0 / 255));
  REQUIRE(wait_for([&] { return pad.outputs_received() > outputs_before; }));
  REQUIRE(wait_for([&] { return pad.feedback_text() == "leds power=on fault=off lamp=on; outputs usage_0008_0003=0"; }));
  CHECK(pad.reports_sent() > 0);
  bridge.stop();
}

TEST_CASE("rise-panel emulate --hid is a HID device the bridge reads and lights", "[vcan]") {
  // The program as a user runs it, its files written here.
  {
    std::ofstream("/tmp/led_pad.yaml") << led_pad_panel;
    std::ofstream("/tmp/led_pad_script.txt") << "0.0 drive_y 1\n0.0 deadman pressed\n0.2 horn pressed\n";
    std::ofstream hex("/tmp/led_pad.hex");
    hex << "# the LED test pad of tests/hid_test_devices.hpp\n";
    for (const uint8_t b : led_pad_descriptor) hex << fmt_hex(b) << ' ';
  }
  rise::process::ChildProcess panel({RISE_PANEL_BIN, "emulate", "--hid", "/tmp/led_pad.hex", "--hid-id", "1209:0003",
                                 "--hid-name", "rise-panel LED pad", "--panel", "/tmp/led_pad.yaml", "--script",
                                 "/tmp/led_pad_script.txt", "--hold"},
                                "/tmp/rise-panel.log");
  const auto log = [] {
    std::ifstream in("/tmp/rise-panel.log");
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  const auto definition = rise::panels::parse_panel_definition(led_pad_panel, "led_pad.yaml");
  std::vector<std::unique_ptr<rise::hil::SourceTransport>> transports;
  transports.push_back(rise::hil::open_source(definition, 0, "hid://1209:0003?name=rise-panel LED pad"));
  Bridge bridge(definition, std::move(transports),
                [](const PanelSnapshot&) {});
  bridge.start();
  const auto control = [&](const char* name) { return *bridge.definition().find_control(name); };
  INFO(log());
  REQUIRE(wait_for([&] { return bridge.snapshot().controls[control("horn")].pressed; }));
  PanelSnapshot snap = bridge.snapshot();
  CHECK_FALSE(snap.failsafe);
  CHECK(snap.controls[control("drive_y")].axis == Approx(1.0).margin(1e-6));
  CHECK(snap.controls[control("deadman")].pressed);
  CHECK(snap.controls[control("drive_x")].axis == Approx(0.0).margin(0.005));
  rise::hil::FeedbackRequest request;
  request.leds = {{"lamp", true}};
  bridge.set_feedback(request);
  REQUIRE(wait_for([&] {
    return log().find("feedback: leds power=on fault=off lamp=on; outputs usage_0008_0003=0") != std::string::npos;
  }));
  bridge.stop();
  CHECK(panel.stop() == 0);  // SIGTERM: a clean stop that unplugs the device
  CHECK(log().find("rise-panel stopped: ") != std::string::npos);
}

TEST_CASE("a live uhid pad recorded as rise-hild --record records it verifies, and a changed byte fails", "[vcan]") {
  const auto definition = rise::panels::parse_panel_definition(led_pad_panel, "led_pad.yaml");
  // On one vCPU under TCG a thread waits milliseconds for the CPU between a
  // report's stamp and the mapper taking it (or between a state and its
  // publish): verified with 20 ms of time tolerance, not 2. The pad repeats
  // its report every 50 ms, so that a changed byte outlives the tolerance.
  rise::panels::HidEmulatorSettings slow;
  slow.report_period_us = 50'000;
  EmulatedPad pad(definition,
                  "0.0 deadman pressed\n0.1 drive_x 0.5\n0.2 drive_y -1\n0.3 horn pressed\n0.4 drive_x -0.25\n", slow);
  rise::hil::VerifySettings verify_settings;
  verify_settings.time_tolerance_us = 20'000;
  const std::string dir = "/tmp/hid-session";
  std::filesystem::remove_all(dir);
  const auto control = [&](const char* name) { return *definition.find_control(name); };
  int64_t reports = 0;
  {
    rise::hil::test::RecordedHidSession session(definition, std::make_unique<io::HidDevice>("hid://1209:0001"), dir);
    auto& published = session.published;
    REQUIRE(published.wait_for([](const PanelSnapshot& s) { return !s.failsafe; }, 20000));
    pad.start_script();
    REQUIRE(published.wait_for(
        [&](const PanelSnapshot& s) {
          return s.controls[control("horn")].pressed && s.controls[control("drive_x")].axis < -0.2f;
        },
        20000));
    // Unplugged and plugged in again: the recording gets a second R: block.
    std::size_t from = published.size();
    pad.unplug();
    REQUIRE(published.wait_for([](const PanelSnapshot& s) { return s.failsafe_reason == "pad: disconnected"; }, 20000,
                               from));
    from = published.size();
    pad.plug();
    REQUIRE(published.wait_for([](const PanelSnapshot& s) { return !s.failsafe && s.sources[0].reconnects == 1; },
                               20000, from));
    REQUIRE(published.wait_for([](const PanelSnapshot&) { return true; }, 20000, published.size() + 20));
    session.stop();
    const auto c = session.recorder().counts();
    CHECK(c.write_errors == 0);
    CHECK(c.lcm_events == session.messages());
    CHECK(c.hid_reports >= 10);  // the script's five changes and the 50 ms repeats around them
    reports = c.hid_reports;
  }
  // The device as the kernel names it, at both plugs.
  rise::hil::io::HidRecordingReader reader(dir + "/pad.hid");
  CHECK(reader.plugs() == 2);
  CHECK(reader.reports() == reports);
  rise::hil::io::HidRecordingRecord first;
  REQUIRE(reader.next(first));
  CHECK(first.kind == rise::hil::io::HidRecordingRecord::Kind::Plug);
  CHECK(first.bytes == std::vector<uint8_t>(std::begin(led_pad_descriptor), std::end(led_pad_descriptor)));
  CHECK(first.identity.name == "rise LED test pad (uhid)");
  CHECK(first.identity.bus == 5);  // uhid's default, Bluetooth
  CHECK(first.identity.vendor_id == 0x1209);
  CHECK(first.identity.product_id == 0x0001);

  const auto golden = rise::hil::read_panel_state_log(dir + "/panel_state.lcmlog");
  const auto started = std::chrono::steady_clock::now();
  const auto report =
      rise::hil::verify_replay(definition, rise::hil::captures_in(definition, dir), golden.messages, verify_settings);
  WARN("recorded " << reports << " HID reports and " << golden.messages.size() << " PanelState messages; verify: "
                   << report.messages << " matched (" << report.off_time << " off their utime) in "
                   << ms_since(started) << " ms");
  if (report.difference) INFO(rise::hil::describe(*report.difference));
  CHECK(report.passed());
  CHECK(report.messages == golden.messages.size());

  // One report byte changed (x of the first report that moved it): the first
  // difference names drive_x.
  std::string text = [&] {
    std::ifstream in(dir + "/pad.hid");
    return std::string(std::istreambuf_iterator<char>(in), {});
  }();
  REQUIRE(rise::hil::test::undo_first_change(text, 1) > 0);  // byte 1 after the report id: x
  std::ofstream(dir + "/pad.hid") << text;
  const auto bad =
      rise::hil::verify_replay(definition, rise::hil::captures_in(definition, dir), golden.messages, verify_settings);
  REQUIRE_FALSE(bad.passed());
  WARN("changed byte: " << rise::hil::describe(*bad.difference));
  CHECK(bad.difference->field == "drive_x");
  std::filesystem::remove_all(dir);
}
