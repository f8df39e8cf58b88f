#include "msgs/command_auth.hpp"
#include "msgs/clock.hpp"

#include <fcntl.h>
#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/hmac.h>
#include <openssl/rand.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <stdexcept>

namespace rise::msgs {
namespace {

class Canonical {
 public:
  explicit Canonical(const char* domain) { add(std::string(domain)); }
  void add(int64_t v) {
    const auto u = static_cast<uint64_t>(v);
    for (int shift = 56; shift >= 0; shift -= 8) bytes_.push_back(static_cast<uint8_t>(u >> shift));
  }
  void add(double v) {
    int64_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    add(bits);
  }
  void add(const std::string& s) {
    const auto n = static_cast<uint32_t>(s.size());
    for (int shift = 24; shift >= 0; shift -= 8) bytes_.push_back(static_cast<uint8_t>(n >> shift));
    bytes_.insert(bytes_.end(), s.begin(), s.end());
  }
  std::vector<uint8_t> take() { return std::move(bytes_); }

 private:
  std::vector<uint8_t> bytes_;
};

int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

template <class Command>
void set_signature(Command& c, const InstructorKey& key) {
  if (c.utime == 0) c.utime = wall_us();
  if (c.nonce == 0) c.nonce = random_nonce();
  const auto mac = hmac_sha256(key, canonical_bytes(c));
  c.signature.assign(mac.begin(), mac.end());
  c.signature_len = static_cast<int16_t>(c.signature.size());
}

}  // namespace

InstructorKey load_instructor_key(const std::string& path) {
  if (path.empty()) throw std::runtime_error("instructor key: no file given (--instructor-key or RISE_INSTRUCTOR_KEY)");
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) throw std::runtime_error(path + ": cannot open: " + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) throw std::runtime_error(path + ": instructor key: not a regular file");
  if ((st.st_mode & 077) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(st.st_mode & 07777));
    throw std::runtime_error(path + ": instructor key: mode " + mode +
                             " lets others read it; chmod 600 it");
  }
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open: " + std::strerror(errno));
  InstructorKey key;
  std::string line;
  int line_no = 0;
  int key_line = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::string hex;
    for (char c : line)
      if (c != ' ' && c != '\t' && c != '\r') hex.push_back(c);
    if (hex.empty()) continue;
    if (key_line != 0)
      throw std::runtime_error(path + ":" + std::to_string(line_no) + ": key: a second key line (first at line " +
                               std::to_string(key_line) + ")");
    key_line = line_no;
    if (hex.size() % 2 != 0)
      throw std::runtime_error(path + ":" + std::to_string(line_no) + ": key: odd number of hex digits");
    for (std::size_t i = 0; i < hex.size(); i += 2) {
      const int hi = hex_digit(hex[i]);
      const int lo = hex_digit(hex[i + 1]);
      if (hi < 0 || lo < 0)
        throw std::runtime_error(path + ":" + std::to_string(line_no) + ": key: '" + hex.substr(i, 2) +
                                 "' is not hex");
      key.bytes.push_back(static_cast<uint8_t>(hi * 16 + lo));
    }
  }
  if (key_line == 0) throw std::runtime_error(path + ": key: no key line");
  if (key.bytes.size() < 32 || key.bytes.size() > 64)
    throw std::runtime_error(path + ":" + std::to_string(key_line) + ": key: " + std::to_string(key.bytes.size()) +
                             " bytes, want 32..64");
  return key;
}

InstructorKey write_new_instructor_key(const std::string& path) {
  InstructorKey key;
  key.bytes.resize(32);
  if (RAND_bytes(key.bytes.data(), static_cast<int>(key.bytes.size())) != 1)
    throw std::runtime_error("instructor key: RAND_bytes failed");
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL, 0600);
  if (fd < 0) throw std::runtime_error(path + ": cannot create: " + std::strerror(errno));
  std::string text = "# rise instructor key (HMAC-SHA256); keep it on the instructor station only\n";
  static const char* digits = "0123456789abcdef";
  for (uint8_t b : key.bytes) {
    text.push_back(digits[b >> 4]);
    text.push_back(digits[b & 15]);
  }
  text.push_back('\n');
  const bool ok = ::write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
  ::close(fd);
  if (!ok) throw std::runtime_error(path + ": instructor key: short write");
  return key;
}

