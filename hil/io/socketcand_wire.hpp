#pragma once

// The socketcand ASCII protocol in raw mode (linux-can/socketcand,
// doc/protocol.md and src/state_raw.c): pure encode/decode, no I/O.
//
//   server → client   < hi >   < ok >   < error TEXT >
//                     < frame 123 1700000000.123456 0A1B2C >       (data: no spaces)
//                     < frame 1ABCDEF0 1700000000.123456  >        (29-bit id, no data)
//                     < fdframe 123 01 1700000000.123456 00..0B >  (flags: 1 BRS, 2 ESI)
//                     < rtr 123 1700000000.123456 4 >
//                     < error 004 1700000000.123456 >              (error class)
//   client → server   < open can0 >   < rawmode >   < echo >
//                     < send 123 3 0A 1B 2C >                      (id hex, dlc, bytes hex)
//                     < fdsend 123 1 12 00 01 .. 0B >              (flags hex, len decimal)
//                     < sendrtr 123 4 >
// An id is a 29-bit id when written with 8 digits (socketcand) or above 7FF.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

#include "hil/io/can_frame.hpp"

namespace rise::hil::io::socketcand {

/// Room for the longest message written here: an fdsend of 64 bytes.
inline constexpr size_t kMaxMessageLength = 256;
using MessageBuffer = std::array<char, kMaxMessageLength>;

/// Writes the server → client message for frame (`frame`, `fdframe`, `rtr`
/// or `error`) stamped with timestamp_us (µs since the epoch). Returns the
/// length written, 0 when the frame is not well formed. No allocation.
size_t format_frame(const CanFrame& frame, int64_t timestamp_us, MessageBuffer& out);

/// Writes the client → server command that sends frame (`send`, `fdsend` or
/// `sendrtr`). Returns the length, 0 for a frame the protocol cannot send
/// (error frames, frames that are not well formed). No allocation.
size_t format_send(const CanFrame& frame, MessageBuffer& out);

enum class MessageKind {
  Hi,
  Ok,
  Echo,
  Open,       ///< text: the bus name
  Rawmode,
  Frame,      ///< frame: a received frame (`frame`, `fdframe`, `rtr`, `error` with class)
  Send,       ///< frame: a frame to send (`send`, `fdsend`, `sendrtr`)
  Error,      ///< text: the error message (`< error could not open bus >`)
  Other,      ///< text: a command this code does not use (`< stat ... >`, `< bcmmode >`)
  Malformed,  ///< text: a known command with bad arguments
};

struct Message {
  MessageKind kind = MessageKind::Other;
  CanFrame frame;
  std::string_view text;  ///< points into the decoded message
};

/// Decodes one message `< ... >` as StreamParser cuts it. No allocation.
Message parse_message(std::string_view message);

/// Cuts a TCP byte stream into `< ... >` messages. Bytes outside brackets
/// are skipped, and so is an opened message that a new '<' interrupts; a
/// message longer than the buffer is dropped. Fixed storage, no allocation.
class StreamParser {
 public:
  static constexpr size_t kCapacity = 4096;

  /// Where to read new bytes to (never empty); moves pending bytes first.
  std::span<char> free_space();
  /// Accepts n bytes written into free_space().
  void commit(size_t n);
  /// The next complete message, brackets included; valid until the next
  /// free_space() or clear().
  std::optional<std::string_view> next();
  void clear();
  /// Bytes skipped as garbage since construction.
  uint64_t skipped_bytes() const { return skipped_; }

 private:
  std::array<char, kCapacity> buffer_{};
  size_t begin_ = 0;
  size_t end_ = 0;
  uint64_t skipped_ = 0;
};

}  // namespace rise::hil::io::socketcand
