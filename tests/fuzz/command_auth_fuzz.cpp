// libFuzzer target: the signed-command verifier on arbitrary LCM bytes of a
// FaultCommand or TrainingControl (the first input byte picks which; seeds
// are real encodings, so mutations reach the fields past LCM's type hash).
// Whatever decodes is never accepted as it came (the receiver's key signed
// none of it: a forged HMAC would be a bug); signed with the key it is accepted
// at its own time and then refused as a replay; its canonical bytes are the
// same twice. Nothing may crash or trigger a sanitizer. The seeds (a signed
// fault and a training command, encoded by lcm-gen's code) are written into
// the corpus folder at start.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <string>

#include "msgs/command_auth.hpp"
#include "msgs/lcm_decode.hpp"
#include "tests/fuzz/fuzz_check.hpp"

namespace m = rise::msgs;

namespace {

// The receiver's key; the seeds are signed with another (a well-formed
// signature the verifier must still refuse).
const m::InstructorKey& key() {
  static const m::InstructorKey k{std::vector<uint8_t>(32, 0x5a)};
  return k;
}
const m::InstructorKey& seed_key() {
  static const m::InstructorKey k{std::vector<uint8_t>(32, 0xa5)};
  return k;
}

template <typename Command>
void verify(const uint8_t* data, std::size_t size) {
  Command command;
  // As every receiver decodes (lcm-gen's decode() throws on a string length <= 0).
  if (!m::decode_message(data, static_cast<int64_t>(size), command)) return;
  fuzz_check(m::canonical_bytes(command) == m::canonical_bytes(command));
  m::CommandVerifier verifier(key());
  fuzz_check(verifier.check(command, command.utime) != m::Verdict::Accepted);
  if (command.utime <= 0 || command.utime > INT64_MAX / 2) return;  // sign() would stamp it with the wall clock
  m::sign(command, key());
  fuzz_check(verifier.check(command, command.utime) == m::Verdict::Accepted);
  fuzz_check(verifier.check(command, command.utime) == m::Verdict::Replayed);
}

template <typename Command>
void write_seed(const std::string& path, uint8_t which, Command command) {
  m::sign(command, seed_key());
  std::vector<uint8_t> bytes(static_cast<std::size_t>(command.getEncodedSize()) + 1);
  bytes[0] = which;
  command.encode(bytes.data() + 1, 0, command.getEncodedSize());
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()),
                                              static_cast<std::streamsize>(bytes.size()));
}

}  // namespace

// The seeds go into every folder named on the command line (the corpus).
extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  rise::fuzz::for_each_corpus_folder(*argc, *argv, [](const std::string& dir) {
    rise_msgs::FaultCommand fault{};
    fault.issuer = "instructor", fault.trainee_id = "t1", fault.action = "inject", fault.fault_id = "stick-stuck";
    fault.kind = "stuck_at", fault.target = "drive_y", fault.value = 0.4, fault.duration_s = 5, fault.seed = 7;
    write_seed(dir + "/fault", 0, fault);
    rise_msgs::TrainingControl control{};
    control.issuer = "instructor", control.trainee_id = "t1", control.command = "start", control.task = "approach";
    write_seed(dir + "/training", 1, control);
  });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  if (data[0] & 1)
    verify<rise_msgs::TrainingControl>(data + 1, size - 1);
  else
    verify<rise_msgs::FaultCommand>(data + 1, size - 1);
  return 0;
}
