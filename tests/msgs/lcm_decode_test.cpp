// The generated decode() with msgs/lcm_gen.sh's checks: a string length of
// 0, -1 or INT32_MIN, and a negative array count, are malformed (decode()
// returns -1: no exception, no signed overflow); decode_message() counts
// them. The INT32_MIN length was found by tests/fuzz/command_auth_fuzz.cpp.

#include <catch2/catch.hpp>

#include <algorithm>
#include <climits>
#include <cstdint>
#include <vector>

#include "msgs/lcm_decode.hpp"
#include "rise_msgs/PanelFeedback.hpp"
#include "rise_msgs/TrainingControl.hpp"

namespace {

template <class Message>
std::vector<uint8_t> encoded(const Message& m) {
  std::vector<uint8_t> bytes(static_cast<size_t>(m.getEncodedSize()));
  REQUIRE(m.encode(bytes.data(), 0, static_cast<int>(bytes.size())) == static_cast<int>(bytes.size()));
  return bytes;
}

void put_be32(std::vector<uint8_t>& bytes, size_t at, int32_t value) {
  const auto v = static_cast<uint32_t>(value);
  for (int i = 0; i < 4; ++i) bytes[at + static_cast<size_t>(i)] = static_cast<uint8_t>(v >> (24 - 8 * i));
}

}  // namespace

TEST_CASE("a string length below 1 is a malformed message, not an exception", "[msgs]") {
  rise_msgs::TrainingControl control{};
  control.issuer = "instructor", control.trainee_id = "t1", control.command = "start", control.task = "approach";
  const std::vector<uint8_t> good = encoded(control);
  rise_msgs::TrainingControl out;
  REQUIRE(out.decode(good.data(), 0, static_cast<int>(good.size())) == static_cast<int>(good.size()));
  REQUIRE(out.issuer == "instructor");

  for (const int32_t length : {0, -1, INT32_MIN}) {
    INFO("issuer length " << length);
    std::vector<uint8_t> bad = good;
    put_be32(bad, 16, length);  // after the type hash and utime
    int result = 0;
    REQUIRE_NOTHROW(result = out.decode(bad.data(), 0, static_cast<int>(bad.size())));
    CHECK(result < 0);
    const uint64_t before = rise::msgs::malformed_messages();
    CHECK_FALSE(rise::msgs::decode_message(bad.data(), static_cast<int64_t>(bad.size()), out));
    CHECK(rise::msgs::malformed_messages() == before + 1);
  }
}

TEST_CASE("a negative array count is a malformed message, not an exception", "[msgs]") {
  rise_msgs::PanelFeedback feedback{};
  feedback.panel_id = "p";
  feedback.num_leds = 1, feedback.led_names = {"a"}, feedback.led_on = {1};
  std::vector<uint8_t> bytes = encoded(feedback);
  // num_leds (int16 1), then led_names[0]: length 2, "a\0".
  const std::vector<uint8_t> leds = {0x00, 0x01, 0x00, 0x00, 0x00, 0x02, 'a', 0x00};
  const auto at = std::search(bytes.begin(), bytes.end(), leds.begin(), leds.end());
  REQUIRE(at != bytes.end());
  at[0] = 0xFF, at[1] = 0xFF;  // -1
  rise_msgs::PanelFeedback out;
  int result = 0;
  REQUIRE_NOTHROW(result = out.decode(bytes.data(), 0, static_cast<int>(bytes.size())));
  CHECK(result < 0);
  CHECK_FALSE(rise::msgs::decode_message(bytes.data(), static_cast<int64_t>(bytes.size()), out));
}

// Found by tests/fuzz/lcm_messages_fuzz.cpp (a PanelFeedback whose display
// name was "s\0\0\x01\0"): lcm-gen's decode() took a string with a NUL
// inside, its encode() writes only up to that NUL while getEncodedSize()
// counted the whole string, so the message re-encoded short and
// lcm::LCM::publish() sent the rest of its buffer uninitialised.
TEST_CASE("a string with a NUL inside does not decode, and encodes no longer than it is", "[msgs]") {
  rise_msgs::TrainingControl control{};
  control.issuer = "instructor", control.trainee_id = "t1", control.command = "start", control.task = "approach";
  std::vector<uint8_t> bytes = encoded(control);
  const auto at = std::search(bytes.begin(), bytes.end(), control.issuer.begin(), control.issuer.end());
  REQUIRE(at != bytes.end());
  at[4] = '\0';  // "inst\0uctor"
  rise_msgs::TrainingControl out;
  CHECK(out.decode(bytes.data(), 0, static_cast<int>(bytes.size())) < 0);
  CHECK_FALSE(rise::msgs::decode_message(bytes.data(), static_cast<int64_t>(bytes.size()), out));

  // Sent anyway (a string made in this process): what is encoded is up to the NUL, and all of it counted.
  control.task = std::string("appr\0ach", 8);
  const std::vector<uint8_t> sent = encoded(control);  // REQUIREs encode() to fill getEncodedSize()
  REQUIRE(rise::msgs::decode_message(sent.data(), static_cast<int64_t>(sent.size()), out));
  CHECK(out.task == "appr");
  CHECK(out.command == "start");
}
