#include <catch2/catch.hpp>

#include <cstring>
#include <string>
#include <vector>

#include "hil/io/socketcand_wire.hpp"
#include "test_support.hpp"

using namespace rise::hil::io;
using namespace rise::hil::io::socketcand;
using rise::hil::io::test::make_fd_frame;
using rise::hil::io::test::make_frame;

namespace {

constexpr int64_t kTime = 1'700'000'000'123'456;

std::string frame_text(const CanFrame& f, int64_t t) {
  MessageBuffer out;
  return std::string(out.data(), format_frame(f, t, out));
}

std::string send_text(const CanFrame& f) {
  MessageBuffer out;
  return std::string(out.data(), format_send(f, out));
}

CanFrame remote(uint32_t id, uint8_t dlc) {
  CanFrame f;
  f.id = id;
  f.remote = true;
  f.len = dlc;
  return f;
}

CanFrame error_frame(uint32_t error_class) {
  CanFrame f;
  f.id = error_class;
  f.error = true;
  return f;
}

// Feeds text in pieces of chunk bytes and collects every message cut.
std::vector<std::string> cut(std::string_view text, size_t chunk, StreamParser& parser) {
  std::vector<std::string> messages;
  while (!text.empty()) {
    const auto space = parser.free_space();
    const size_t n = std::min({chunk, space.size(), text.size()});
    std::memcpy(space.data(), text.data(), n);
    parser.commit(n);
    text.remove_prefix(n);
    while (const auto m = parser.next()) messages.emplace_back(*m);
  }
  return messages;
}

}  // namespace

TEST_CASE("socketcand frames are written as socketcand writes them", "[hil_io]") {
  CHECK(frame_text(make_frame(0x111, {0x0A, 0x1B, 0x2C}), kTime) ==
        "< frame 111 1700000000.123456 0A1B2C >");
  CHECK(frame_text(make_frame(0x1ABCDEF0, {0xFF}, true), kTime) ==
        "< frame 1ABCDEF0 1700000000.123456 FF >");
  CHECK(frame_text(make_frame(0x5, {}, true), 1'000'000) == "< frame 00000005 1.000000  >");
  CHECK(frame_text(remote(0x123, 4), kTime) == "< rtr 123 1700000000.123456 4 >");
  CHECK(frame_text(error_frame(0x4), kTime) == "< error 004 1700000000.123456 >");
  CHECK(frame_text(make_fd_frame(0x123, 12, true), 0) ==
        "< fdframe 123 01 0.000000 A0A1A2A3A4A5A6A7A8A9AAAB >");
}

TEST_CASE("socketcand send commands are written with spaced hex bytes", "[hil_io]") {
  CHECK(send_text(make_frame(0x123, {0x0A, 0x1B, 0x2C})) == "< send 123 3 0A 1B 2C >");
  CHECK(send_text(make_frame(0xABCD, {}, true)) == "< send 0000ABCD 0 >");
  CHECK(send_text(remote(0x7FF, 8)) == "< sendrtr 7FF 8 >");
  CHECK(send_text(make_fd_frame(0x10, 12, true)).rfind("< fdsend 010 1 12 A0 A1 ", 0) == 0);
  CHECK(send_text(error_frame(0x4)).empty());
  CHECK(send_text(make_frame(0x800, {})).empty());
}

TEST_CASE("socketcand messages round-trip every kind of frame", "[hil_io]") {
  const CanFrame frame = GENERATE(make_frame(0x123, {1, 2, 3}), make_frame(0x7FF, {}),
                                  make_frame(0x1ABCDEF0, {0xDE, 0xAD}, true),
                                  make_frame(0x5, {1, 2, 3, 4, 5, 6, 7, 8}, true), remote(0x321, 2),
                                  make_fd_frame(0x42, 64, true), make_fd_frame(0x43, 20, false));
  SECTION("server to client") {
    const Message m = parse_message(frame_text(frame, kTime));
    REQUIRE(m.kind == MessageKind::Frame);
    CHECK(same_content(m.frame, frame));
    CHECK(m.frame.timestamp_us == kTime);
  }
  SECTION("client to server") {
    const Message m = parse_message(send_text(frame));
    REQUIRE(m.kind == MessageKind::Send);
    CHECK(same_content(m.frame, frame));
  }
}

