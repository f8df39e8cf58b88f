#include <catch2/catch.hpp>

#include "instructor/trainee_links.hpp"

using rise::instructor::TraineeLinks;

namespace {

// An echo of a station whose clock is `offset_us` ahead, `leg_us` each way,
// probed at t1 (ours); returns t4 (ours) for on_echo.
rise_msgs::ClockEcho echo(int64_t t1, int64_t offset_us, int64_t leg_us, int64_t* t4) {
  rise_msgs::ClockEcho e{};
  e.probe_utime = t1;
  e.receive_utime = t1 + leg_us + offset_us;
  e.utime = e.receive_utime + 50;
  e.publisher.host = "station-b";
  *t4 = t1 + 2 * leg_us + 50;
  return e;
}

constexpr int64_t kWall = 1'800'000'000'000'000;  // our wall clock, µs

}  // namespace

TEST_CASE("a trainee is live while heard, lost after the silence, and live again when heard", "[instructor]") {
  TraineeLinks links(500'000);
  CHECK_FALSE(links.link("t1", 0));
  links.heard("t1", "station-a", kWall - 1'000, kWall, 10'000'000);
  auto l = links.link("t1", 10'100'000);
  REQUIRE(l);
  CHECK(l->state == "live");
  CHECK(l->heard_ago_us == 100'000);
  CHECK(l->arrival_age_us == 1'000);
  CHECK(links.link("t1", 10'500'000)->state == "live");
  CHECK(links.link("t1", 10'500'001)->state == "lost");
  links.heard("t1", "station-a", kWall + 700'000, kWall + 700'000, 10'700'000);
  CHECK(links.link("t1", 10'700'010)->state == "live");
  CHECK(links.links(10'700'010).size() == 1);
}

TEST_CASE("a station's clock offset is measured and its states are judged in our clock", "[instructor]") {
  TraineeLinks links(500'000);
  // Station B's clock runs 7 s ahead: its states look 7 s from the future.
  links.heard("b", "station-b", kWall + 7'000'000, kWall + 1'000, 1'000'000);
  SECTION("before any echo its stamps are taken as ours: stale") {
    const auto l = links.link("b", 1'000'000);
    CHECK_FALSE(l->clock);
    CHECK(l->state == "stale");
    CHECK(l->arrival_age_us == 1'000 - 7'000'000);
    CHECK_FALSE(links.offset_us("b"));
  }
  SECTION("after echoes the least delayed one's offset applies: live") {
    int64_t t4 = 0;
    const auto slow = echo(kWall, 7'000'000, 9'000, &t4);
    auto late_leg = slow;
    late_leg.receive_utime += 8'000;  // the probe's leg took 8 ms longer: 4 ms off
    late_leg.utime += 8'000;
    links.on_echo("b", late_leg, t4 + 8'000);
    const auto quick = echo(kWall + 500'000, 7'000'000, 200, &t4);
    links.on_echo("b", quick, t4);
    REQUIRE(links.offset_us("b"));
    CHECK(*links.offset_us("b") == 7'000'000);
    const auto l = links.link("b", 1'000'000);
    REQUIRE(l->clock);
    CHECK(l->clock->delay_us == 400);
    CHECK(l->clock_host == "station-b");
    CHECK(l->state == "live");
    CHECK(l->arrival_age_us == 1'000);
  }
}

TEST_CASE("each host of a station is judged by its own clock", "[instructor]") {
  TraineeLinks links(500'000);
  int64_t t4 = 0;
  // rise-hild on the console's PC (station-b, 7 s ahead), rise-sim on a server whose clock is right.
  const auto b = echo(kWall, 7'000'000, 300, &t4);
  links.on_echo("b", b, t4);
  auto here = echo(kWall, 0, 100, &t4);
  here.publisher.host = "sim-server";
  links.on_echo("b", here, t4);
  links.heard("b", "station-b", kWall + 7'000'000, kWall + 1'000, 1'000'000);
  auto l = links.link("b", 1'000'000);
  CHECK(l->clock_host == "station-b");
  CHECK(l->arrival_age_us == 1'000);
  CHECK(l->state == "live");
  links.heard("b", "sim-server", kWall + 2'000, kWall + 2'500, 1'001'000);
  l = links.link("b", 1'001'000);
  CHECK(l->clock_host == "sim-server");
  CHECK(l->arrival_age_us == 500);
  CHECK(l->state == "live");
  SECTION("a host that never answered is judged by the station's best clock") {
    links.heard("b", "elsewhere", kWall + 7'003'000, kWall + 3'500, 1'002'000);
    l = links.link("b", 1'002'000);
    CHECK(l->clock_host == "sim-server");  // the least delayed of the two
    CHECK(l->state == "stale");
  }
  CHECK(*links.offset_us("b") == 0);  // the least delayed host's
}
