#include <catch2/catch.hpp>

#include <lcm/lcm-cpp.hpp>

#include <cstdlib>
#include <optional>

#include "msgs/channels.hpp"
#include "msgs/clock.hpp"
#include "msgs/clock_offset.hpp"
#include "msgs/publisher_session.hpp"

using rise::msgs::clock_sample;
using rise::msgs::ClockOffsetFilter;

TEST_CASE("a probe and its echo give the offset and the round trip of the header's worked example", "[msgs]") {
  const auto s = clock_sample(1000, 6'001'200, 6'001'250, 1500);
  CHECK(s.offset_us == 5'999'975);
  CHECK(s.delay_us == 450);
  CHECK(s.at_us == 1500);
  SECTION("a clock behind gives a negative offset") {
    // The station 3 s behind, 100 µs each way, 20 µs to answer.
    const int64_t t1 = 1'700'000'000'000'000;
    const auto behind = clock_sample(t1, t1 + 100 - 3'000'000, t1 + 120 - 3'000'000, t1 + 220);
    CHECK(behind.offset_us == -3'000'000);
    CHECK(behind.delay_us == 200);
  }
}

TEST_CASE("the clock filter takes the least delayed of its last samples", "[msgs]") {
  ClockOffsetFilter filter(3);
  CHECK_FALSE(filter.best());
  // One leg held up 8 ms: that sample's offset is 4 ms off.
  filter.add({5'004'000, 8'300, 1});
  filter.add({5'000'050, 300, 2});
  filter.add({5'001'000, 2'300, 3});
  REQUIRE(filter.best());
  CHECK(filter.best()->offset_us == 5'000'050);
  SECTION("the best one leaves the window after `window` newer ones") {
    filter.add({5'002'000, 4'300, 4});
    CHECK(filter.best()->offset_us == 5'000'050);
    filter.add({5'003'000, 6'300, 5});
    CHECK(filter.best()->offset_us == 5'001'000);
    filter.add({5'001'500, 3'300, 6});
    filter.add({5'002'500, 5'300, 7});
    CHECK(filter.best()->offset_us == 5'001'500);
  }
}

namespace {
struct EchoTaker {
  std::optional<rise_msgs::ClockEcho> echo;
  int64_t t4 = 0;
  void on(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::ClockEcho* e) {
    echo = *e;
    t4 = rise::msgs::wall_us();
  }
};
}  // namespace

TEST_CASE("a responder answers a probe for its station only, with its publisher and its clock", "[msgs]") {
  lcm::LCM lcm("memq://");
  REQUIRE(lcm.good());
  const rise_msgs::Publisher& self = rise::msgs::init_publisher("clock-test");
  rise::msgs::ClockEchoResponder responder(lcm, self);
  responder.listen("t1");
  EchoTaker taker;
  lcm.subscribe(rise::msgs::clock_echo_channel("t1"), &EchoTaker::on, &taker);
  lcm.subscribe(rise::msgs::clock_echo_channel("t2"), &EchoTaker::on, &taker);

  rise_msgs::ClockProbe probe{};
  probe.prober_session = 42;
  probe.seq = 7;
  SECTION("another station's probe is not answered") {
    probe.utime = rise::msgs::wall_us();
    lcm.publish(rise::msgs::clock_probe_channel("t2"), &probe);
    while (lcm.handleTimeout(20) > 0) {
    }
    CHECK_FALSE(taker.echo);
    CHECK(responder.answered() == 0);
  }
  SECTION("its own station's probe is echoed") {
    probe.utime = rise::msgs::wall_us();
    lcm.publish(rise::msgs::clock_probe_channel("t1"), &probe);
    while (lcm.handleTimeout(20) > 0) {
    }
    REQUIRE(taker.echo);
    CHECK(responder.answered() == 1);
    CHECK(taker.echo->seq == 7);
    CHECK(taker.echo->prober_session == 42);
    CHECK(taker.echo->publisher.session_id == self.session_id);
    const auto s = clock_sample(taker.echo->probe_utime, taker.echo->receive_utime, taker.echo->utime, taker.t4);
    // One process, one clock: no offset beyond the scheduling noise.
    CHECK(std::abs(s.offset_us) < 20'000);
    CHECK(s.delay_us >= 0);
  }
}
