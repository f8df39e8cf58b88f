// One publisher per station: the Publisher every periodic message carries,
// the watch that reports a second process on a channel, and the start-up
// probe, over LCM's in-process memq:// provider.

#include <catch2/catch.hpp>

#include <lcm/lcm-cpp.hpp>
#include <unistd.h>

#include <chrono>
#include <climits>
#include <future>
#include <thread>

#include "msgs/publisher_session.hpp"
#include "rise_msgs/PanelState.hpp"
#include "rise_msgs/RobotState.hpp"

using rise::msgs::PublisherWatch;

namespace {
rise_msgs::Publisher other_process(int64_t session, int64_t started_utime = 1'000'000) {
  rise_msgs::Publisher p{};
  p.session_id = session;
  p.program = "rise-hild";
  p.host = "lab3";
  p.pid = 4242;
  p.started_utime = started_utime;
  return p;
}
}  // namespace

TEST_CASE("this process is one publisher: a session id, its host, pid and start time, drawn once", "[panels]") {
  const auto& p = rise::msgs::init_publisher("rise-test");
  CHECK(p.session_id > 0);
  CHECK(p.program == "rise-test");
  CHECK(p.pid == static_cast<int32_t>(::getpid()));
  CHECK_FALSE(p.host.empty());
  CHECK(p.started_utime > 0);
  CHECK(rise::msgs::this_publisher().session_id == p.session_id);
  CHECK(rise::msgs::describe(other_process(0x5f3a09c100000000), 13'000'000) ==
        "rise-hild pid 4242 on lab3 (session 5f3a09c1, started 12.0 s ago)");
}

TEST_CASE("the publisher watch reports another process once per channel and again after it was gone",
          "[panels]") {
  PublisherWatch watch(7, 2'000'000);
  const auto other = other_process(9);
  SECTION("its own messages are not another publisher") {
    CHECK_FALSE(watch.observe("rise/t1/panel_state", other_process(7), 0));
    CHECK(watch.others(0).empty());
  }
  SECTION("a new process is reported once, with its host and pid") {
    const auto first = watch.observe("rise/t1/panel_state", other, 100);
    REQUIRE(first);
    CHECK(first->channel == "rise/t1/panel_state");
    CHECK(first->publisher.pid == 4242);
    CHECK(first->publisher.host == "lab3");
    CHECK_FALSE(watch.observe("rise/t1/panel_state", other, 10'000));
    CHECK(watch.others(10'000).size() == 1);
    // The same process on another channel is another report.
    CHECK(watch.observe("rise/t1/robot_state", other, 20'000));
  }
  SECTION("one gone for longer than the window is forgotten, and reported again when it is back") {
    REQUIRE(watch.observe("rise/t1/panel_state", other, 0));
    CHECK(watch.others(2'500'000).empty());
    CHECK(watch.observe("rise/t1/panel_state", other, 2'500'000));
  }
}

TEST_CASE("of two publishers that started together the later one gives way, a tie to the lower session",
          "[panels]") {
  CHECK(rise::msgs::yields_to(other_process(1, 2000), other_process(2, 1000)));
  CHECK_FALSE(rise::msgs::yields_to(other_process(2, 1000), other_process(1, 2000)));
  CHECK(rise::msgs::yields_to(other_process(5, 1000), other_process(3, 1000)));
  CHECK_FALSE(rise::msgs::yields_to(other_process(3, 1000), other_process(5, 1000)));
}

TEST_CASE("the start-up probe finds another process on a station's channel and ignores this one's", "[panels]") {
  lcm::LCM lcm("memq://");
  REQUIRE(lcm.good());
  // A periodic publisher beside the probe (memq:// drops a message that no
  // subscription waits for, as a real channel nobody listens on would).
  const auto publishing = [&lcm](const std::string& channel, auto message) {
    return std::async(std::launch::async, [&lcm, channel, message] {
      for (int i = 0; i < 40; ++i) {
        lcm.publish(channel, &message);
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
    });
  };
  rise_msgs::PanelState own{};
  own.publisher = rise::msgs::this_publisher();
  rise_msgs::PanelState foreign{};
  foreign.publisher = other_process(99);
  SECTION("nothing there") {
    CHECK_FALSE(rise::msgs::probe_channel<rise_msgs::PanelState>(lcm, "rise/t1/panel_state", 30));
  }
  SECTION("only this process's own messages there") {
    auto done = publishing("rise/t1/panel_state", own);
    CHECK_FALSE(rise::msgs::probe_channel<rise_msgs::PanelState>(lcm, "rise/t1/panel_state", 100));
  }
  SECTION("another process there, on one of several channels") {
    auto done = publishing("rise/t2/panel_state", foreign);
    const auto found =
        rise::msgs::probe_channels<rise_msgs::PanelState>(lcm, {"rise/t1/panel_state", "rise/t2/panel_state"}, 150);
    REQUIRE(found);
    CHECK(found->channel == "rise/t2/panel_state");
    CHECK(found->publisher.session_id == 99);
    CHECK(found->publisher.pid == 4242);
  }
  SECTION("another type's channel is not this probe's") {
    rise_msgs::RobotState robot{};
    robot.publisher = other_process(99);
    auto done = publishing("rise/t1/robot_state", robot);
    CHECK_FALSE(rise::msgs::probe_channel<rise_msgs::PanelState>(lcm, "rise/t1/panel_state", 100));
  }
}

TEST_CASE("a publisher gives way only within its start-up window", "[panels]") {
  const auto self = other_process(5, 10'000'000);
  const auto earlier = other_process(3, 9'000'000);
  CHECK(rise::msgs::gives_way(self, earlier, 10'000'000 + rise::msgs::kGiveWayWindowUs - 1));
  CHECK_FALSE(rise::msgs::gives_way(self, earlier, 10'000'000 + rise::msgs::kGiveWayWindowUs));
  CHECK_FALSE(rise::msgs::gives_way(earlier, self, 9'000'001));  // the first one stays
}

// Found by the lcm_messages fuzz target: describe() subtracted a Publisher's
// started_utime, anyone's 64-bit number, from now in int64 (signed overflow
// for INT64_MIN); the age is computed in double.
TEST_CASE("a publisher's description takes any start time", "[msgs]") {
  rise_msgs::Publisher p{};
  p.program = "rise-sim", p.host = "h", p.pid = 7, p.started_utime = INT64_MIN;
  const std::string text = rise::msgs::describe(p, 1796289352257872);
  CHECK(text.rfind("rise-sim pid 7 on h", 0) == 0);
  CHECK(text.find("s ago)") != std::string::npos);
}
