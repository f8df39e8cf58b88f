#include "firmware_protocol/sdl_mapping.hpp"

#include <catch2/catch.hpp>

#include <string>

#include "tests/test_data.hpp"

namespace fp = rise::firmware_protocol;
using Catch::Matchers::Contains;

namespace {

const fp::SdlBinding* binding(const fp::SdlMapping& m, const std::string& target) {
  for (const auto& b : m.bindings)
    if (b.target == target) return &b;
  return nullptr;
}

void check_button(const fp::SdlMapping& m, const std::string& target, int index) {
  INFO(target);
  const fp::SdlBinding* b = binding(m, target);
  REQUIRE(b != nullptr);
  CHECK(b->input.kind == fp::SdlInput::Kind::Button);
  CHECK(b->input.index == index);
}

}  // namespace

TEST_CASE("SDL GUID of a Linux evdev device", "[sdl]") {
  // The Xbox 360 pad through xpad: bus 3 (USB), 045e:028e, version 0x0110.
  CHECK(fp::to_string(fp::sdl_linux_guid(3, 0x045e, 0x028e, 0x0110)) == "030000005e0400008e02000010010000");
  CHECK(fp::parse_sdl_guid("030000005e0400008e02000010010000") == fp::sdl_linux_guid(3, 0x045e, 0x028e, 0x0110));
  CHECK_FALSE(fp::parse_sdl_guid("030000005e0400008e0200001001000"));
  CHECK_FALSE(fp::parse_sdl_guid("030000005e0400008e0200001001000g"));
}

TEST_CASE("SDL mapping elements: buttons, half axes, inverted axes, hats", "[sdl]") {
  const auto m = fp::parse_sdl_mapping(
      "03000000c82d00005106000000000000,8BitDo M30,a:b0,dpdown:+a2,dpleft:-a0,lefty:a1~,-leftx:h0.8,"
      "righttrigger:+a5~,platform:Linux,");
  REQUIRE(m);
  CHECK(m->name == "8BitDo M30");
  CHECK(m->platform == "Linux");
  REQUIRE(m->bindings.size() == 6);
  CHECK(binding(*m, "dpdown")->input.half == 1);
  CHECK(binding(*m, "dpleft")->input.half == -1);
  CHECK(binding(*m, "lefty")->input.invert);
  const auto* left = binding(*m, "leftx");
  CHECK(left->target_half == -1);
  CHECK(left->input.kind == fp::SdlInput::Kind::Hat);
  CHECK(left->input.hat_mask == 8);
  CHECK(binding(*m, "righttrigger")->input.half == 1);
  CHECK(binding(*m, "righttrigger")->input.invert);
}

TEST_CASE("malformed SDL lines are counted with file:line and skipped", "[sdl]") {
  const auto db = fp::SdlControllerDb::parse(
      "# comment\n"
      "030000005e0400008e02000010010000,Pad,a:b0,platform:Linux,\n"
      "nothex,Pad,a:b0,platform:Linux,\n"
      "030000005e0400008e02000010010000,Pad,jump:b0,platform:Linux,\n"
      "030000005e0400008e02000010010000,Pad,a:q0,platform:Linux,\n"
      "030000005e0400008e02000010010000\n"
      "030000005e0400008e02000010010000,Pad,a:h0.99,platform:Linux,\n",
      "db.txt");
  CHECK(db.mappings().size() == 1);
  REQUIRE(db.problems().size() == 5);
  CHECK_THAT(db.problems()[0], Contains("db.txt:3:") && Contains("GUID 'nothex'"));
  CHECK_THAT(db.problems()[1], Contains("db.txt:4:") && Contains("unknown target 'jump'"));
  CHECK_THAT(db.problems()[2], Contains("db.txt:5:") && Contains("a:q0"));
  CHECK_THAT(db.problems()[3], Contains("db.txt:6:"));
  CHECK_THAT(db.problems()[4], Contains("db.txt:7:"));
  CHECK_THROWS_WITH(fp::SdlControllerDb::load("/nonexistent/db.txt"), "/nonexistent/db.txt: cannot read");
}

TEST_CASE("SDL lookup: exact version first, then any version; Linux lines only", "[sdl]") {
  const auto db = fp::SdlControllerDb::parse(
      "030000005e0400008e02000010010000,Win,a:b9,platform:Windows,\n"
      "030000005e0400008e02000000010000,Loose,a:b1,platform:Linux,\n"
      "030000005e0400008e02000010010000,Exact,a:b0,platform:Linux,\n",
      "db.txt");
  REQUIRE(db.find_linux(3, 0x045e, 0x028e, 0x0110) != nullptr);
  CHECK(db.find_linux(3, 0x045e, 0x028e, 0x0110)->name == "Exact");
  CHECK(db.find_linux(3, 0x045e, 0x028e, 0x0777)->name == "Loose");
  CHECK(db.find_linux(5, 0x045e, 0x028e, 0x0110) == nullptr);  // Bluetooth: another GUID
}

TEST_CASE("SDL_GameControllerDB's gamecontrollerdb.txt", "[sdl]") {
  const std::string path = rise::test::data_file("joystick-db/gamecontrollerdb.txt");
  if (path.empty()) {
    WARN("skipped: RISE_TEST_DATA/joystick-db/gamecontrollerdb.txt not found");
    return;
  }
  const auto db = fp::SdlControllerDb::load(path);
  // MANIFEST.md: 2256 device mappings in 2270 lines, and two "xinput" lines
  // (grep -v '^#' | grep -vc '^$': 2258); `grep -c platform:Linux`: 734.
  CHECK(db.problems().empty());
  CHECK(db.mappings().size() == 2258);
  CHECK(db.count_platform("Linux") == 734);
  const fp::SdlMapping* pad = db.find_linux(3, 0x045e, 0x028e, 0x0110);
  REQUIRE(pad != nullptr);
  CHECK(fp::to_string(pad->guid) == "030000005e0400008e02000010010000");
  CHECK(pad->name == "Xbox 360 Controller");
  CHECK(pad->bindings.size() == 21);
  for (const auto& [name, index] : {std::pair{"a", 0}, {"b", 1}, {"x", 2}, {"y", 3}, {"leftshoulder", 4},
                                    {"rightshoulder", 5}, {"back", 6}, {"start", 7}, {"guide", 8},
                                    {"leftstick", 9}, {"rightstick", 10}})
    check_button(*pad, name, index);
  for (const auto& [name, index] : {std::pair{"leftx", 0}, {"lefty", 1}, {"lefttrigger", 2}, {"rightx", 3},
                                    {"righty", 4}, {"righttrigger", 5}}) {
    INFO(name);
    const fp::SdlBinding* b = binding(*pad, name);
    REQUIRE(b != nullptr);
    CHECK(b->input.kind == fp::SdlInput::Kind::Axis);
    CHECK(b->input.index == index);
    CHECK(b->input.half == 0);
  }
  for (const auto& [name, mask] : {std::pair{"dpup", 1}, {"dpright", 2}, {"dpdown", 4}, {"dpleft", 8}}) {
    const fp::SdlBinding* b = binding(*pad, name);
    REQUIRE(b != nullptr);
    CHECK(b->input.kind == fp::SdlInput::Kind::Hat);
    CHECK(b->input.index == 0);
    CHECK(b->input.hat_mask == mask);
  }
  CHECK(pad->line > 1191);  // in the Linux section
}
