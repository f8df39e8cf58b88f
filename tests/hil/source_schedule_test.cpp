// When the bridge's one source loop reopens a transport and writes its
// feedback (hil/source_schedule.hpp), for each policy a transport states.

#include <catch2/catch.hpp>

#include "hil/source_schedule.hpp"

using rise::hil::FeedbackPolicy;
using rise::hil::FeedbackSchedule;
using rise::hil::ReopenSchedule;

TEST_CASE("a back-off reopen waits min_ms after a failure, doubling up to max_ms, and starts again once open",
          "[hil]") {
  ReopenSchedule s = ReopenSchedule::back_off(100, 350);
  CHECK(s.due(0));
  s.attempted(0, false);
  CHECK_FALSE(s.due(99'999));
  CHECK(s.due(100'000));
  s.attempted(100'000, false);
  CHECK_FALSE(s.due(299'999));
  CHECK(s.due(300'000));
  s.attempted(300'000, false);  // 400 ms capped at 350
  CHECK_FALSE(s.due(649'999));
  CHECK(s.due(650'000));
  s.attempted(650'000, true);
  SECTION("a transport lost again is tried at once, then after min_ms") {
    CHECK(s.due(700'000));
    s.attempted(700'000, false);
    CHECK_FALSE(s.due(799'999));
    CHECK(s.due(800'000));
  }
}

TEST_CASE("an enumeration looks every period from each attempt, and every 20 ms for a second after an arrival",
          "[hil]") {
  ReopenSchedule s = ReopenSchedule::enumeration(500);
  CHECK(s.due(0));
  s.attempted(0, true);
  CHECK_FALSE(s.due(499'999));  // even after a success: the period runs from the attempt
  CHECK(s.due(500'000));
  s.attempted(500'000, false);
  s.arrived(600'000);
  CHECK(s.due(600'000));
  s.attempted(600'000, false);
  CHECK_FALSE(s.due(619'999));
  CHECK(s.due(620'000));
  s.attempted(1'700'000, false);  // the second is over
  CHECK_FALSE(s.due(2'199'999));
  CHECK(s.due(2'200'000));
}

TEST_CASE("feedback is built when never written, at its period or when the request changes, and resent by policy",
          "[hil]") {
  const auto [repeat, resent_at_period] = GENERATE(table<bool, bool>({{true, true}, {false, false}}));
  FeedbackPolicy policy;
  policy.repeat = repeat;
  FeedbackSchedule s(policy, 100);
  CHECK(s.due(0, 0, false));
  CHECK(s.resend(0));
  s.built(0, 0, true);
  CHECK_FALSE(s.due(50'000, 0, true));
  CHECK(s.due(50'000, 1, false));       // a new request
  CHECK_FALSE(s.resend(50'000));         // written only if it changed
  s.built(50'000, 1, true);
  CHECK(s.due(100'000, 1, false));      // the period, from the last one
  CHECK(s.resend(100'000) == resent_at_period);
  s.built(100'000, 1, false);           // failed: tried again at once, whatever it is
  CHECK(s.due(100'001, 1, false));
  CHECK(s.resend(100'001));
  s.built(100'001, 1, true);
  CHECK_FALSE(s.due(150'000, 1, false));
  s.forget();                            // reopened
  CHECK(s.due(150'000, 1, false));
  CHECK(s.resend(150'000));
}

TEST_CASE("a polled transport's feedback is built after each poll and only then", "[hil]") {
  FeedbackPolicy policy;
  policy.after_each_poll = true;
  FeedbackSchedule s(policy, 100);
  CHECK_FALSE(s.due(0, 0, false));
  CHECK(s.due(0, 0, true));
  CHECK(s.resend(0));
  s.built(0, 0, true);
  CHECK_FALSE(s.due(200'000, 5, false));
  CHECK(s.due(20'000, 0, true));
  CHECK_FALSE(s.resend(20'000));
  CHECK(s.resend(100'000));
}
