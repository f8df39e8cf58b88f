#include <catch2/catch.hpp>

#include <atomic>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "hil/bridge.hpp"
#include "msgs/failsafe.hpp"
#include "panels/console_emulator.hpp"
#include "tests/hil/bridge_test_support.hpp"
#include "tests/hil_io/slcan_test_support.hpp"

using rise::hil::PanelSnapshot;
using namespace rise::hil::test;
using rise::hil::io::test::FakeAdapter;
using rise::hil::io::test::FakeAdapterOptions;
using rise::hil::io::test::SocatPtys;
using rise::hil::io::test::TempDir;

namespace {

constexpr const char* kMemUrl = "mem://slcan_chain";



// A USB slcan adapter plugged into the console's CAN: the fake adapter on the
// pty forwards what the bridge sends onto the mem:// bus, and every frame of
// the mem:// bus to the bridge as slcan text.
class AdapterOnMemBus {
 public:
  explicit AdapterOnMemBus(const std::string& pty_path) : mem_(rise::hil::io::open_can_bus(kMemUrl)) {
    FakeAdapterOptions options;
    options.on_frame_line = [this](const std::string& line) {
      if (const auto frame = rise::hil::io::test::parse_slcan_text(line)) mem_->send(*frame);
    };
    adapter_ = std::make_unique<FakeAdapter>(pty_path, std::move(options));
    thread_ = std::thread([this] { run(); });
  }
  ~AdapterOnMemBus() {
    running_ = false;
    thread_.join();
    adapter_.reset();
  }
  bool opened() const { return adapter_->opened(); }
  bool channel_open() const { return adapter_->channel_open(); }

 private:
  void run() {
    rise::hil::io::CanFrame f;
    while (running_) {
      // Like the real adapter: frames reach the host only while the channel is open.
      if (mem_->receive(f, 5) == rise::hil::io::IoStatus::Ok && adapter_->channel_open()) {
        adapter_->write(rise::hil::io::test::slcan_text(f) + "\r");
      }
    }
  }
  std::unique_ptr<rise::hil::io::CanBus> mem_;
  std::unique_ptr<FakeAdapter> adapter_;
  std::atomic<bool> running_{true};
  std::thread thread_;
};



}  // namespace

TEST_CASE("the bridge drives the emulated console over slcan through a pty pair, goes failsafe when the "
          "adapter is unplugged and recovers when it comes back",
          "[hil]") {
  if (!rise::hil::io::test::have_socat()) {
    WARN("/usr/bin/socat is absent (Debian package socat): skip");
    return;
  }
  const auto def = console();
  const auto drive_y = *def.find_control("drive_y");
  TempDir dir;
  auto ptys = std::make_unique<SocatPtys>(dir.path());
  REQUIRE(ptys->ready());
  auto adapter = std::make_unique<AdapterOnMemBus>(ptys->b());
  REQUIRE(adapter->opened());
  auto emulator = std::make_unique<EmulatorThread>(def, kMemUrl);
  emulator->apply(set(def, "deadman", 0, true));
  emulator->apply(set(def, "drive_y", 0.6f, false));

  Published published;
  std::vector<std::unique_ptr<rise::hil::io::CanBus>> buses;
  buses.push_back(rise::hil::io::open_can_bus("slcan://" + ptys->a() + "?bitrate=500000"));
  REQUIRE(buses.back()->is_open());
  rise::hil::Bridge bridge(def, std::move(buses), [&](const PanelSnapshot& s) { published.add(s); });
  bridge.start();

  const auto is_live = [&](const PanelSnapshot& s) {
    return !s.failsafe && s.deadman && s.controls[drive_y].axis > 0.5f;
  };
  const auto live = published.wait_for(is_live, 3000);
  REQUIRE(live.has_value());
  CHECK(live->controls[drive_y].axis == Approx((0.6 - 0.05) / 0.95).margin(1e-3));

  // Feedback travels the other way: bridge → slcan → adapter → console.
  rise::hil::FeedbackRequest request;
  request.displays.emplace_back("speed", 1.25f);
  bridge.set_feedback(request);
  const auto shows_speed = [&] {
    const auto fb = emulator->feedback();
    return fb.displays.count(0) == 1 && fb.displays.at(0).raw == 125 && (fb.leds_on & 1u) != 0;
  };
  CHECK(rise::hil::io::test::wait_until(shows_speed, std::chrono::seconds(3)));
  CHECK(emulator->feedback().bad_frames == 0);

  // Unplug the adapter: socat ends, the tty hangs up.
  const std::size_t before = published.size();
  ptys->stop();
  const auto lost = published.wait_for([](const PanelSnapshot& s) { return s.failsafe; }, 3000, before);
  REQUIRE(lost.has_value());
  CHECK(lost->controls[drive_y].axis == 0.0f);
  CHECK((rise::msgs::has(lost->failsafe_causes, rise::msgs::FailsafeCause::SourceDown) ||
         rise::msgs::has(lost->failsafe_causes, rise::msgs::FailsafeCause::SourceStale)));
  const int64_t timeout_us = 1000 * def.sources[0].timeout_ms;
  const int64_t period_us = def.publish_period_us();
  {
    std::lock_guard lock(published.mutex);
    for (const auto& s : published.snapshots)
      if (s.sources[0].last_frame_age_us > timeout_us) CHECK(s.failsafe);
  }
  // Within one publish period of the source timeout (plus slack for this
  // 2-core machine), whether the hang-up or the silence was noticed first.
  CHECK(lost->sources[0].last_frame_age_us <= timeout_us + period_us + 15000);
  adapter.reset();

  // Plug it in again: a new pty pair on the same path; the bridge reopens.
  ptys = std::make_unique<SocatPtys>(dir.path());
  REQUIRE(ptys->ready());
  adapter = std::make_unique<AdapterOnMemBus>(ptys->b());
  REQUIRE(adapter->opened());
  const std::size_t unplugged = published.size();
  // The bridge retries with a back-off of up to BridgeSettings::reopen_max_ms (2 s).
  const auto back = published.wait_for(is_live, 8000, unplugged);
  REQUIRE(back.has_value());
  CHECK(adapter->channel_open());
  CHECK(back->controls[drive_y].axis == Approx((0.6 - 0.05) / 0.95).margin(1e-3));
  bridge.stop();
}
