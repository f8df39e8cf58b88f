#include <catch2/catch.hpp>

#include <array>
#include <cmath>

#include "hil/control_transforms.hpp"

using namespace rise::hil;

TEST_CASE("axis shaping applies invert, deadband, expo and scale in that order", "[hil]") {
  struct Row {
    float raw;
    AxisShaping s;
    float expected;
  };
  const auto r = GENERATE(Row{0.04f, {0.05f, 0.0f, 1.0f, false}, 0.0f},            // inside the deadband
                          Row{1.0f, {0.05f, 0.0f, 1.0f, false}, 1.0f},             // full travel kept
                          Row{0.525f, {0.05f, 0.0f, 1.0f, false}, 0.5f},           // rescaled: (0.525-0.05)/0.95
                          Row{0.5f, {0.0f, 1.0f, 1.0f, false}, 0.125f},            // pure cubic
                          Row{0.5f, {0.0f, 0.5f, 1.0f, false}, 0.3125f},           // 0.5·0.5 + 0.5·0.125
                          Row{-1.0f, {0.0f, 0.7f, 1.0f, false}, -1.0f},            // expo keeps the ends
                          Row{0.8f, {0.0f, 0.0f, 0.5f, true}, -0.4f},              // invert then scale
                          Row{3.0f, {0.0f, 0.0f, 1.0f, false}, 1.0f});             // clamped
  CHECK(shape_axis(r.raw, r.s) == Approx(r.expected).margin(1e-6));
}

TEST_CASE("the low-pass follows a step with the exponential of its time constant", "[hil]") {
  LowPass lp(100.0f);  // τ = 100 ms
  CHECK(lp.update(0.0f, 0) == 0.0f);
  float y = 0.0f;
  for (int64_t t = 10'000; t <= 100'000; t += 10'000) y = lp.update(1.0f, t);
  CHECK(y == Approx(1.0 - std::exp(-1.0)).margin(1e-4));  // one τ → 63.2 %
  lp.reset(0.0f, 100'000);
  CHECK(lp.update(0.0f, 110'000) == 0.0f);
  LowPass pass(0.0f);
  CHECK(pass.update(0.7f, 5) == 0.7f);
}

TEST_CASE("debounce ignores chatter shorter than its time", "[hil]") {
  ButtonFilter b({ButtonMode::Direct, 20, 0, 0});
  CHECK_FALSE(b.update(false, 0));
  CHECK_FALSE(b.update(true, 1'000));
  CHECK_FALSE(b.update(false, 5'000));   // bounced back within 20 ms
  CHECK_FALSE(b.update(true, 10'000));
  CHECK_FALSE(b.update(true, 29'000));   // held 19 ms
  CHECK(b.update(true, 30'000));         // held 20 ms
  CHECK(b.update(false, 31'000));        // release not yet accepted
  CHECK_FALSE(b.update(false, 51'000));
}

TEST_CASE("toggle flips on each press, and a button held at start-up does not toggle", "[hil]") {
  ButtonFilter t({ButtonMode::Toggle, 0, 0, 0});
  CHECK_FALSE(t.update(true, 0));  // held when first read
  CHECK_FALSE(t.update(true, 1000));
  CHECK_FALSE(t.update(false, 2000));
  CHECK(t.update(true, 3000));
  CHECK(t.update(false, 4000));
  CHECK_FALSE(t.update(true, 5000));
}

TEST_CASE("long press reports only after the hold time, edge pulses once per press", "[hil]") {
  ButtonFilter lp({ButtonMode::LongPress, 0, 800, 0});
  CHECK_FALSE(lp.update(false, 0));
  CHECK_FALSE(lp.update(true, 100'000));
  CHECK_FALSE(lp.update(true, 899'000));
  CHECK(lp.update(true, 900'000));
  CHECK_FALSE(lp.update(false, 950'000));

  ButtonFilter e({ButtonMode::Edge, 0, 0, 100});
  CHECK_FALSE(e.update(false, 0));
  CHECK(e.update(true, 10'000));
  CHECK(e.update(true, 109'000));
  CHECK_FALSE(e.update(true, 110'000));  // still held: one pulse per press
  CHECK_FALSE(e.update(false, 200'000));
  CHECK(e.update(true, 210'000));
}

TEST_CASE("a multi-position switch is read from several bits", "[hil]") {
  const std::array<uint8_t, 2> two{4, 5};
  CHECK(switch_from_bits(0b000000, two, BitsEncoding::Binary, 3) == std::optional<uint8_t>(0));
  CHECK(switch_from_bits(0b010000, two, BitsEncoding::Binary, 3) == std::optional<uint8_t>(1));
  CHECK(switch_from_bits(0b100000, two, BitsEncoding::Binary, 3) == std::optional<uint8_t>(2));
  CHECK_FALSE(switch_from_bits(0b110000, two, BitsEncoding::Binary, 3).has_value());  // 3 ≥ positions
  const std::array<uint8_t, 3> three{0, 1, 2};
  CHECK(switch_from_bits(0b100, three, BitsEncoding::OneHot, 3) == std::optional<uint8_t>(2));
  CHECK_FALSE(switch_from_bits(0b000, three, BitsEncoding::OneHot, 3).has_value());   // between positions
  CHECK_FALSE(switch_from_bits(0b011, three, BitsEncoding::OneHot, 3).has_value());   // two contacts closed
}
