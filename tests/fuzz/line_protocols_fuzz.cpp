// libFuzzer target: the CAN line protocols read from a peer — socketcand's
// `< ... >` messages cut from a TCP byte stream, and slcan adapter lines. The
// bytes go through socketcand's StreamParser in chunks the input's first byte
// sizes, each message through parse_message, each '\r'-ended piece through
// parse_slcan_line. A decoded frame is well formed (a `frame`/`send` one),
// writes back to a message or line that decodes to the same frame, and
// nothing may crash, allocate without bound or trigger a sanitizer.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string_view>

#include "hil/io/slcan_wire.hpp"
#include "hil/io/socketcand_wire.hpp"

namespace io = rise::hil::io;
namespace sc = rise::hil::io::socketcand;

namespace {

void check(bool ok) {
  if (!ok) std::abort();
}

bool same(const io::CanFrame& a, const io::CanFrame& b) {
  return a.id == b.id && a.extended == b.extended && a.remote == b.remote && a.fd == b.fd && a.len == b.len &&
         (a.remote || std::memcmp(a.data.data(), b.data.data(), a.len) == 0);
}

void socketcand_message(std::string_view message) {
  const sc::Message m = sc::parse_message(message);
  if (m.kind != sc::MessageKind::Frame && m.kind != sc::MessageKind::Send) return;
  if (m.frame.error) return;  // error frames carry a class, written back differently
  check(io::is_well_formed(m.frame));
  sc::MessageBuffer out;
  const size_t n = m.kind == sc::MessageKind::Frame ? sc::format_frame(m.frame, 1'700'000'000'123'456, out)
                                                    : sc::format_send(m.frame, out);
  check(n > 0 && n <= out.size());
  const sc::Message again = sc::parse_message(std::string_view(out.data(), n));
  check(again.kind == m.kind && same(again.frame, m.frame));
}

void slcan_lines(std::string_view bytes) {
  size_t begin = 0;
  while (begin < bytes.size()) {
    const size_t end = std::min(bytes.find('\r', begin), bytes.size());
    const auto line = io::parse_slcan_line(bytes.substr(begin, end - begin));
    if (line) {
      check(io::is_well_formed(line->frame) && !line->frame.fd);
      check(line->stamp_ms < io::kSlcanStampWrapMs);
      io::SlcanLineBuffer out;
      const size_t n = io::format_slcan_line(line->frame, out);
      check(n >= 2 && n <= out.size() && out[0] == '\r' && out[n - 1] == '\r');
      const auto again = io::parse_slcan_line(std::string_view(out.data() + 1, n - 2));
      check(again && same(again->frame, line->frame) && again->stamp_ms == -1);
    }
    begin = end + 1;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string_view bytes(reinterpret_cast<const char*>(data) + 1, size - 1);
  // The stream in chunks of 1..256 bytes, as TCP might deliver it.
  const size_t chunk = static_cast<size_t>(data[0]) + 1;
  sc::StreamParser parser;
  for (size_t at = 0; at < bytes.size();) {
    const auto room = parser.free_space();
    check(!room.empty());
    const size_t n = std::min({chunk, room.size(), bytes.size() - at});
    std::memcpy(room.data(), bytes.data() + at, n);
    parser.commit(n);
    at += n;
    while (const auto message = parser.next()) {
      check(message->size() >= 2 && message->front() == '<' && message->back() == '>');
      socketcand_message(*message);
    }
  }
  slcan_lines(bytes);
  return 0;
}