std::string instructor_key_path(const std::string& flag) {
  if (!flag.empty()) return flag;
  const char* env = std::getenv("RISE_INSTRUCTOR_KEY");
  return env ? std::string(env) : std::string();
}

std::array<uint8_t, 32> hmac_sha256(const InstructorKey& key, std::span<const uint8_t> data) {
  std::array<uint8_t, 32> out{};
  unsigned int len = 0;
  HMAC(EVP_sha256(), key.bytes.data(), static_cast<int>(key.bytes.size()), data.data(), data.size(), out.data(),
       &len);
  return out;
}

std::vector<uint8_t> canonical_bytes(const rise_msgs::FaultCommand& c) {
  Canonical b("rise-fault-command-v1");
  b.add(c.utime);
  b.add(c.issuer);
  b.add(c.nonce);
  b.add(c.trainee_id);
  b.add(c.action);
  b.add(c.fault_id);
  b.add(c.kind);
  b.add(c.target);
  b.add(c.value);
  b.add(c.rate);
  b.add(c.duration_s);
  b.add(c.seed);
  return b.take();
}

std::vector<uint8_t> canonical_bytes(const rise_msgs::TrainingControl& c) {
  Canonical b("rise-training-control-v1");
  b.add(c.utime);
  b.add(c.issuer);
  b.add(c.nonce);
  b.add(c.trainee_id);
  b.add(c.command);
  b.add(c.task);
  return b.take();
}

int64_t random_nonce() {
  int64_t n = 0;
  while (n == 0) RAND_bytes(reinterpret_cast<unsigned char*>(&n), sizeof n);
  return n;
}

void sign(rise_msgs::FaultCommand& command, const InstructorKey& key) { set_signature(command, key); }
void sign(rise_msgs::TrainingControl& command, const InstructorKey& key) { set_signature(command, key); }

const char* to_string(Verdict verdict) {
  switch (verdict) {
    case Verdict::Accepted: return "accepted";
    case Verdict::Unsigned: return "unsigned";
    case Verdict::BadSignature: return "bad signature";
    case Verdict::OutsideWindow: return "outside window";
    case Verdict::Replayed: return "replayed";
  }
  return "?";
}

CommandVerifier::CommandVerifier(InstructorKey key, int64_t window_us) : key_(std::move(key)), window_us_(window_us) {}

Verdict CommandVerifier::check(const rise_msgs::FaultCommand& c, int64_t now_us) {
  return check(c.issuer, c.utime, c.nonce, canonical_bytes(c), c.signature, now_us);
}

Verdict CommandVerifier::check(const rise_msgs::TrainingControl& c, int64_t now_us) {
  return check(c.issuer, c.utime, c.nonce, canonical_bytes(c), c.signature, now_us);
}

Verdict CommandVerifier::check(const std::string& issuer, int64_t utime, int64_t nonce,
                               std::span<const uint8_t> canonical, const std::vector<uint8_t>& signature,
                               int64_t now_us) {
  const auto verdict = [&]() {
    if (signature.empty()) return Verdict::Unsigned;
    const auto mac = hmac_sha256(key_, canonical);
    if (signature.size() != mac.size() || CRYPTO_memcmp(signature.data(), mac.data(), mac.size()) != 0)
      return Verdict::BadSignature;
    if (utime > now_us + window_us_ || utime < now_us - window_us_) return Verdict::OutsideWindow;
    auto& seen = seen_[issuer];
    while (!seen.empty() && seen.front().at_us < now_us - 2 * window_us_) seen.pop_front();
    for (const Seen& s : seen)
      if (s.nonce == nonce) return Verdict::Replayed;
    seen.push_back({nonce, now_us});
    return Verdict::Accepted;
  }();
  if (verdict == Verdict::Accepted)
    ++accepted_;
  else
    ++rejected_;
  return verdict;
}

}  // namespace rise::msgs
