#pragma once

// Signed instructor commands: HMAC-SHA256 (RFC 2104, OpenSSL) over a
// canonical encoding of a command's fields, a timestamp window and a
// per-issuer nonce record, so that only the station holding the instructor
// key can inject or clear faults or start/stop tasks, and a recorded command
// cannot be played again.
//
// Key file (`--instructor-key FILE`, or env RISE_INSTRUCTOR_KEY): text, one
// line of 64 hex digits (32 key bytes; 32..64 bytes accepted), `#` comments
// and blank lines ignored. It must be a regular file that neither group nor
// others can read or write (mode 0600 or 0400): anything else is refused,
// as ssh refuses a private key others can read. `rise-instructor keygen FILE`
// writes one from /dev/urandom (OpenSSL RAND_bytes) with mode 0600.
//
// Canonical encoding (what the HMAC covers), in field order, big-endian:
//   domain string ("rise-fault-command-v1" or "rise-training-control-v1"),
//   then each field: int64 → 8 bytes; double → its IEEE-754 bits as 8
//   bytes; string → uint32 length + UTF-8 bytes. Example: the string "ab"
//   encodes as 00 00 00 02 61 62; the int64 5 as 00 00 00 00 00 00 00 05.
//   FaultCommand: utime issuer nonce trainee_id action fault_id kind target
//   value rate duration_s seed. TrainingControl: utime issuer nonce
//   trainee_id command task. The signature field itself is not covered.
//
// Verification (CommandVerifier): no signature → Unsigned; a signature that
// is not the HMAC of the fields under the key (compared in constant time) →
// BadSignature; |utime − now| > window → OutsideWindow; an (issuer, nonce)
// already accepted within the window → Replayed. Nonces are remembered for
// twice the window, so a replay is caught however the clocks differ inside it.

#include <array>
#include <cstdint>
#include <deque>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "rise_msgs/FaultCommand.hpp"
#include "rise_msgs/TrainingControl.hpp"

namespace rise::msgs {

/// The instructor's secret (32..64 bytes).
struct InstructorKey {
  std::vector<uint8_t> bytes;
};

/// Reads a key file (format above). Throws std::runtime_error naming the
/// file (and line) for a missing file, a mode others can read, bad hex or a
/// wrong length. Not for the cyclic path.
InstructorKey load_instructor_key(const std::string& path);
/// Writes a new random 32-byte key to `path` with mode 0600 (refuses to
/// overwrite an existing file). Throws std::runtime_error on failure.
InstructorKey write_new_instructor_key(const std::string& path);
/// `flag` when not empty, else env RISE_INSTRUCTOR_KEY, else "".
std::string instructor_key_path(const std::string& flag);

/// HMAC-SHA256 of `data` under `key`.
std::array<uint8_t, 32> hmac_sha256(const InstructorKey& key, std::span<const uint8_t> data);

/// The canonical bytes the signature covers (format above).
std::vector<uint8_t> canonical_bytes(const rise_msgs::FaultCommand& command);
std::vector<uint8_t> canonical_bytes(const rise_msgs::TrainingControl& command);

/// A random nonce from OpenSSL's CSPRNG.
int64_t random_nonce();

/// Fills utime (when 0, with the wall clock) and nonce (when 0, random),
/// then sets the signature. Use right before publishing.
void sign(rise_msgs::FaultCommand& command, const InstructorKey& key);
void sign(rise_msgs::TrainingControl& command, const InstructorKey& key);

enum class Verdict { Accepted, Unsigned, BadSignature, OutsideWindow, Replayed };
/// "accepted", "unsigned", "bad signature", "outside window", "replayed".
const char* to_string(Verdict verdict);

/// Checks commands of every issuer against one key; remembers accepted
/// nonces per issuer. Not thread-safe (the receiver's LCM thread owns it).
class CommandVerifier {
 public:
  /// `window_us`: largest accepted |command time − now|.
  explicit CommandVerifier(InstructorKey key, int64_t window_us = 5'000'000);

  /// Judges one command at the receiver's wall clock `now_us`; an accepted
  /// one's nonce is recorded. Allocates a little (the nonce record).
  Verdict check(const rise_msgs::FaultCommand& command, int64_t now_us);
  Verdict check(const rise_msgs::TrainingControl& command, int64_t now_us);

  int64_t rejected() const { return rejected_; }
  int64_t accepted() const { return accepted_; }

 private:
  Verdict check(const std::string& issuer, int64_t utime, int64_t nonce, std::span<const uint8_t> canonical,
                const std::vector<uint8_t>& signature, int64_t now_us);

  InstructorKey key_;
  int64_t window_us_;
  struct Seen {
    int64_t nonce;
    int64_t at_us;  // receiver time it was accepted
  };
  std::map<std::string, std::deque<Seen>> seen_;  // per issuer, oldest first
  int64_t rejected_ = 0;
  int64_t accepted_ = 0;
};

}  // namespace rise::msgs
