#include <catch2/catch.hpp>

#include <fstream>
#include <sstream>
#include <string>

#include "firmware_protocol/console_modbus.hpp"

namespace fp = rise::firmware_protocol;

namespace {
// The README's worked example.
fp::ConsoleInputs worked_example() {
  fp::ConsoleInputs in;
  in.axes = {fp::axis_from_unit(0.5f), fp::axis_from_unit(-0.25f), 0, 0, 0, fp::kAxisInvalid};
  in.switches = {1, 0, fp::kSwitchInvalid, 0, 0, 0};
  in.buttons = (1u << 0) | (1u << 5) | (1u << 17);
  in.status = fp::PanelStatus::Operational;
  in.uptime_ms = 70000;
  in.alive_counter = 3;
  return in;
}
}  // namespace

TEST_CASE("crc16_modbus gives the catalogue check value", "[firmware_protocol]") {
  const std::string text = "123456789";
  CHECK(fp::crc16_modbus({reinterpret_cast<const uint8_t*>(text.data()), text.size()}) == 0x4B37);
}

TEST_CASE("encode_inputs produces the README's worked example registers", "[firmware_protocol]") {
  const fp::ModbusInputBlock block = encode_inputs(worked_example());
  const std::array<uint16_t, fp::modbus_ir::kCount> expected = {
      0x4000, 0xE000, 0x0000, 0x0000, 0x0000, 0x8000, 0x0001, 0x0000, 0x00FF,
      0x0000, 0x0000, 0x0000, 0x0001, 0x0001, 0x0001, 0x1170, 0x0003, 0xB607};
  CHECK(block.registers == expected);
  CHECK(block.discrete_bits == 0x00020021u);

  std::ifstream readme(RISE_SOURCE_DIR "/firmware_protocol/README.md");
  std::stringstream text;
  text << readme.rdbuf();
  CHECK(text.str().find("4000 E000 0000 0000 0000 8000 0001 0000 00FF 0000 0000 0000 0001 0001 0001 1170 "
                        "0003 B607") != std::string::npos);
  CHECK(text.str().find("CRC-16/MODBUS → **0xB607**") != std::string::npos);
}

TEST_CASE("decode_inputs round-trips what encode_inputs wrote", "[firmware_protocol]") {
  fp::ConsoleInputs in = worked_example();
  const auto axis = GENERATE(as<int16_t>{}, -32768, -32767, -1, 0, 1, 12345, 32767);
  const auto sw = GENERATE(as<uint8_t>{}, 0, 7, 254, 255);
  const auto status = GENERATE(fp::PanelStatus::Init, fp::PanelStatus::Operational, fp::PanelStatus::Fault,
                               fp::PanelStatus::Shutdown);
  const auto uptime = GENERATE(0u, 65535u, 65536u, 0xFFFFFFFFu);
  in.axes[2] = axis;
  in.switches[4] = sw;
  in.status = status;
  in.uptime_ms = uptime;
  in.buttons = 0x80000001u;
  const fp::ModbusInputBlock block = encode_inputs(in);
  const fp::ModbusInputsResult r = fp::decode_inputs(block.registers, block.discrete_bits);
  REQUIRE(r.ok());
  CHECK(r.inputs == in);
}

TEST_CASE("decode_inputs classifies every error kind", "[firmware_protocol]") {
  fp::ModbusInputBlock block = encode_inputs(worked_example());
  SECTION("good block with a moving counter") {
    CHECK(fp::decode_inputs(block.registers, block.discrete_bits, uint16_t{2}).ok());
  }
  SECTION("a flipped bit fails the CRC") {
    block.registers[fp::modbus_ir::kAxis0] ^= 0x0100;
    CHECK(fp::decode_inputs(block.registers, block.discrete_bits).error == fp::ModbusDecodeError::BadCrc);
  }
  SECTION("a half-updated block (new axes, old CRC) fails the CRC") {
    block.registers[fp::modbus_ir::kAlive] = 4;
    CHECK(fp::decode_inputs(block.registers, block.discrete_bits).error == fp::ModbusDecodeError::BadCrc);
  }
  SECTION("out-of-range values with a valid CRC are BadValue") {
    const auto reg = GENERATE(fp::modbus_ir::kStatus, fp::modbus_ir::kSwitch0, fp::modbus_ir::kVersion);
    block.registers[reg] = reg == fp::modbus_ir::kStatus ? 4 : 256;
    block.registers[fp::modbus_ir::kCrc] = fp::input_block_crc(block.registers);
    CHECK(fp::decode_inputs(block.registers, block.discrete_bits).error == fp::ModbusDecodeError::BadValue);
  }
  SECTION("a counter that did not move is StaleCounter but still decoded") {
    const auto r = fp::decode_inputs(block.registers, block.discrete_bits, uint16_t{3});
    CHECK(r.error == fp::ModbusDecodeError::StaleCounter);
    CHECK(r.inputs.alive_counter == 3);
  }
  CHECK(std::string(fp::to_string(fp::ModbusDecodeError::StaleCounter)) == "StaleCounter");
}

TEST_CASE("feedback round-trips through coils and holding registers", "[firmware_protocol]") {
  const auto raw = GENERATE(0, 1, -1, 123456, INT32_MIN, INT32_MAX);
  const auto buzzer = GENERATE(fp::BuzzerMode::Off, fp::BuzzerMode::On, fp::BuzzerMode::Beep);
  const fp::IndicatorsFrame ind{0xA5000001u, buzzer};
  const std::array<fp::DisplayFrame, 3> displays = {fp::DisplayFrame{0, 2, raw}, fp::DisplayFrame{7, 9, -raw / 2},
                                                    fp::DisplayFrame{8, 1, 5}};
  const fp::ModbusFeedbackBlock block = fp::encode_feedback(ind, displays);
  CHECK(block.coil_bits == 0xA5000001u);
  CHECK(block.holding[0] == static_cast<uint16_t>(buzzer));
  CHECK(block.holding[2] == static_cast<uint16_t>(static_cast<uint32_t>(raw) >> 16));  // high word first
  const fp::ModbusFeedbackResult r = fp::decode_feedback(block);
  REQUIRE(r.ok());
  CHECK(r.indicators.leds_on == ind.leds_on);
  CHECK(r.indicators.buzzer == buzzer);
  CHECK(r.displays[0].raw == raw);
  CHECK(r.displays[0].decimals == 2);
  CHECK(r.displays[7].raw == -raw / 2);
  CHECK(r.displays[7].index == 7);
  CHECK(r.displays[3].raw == 0);  // index 8 is outside the map and was skipped
}

TEST_CASE("decode_feedback rejects an unknown buzzer mode or too many decimals", "[firmware_protocol]") {
  fp::ModbusFeedbackBlock block;
  SECTION("buzzer 3") { block.holding[fp::modbus_hr::kBuzzer] = 3; }
  SECTION("decimals 10 on display 5") { block.holding[fp::modbus_hr::kDisplay0 + 3 * 5] = 10; }
  CHECK(fp::decode_feedback(block).error == fp::ModbusDecodeError::BadValue);
}