TEST_CASE("socketcand messages from other peers decode", "[hil_io]") {
  SECTION("python-can writes unpadded ids and single-digit bytes") {
    const Message m = parse_message("< send 1ABCDEF0 2 de a >");
    REQUIRE(m.kind == MessageKind::Send);
    CHECK(same_content(m.frame, make_frame(0x1ABCDEF0, {0xDE, 0x0A}, true)));
  }
  SECTION("an id above 7FF is a 29-bit id even when short") {
    const Message m = parse_message("< send 12345 0 >");
    REQUIRE(m.kind == MessageKind::Send);
    CHECK(m.frame.extended);
  }
  SECTION("protocol.md writes frame data spaced") {
    const Message m = parse_message("< frame 123 23.424242 11 22 33 44 >");
    REQUIRE(m.kind == MessageKind::Frame);
    CHECK(same_content(m.frame, make_frame(0x123, {0x11, 0x22, 0x33, 0x44})));
    CHECK(m.frame.timestamp_us == 23'424'242);
  }
  SECTION("handshake and replies") {
    CHECK(parse_message("< hi >").kind == MessageKind::Hi);
    CHECK(parse_message("< ok >").kind == MessageKind::Ok);
    CHECK(parse_message("<rawmode>").kind == MessageKind::Rawmode);
    const Message open = parse_message("< open can0 >");
    CHECK(open.kind == MessageKind::Open);
    CHECK(open.text == "can0");
    const Message error = parse_message("< error could not open bus >");
    CHECK(error.kind == MessageKind::Error);
    CHECK(error.text == "could not open bus");
    CHECK(parse_message("< stat 1 2 3 4 >").kind == MessageKind::Other);
  }
}

TEST_CASE("malformed socketcand frames and sends are recognised", "[hil_io]") {
  const std::string text = GENERATE(as<std::string>{}, "< frame 123 >", "< frame XYZ 1.000000 00 >",
      "< frame 123 1.000000 ABC >", "< frame 123 1.000000 0102030405060708FF >",
      "< frame 20000000 1.000000 >", "< frame 123 1.1234567 00 >", "< frame 123 x.5 00 >",
      "< fdframe 123 01 1.000000 010203040506070809 >", "< rtr 123 1.000000 9 >",
      "< send 123 3 01 02 >", "< send 123 9 1 2 3 4 5 6 7 8 9 >", "< send 123 1 100 >",
      "< send 123456789 0 >", "< fdsend 123 0 13 >", "< sendrtr 123 >", "< open >");
  CAPTURE(text);
  CHECK(parse_message(text).kind == MessageKind::Malformed);
}

TEST_CASE("the stream parser cuts messages wherever the reads split them", "[hil_io]") {
  const std::string stream = "< hi >< ok >< frame 123 1.000000 0A1B2C >< frame 456 2.000000  >";
  const size_t chunk = GENERATE(as<size_t>{}, 1, 2, 3, 7, 64);
  StreamParser parser;
  const auto messages = cut(stream, chunk, parser);
  CAPTURE(chunk);
  REQUIRE(messages.size() == 4);
  CHECK(messages[0] == "< hi >");
  CHECK(messages[2] == "< frame 123 1.000000 0A1B2C >");
  CHECK(messages[3] == "< frame 456 2.000000  >");
  CHECK(parser.skipped_bytes() == 0);
}

TEST_CASE("the stream parser skips garbage between messages", "[hil_io]") {
  StreamParser parser;
  const auto messages = cut("noise< ok >\r\n>>junk<< frame 1 1.0 >xx<unterminated < hi >", 5, parser);
  REQUIRE(messages.size() == 3);
  CHECK(messages[0] == "< ok >");
  CHECK(messages[1] == "< frame 1 1.0 >");
  CHECK(messages[2] == "< hi >");
  CHECK(parser.skipped_bytes() > 0);
}

TEST_CASE("the stream parser drops a message longer than its buffer", "[hil_io]") {
  StreamParser parser;
  std::string stream = "<" + std::string(StreamParser::kCapacity + 10, 'x') + "< ok >";
  const auto messages = cut(stream, 512, parser);
  REQUIRE(messages.size() == 1);
  CHECK(messages[0] == "< ok >");
}
