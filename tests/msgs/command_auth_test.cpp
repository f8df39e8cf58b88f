#include <catch2/catch.hpp>

#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "msgs/command_auth.hpp"

namespace fs = std::filesystem;
using rise::msgs::CommandVerifier;
using rise::msgs::Verdict;

namespace {
fs::path temp_dir() {
  fs::path dir = fs::temp_directory_path() / ("rise-auth-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}
rise::msgs::InstructorKey test_key(uint8_t fill) {
  rise::msgs::InstructorKey key;
  key.bytes.assign(32, fill);
  return key;
}
rise_msgs::FaultCommand stuck_command() {
  rise_msgs::FaultCommand c{};
  c.issuer = "instructor";
  c.trainee_id = "t1";
  c.action = "inject";
  c.fault_id = "f1";
  c.kind = "stuck_at";
  c.target = "drive_y";
  c.value = 0.5;
  return c;
}
}  // namespace

TEST_CASE("hmac-sha256 matches the RFC 4231 test case 2 vector", "[instructor]") {
  rise::msgs::InstructorKey key;
  key.bytes = {'J', 'e', 'f', 'e'};
  const std::string data = "what do ya want for nothing?";
  const auto mac = rise::msgs::hmac_sha256(key, std::span(reinterpret_cast<const uint8_t*>(data.data()), data.size()));
  const std::array<uint8_t, 32> expected = {0x5b, 0xdc, 0xc1, 0x46, 0xbf, 0x60, 0x75, 0x4e, 0x6a, 0x04, 0x24,
                                            0x26, 0x08, 0x95, 0x75, 0xc7, 0x5a, 0x00, 0x3f, 0x08, 0x9d, 0x27,
                                            0x39, 0x83, 0x9d, 0xec, 0x58, 0xb9, 0x64, 0xec, 0x38, 0x43};
  CHECK(mac == expected);
}

TEST_CASE("canonical encoding length-prefixes strings so fields cannot be shifted", "[instructor]") {
  rise_msgs::FaultCommand a = stuck_command();
  rise_msgs::FaultCommand b = a;
  a.kind = "stuck_at";
  a.target = "drive_y";
  b.kind = "stuck_atdrive_y";
  b.target = "";
  CHECK(rise::msgs::canonical_bytes(a) != rise::msgs::canonical_bytes(b));
  const auto bytes = rise::msgs::canonical_bytes(a);
  // domain "rise-fault-command-v1": 4-byte length 21, then the text.
  REQUIRE(bytes.size() > 25);
  CHECK(bytes[3] == 21);
  CHECK(std::string(bytes.begin() + 4, bytes.begin() + 25) == "rise-fault-command-v1");
}

TEST_CASE("a verifier accepts a signed command once and rejects every forgery", "[instructor]") {
  const auto key = test_key(0x42);
  CommandVerifier verifier(key, 5'000'000);
  const int64_t now = 1'700'000'000'000'000;
  rise_msgs::FaultCommand c = stuck_command();
  c.utime = now;
  rise::msgs::sign(c, key);
  CHECK(c.signature_len == 32);
  CHECK(c.nonce != 0);

  SECTION("good, then replayed") {
    CHECK(verifier.check(c, now + 1000) == Verdict::Accepted);
    CHECK(verifier.check(c, now + 2000) == Verdict::Replayed);
    CHECK(verifier.rejected() == 1);
  }
  SECTION("unsigned") {
    c.signature.clear();
    c.signature_len = 0;
    CHECK(verifier.check(c, now) == Verdict::Unsigned);
  }
  SECTION("signed with another key") {
    rise_msgs::FaultCommand other = stuck_command();
    other.utime = now;
    rise::msgs::sign(other, test_key(0x43));
    CHECK(verifier.check(other, now) == Verdict::BadSignature);
  }
  SECTION("a field changed after signing") {
    c.value = 0.9;
    CHECK(verifier.check(c, now) == Verdict::BadSignature);
  }
  SECTION("too old or from the future") {
    CHECK(verifier.check(c, now + 6'000'000) == Verdict::OutsideWindow);
    CHECK(verifier.check(c, now - 6'000'000) == Verdict::OutsideWindow);
  }
  SECTION("training control is signed and checked the same way") {
    rise_msgs::TrainingControl t{};
    t.issuer = "instructor";
    t.trainee_id = "t1";
    t.command = "restart";
    t.utime = now;
    rise::msgs::sign(t, key);
    CHECK(verifier.check(t, now) == Verdict::Accepted);
    t.command = "stop";
    CHECK(verifier.check(t, now) == Verdict::BadSignature);
  }
}

TEST_CASE("key files are written 0600 and refused when others can read them", "[instructor]") {
  const fs::path dir = temp_dir();
  const fs::path path = dir / "instructor.key";
  fs::remove(path);
  const auto written = rise::msgs::write_new_instructor_key(path.string());
  struct stat st {};
  REQUIRE(::stat(path.c_str(), &st) == 0);
  CHECK((st.st_mode & 0777) == 0600);
  CHECK(rise::msgs::load_instructor_key(path.string()).bytes == written.bytes);
  CHECK_THROWS_WITH(rise::msgs::write_new_instructor_key(path.string()), Catch::Contains("exists"));

  SECTION("world-readable") {
    ::chmod(path.c_str(), 0644);
    CHECK_THROWS_WITH(rise::msgs::load_instructor_key(path.string()), Catch::Contains("mode 0644"));
  }
  SECTION("bad hex names the line") {
    const fs::path bad = dir / "bad.key";
    std::ofstream(bad) << "# comment\n\nzz00\n";
    ::chmod(bad.c_str(), 0600);
    CHECK_THROWS_WITH(rise::msgs::load_instructor_key(bad.string()), Catch::Contains("bad.key:3: key"));
  }
  SECTION("too short") {
    const fs::path shorter = dir / "short.key";
    std::ofstream(shorter) << "00112233\n";
    ::chmod(shorter.c_str(), 0600);
    CHECK_THROWS_WITH(rise::msgs::load_instructor_key(shorter.string()), Catch::Contains("4 bytes"));
  }
  fs::remove_all(dir);
}
