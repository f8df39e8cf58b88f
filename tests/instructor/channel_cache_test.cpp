// The web console's channel cache: each SSE stream gets what changed since
// its last push, and a closed cache ends the streams.

#include <catch2/catch.hpp>

#include <chrono>

#include "instructor/channel_cache.hpp"

using rise::instructor::ChannelCache;
using namespace std::chrono_literals;

namespace {
Json::Value value(int n) {
  Json::Value v;
  v["n"] = n;
  return v;
}
}  // namespace

TEST_CASE("the channel cache gives a stream only the channels and events newer than its last push", "[instructor]") {
  ChannelCache cache;
  cache.store_latest("rise/a/panel_state", "a", "panel_state", value(1));
  cache.store_latest("rise/b/robot_state", "b", "robot_state", value(2));
  cache.store_event("a", "sim_event", value(3));

  uint64_t version = 0;
  auto first = cache.changes_since(&version, 0ms);
  REQUIRE(first);
  CHECK((*first)["channels"].size() == 2);
  CHECK((*first)["channels"]["rise/b/robot_state"]["trainee"].asString() == "b");
  REQUIRE((*first)["events"].size() == 1);
  CHECK((*first)["events"][0]["channel_kind"].asString() == "sim_event");
  CHECK((*first)["events"][0]["trainee"].asString() == "a");

  cache.store_latest("rise/a/panel_state", "a", "panel_state", value(4));
  auto second = cache.changes_since(&version, 0ms);
  REQUIRE(second);
  REQUIRE((*second)["channels"].size() == 1);
  CHECK((*second)["channels"]["rise/a/panel_state"]["value"]["n"].asInt() == 4);
  CHECK((*second)["events"].empty());

  auto none = cache.changes_since(&version, 10ms);
  REQUIRE(none);
  CHECK((*none)["channels"].empty());

  const auto trainees = cache.trainees();
  REQUIRE(trainees.size() == 2);
  CHECK(trainees.at("a")["panel_state"]["n"].asInt() == 4);

  cache.close();
  CHECK_FALSE(cache.changes_since(&version, 1s));
}

TEST_CASE("the channel cache keeps the newest events for a stream that falls behind", "[instructor]") {
  ChannelCache cache;
  const int stored = static_cast<int>(ChannelCache::kRecentEvents) + 50;
  for (int i = 0; i < stored; ++i) cache.store_event("a", "task_event", value(i));
  uint64_t version = 0;
  const auto update = cache.changes_since(&version, 0ms);
  REQUIRE(update);
  REQUIRE((*update)["events"].size() == ChannelCache::kRecentEvents);
  CHECK((*update)["events"][0]["n"].asInt() == 50);
}

TEST_CASE("the channel cache sends every sound cue to a stream, but none from before it opened", "[instructor]") {
  ChannelCache cache;
  cache.store_sound("a", value(1));  // played before the page opened
  uint64_t version = 0;
  auto first = cache.changes_since(&version, 0ms);
  REQUIRE(first);
  CHECK((*first)["sounds"].empty());
  // Two cues between pushes: both go out (a one-shot must not be coalesced away).
  cache.store_sound("a", value(2));
  cache.store_sound("b", value(3));
  auto second = cache.changes_since(&version, 0ms);
  REQUIRE(second);
  REQUIRE((*second)["sounds"].size() == 2);
  CHECK((*second)["sounds"][0]["n"].asInt() == 2);
  CHECK((*second)["sounds"][1]["trainee"].asString() == "b");
  CHECK((*second)["channels"].empty());
  auto none = cache.changes_since(&version, 0ms);
  REQUIRE(none);
  CHECK((*none)["sounds"].empty());
}
