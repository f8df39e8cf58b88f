#include "hil/io/recording_modbus_link.hpp"

#include "hil/io/posix_io.hpp"
#include "msgs/clock.hpp"

namespace rise::hil::io {

RecordingModbusLink::RecordingModbusLink(std::unique_ptr<ModbusLink> link, const std::string& path,
                                         std::string source, int unit)
    : link_(std::move(link)), file_(path, "Modbus trace"), source_(std::move(source)), unit_(unit) {
  // The largest request of the map is 25 registers; 125 (the protocol's
  // limit) fit too without growing.
  line_.reserve(64 + source_.size() + 5 * 125);
  file_.write_line(
      "# rise-hild modbus trace v1: (request time) source unit= fc= addr= count= rtt_us= result [closed] [values]; "
      "see hil/io/modbus_trace.hpp");
  line_.clear();
  append_modbus_event(line_, msgs::wall_us(), source_, ModbusTraceRecord::Kind::Link, link_->is_open());
  file_.write_line(line_);
}

RecordingModbusLink::~RecordingModbusLink() = default;

template <typename T>
ModbusResult RecordingModbusLink::transact(ModbusFunction function, uint16_t address, std::span<T> values,
                                           ModbusResult result, int64_t time_us, Clock::time_point start) {
  const int64_t rtt_us = std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - start).count();
  line_.clear();
  append_modbus_transaction(line_, time_us, source_, unit_, function, address, static_cast<uint16_t>(values.size()),
                            rtt_us, result, !link_->is_open(), std::span<const std::remove_const_t<T>>(values));
  file_.write_line(line_);
  return count(result);
}

ModbusResult RecordingModbusLink::read_coils(uint16_t address, std::span<uint8_t> bits) {
  const int64_t time_us = msgs::wall_us();
  const auto start = Clock::now();
  return transact(ModbusFunction::ReadCoils, address, bits, link_->read_coils(address, bits), time_us, start);
}

ModbusResult RecordingModbusLink::read_holding_registers(uint16_t address, std::span<uint16_t> registers) {
  const int64_t time_us = msgs::wall_us();
  const auto start = Clock::now();
  return transact(ModbusFunction::ReadHoldingRegisters, address, registers,
                  link_->read_holding_registers(address, registers), time_us, start);
}

ModbusResult RecordingModbusLink::read_discrete_inputs(uint16_t address, std::span<uint8_t> bits) {
  const int64_t time_us = msgs::wall_us();
  const auto start = Clock::now();
  return transact(ModbusFunction::ReadDiscreteInputs, address, bits, link_->read_discrete_inputs(address, bits),
                  time_us, start);
}

ModbusResult RecordingModbusLink::read_input_registers(uint16_t address, std::span<uint16_t> registers) {
  const int64_t time_us = msgs::wall_us();
  const auto start = Clock::now();
  return transact(ModbusFunction::ReadInputRegisters, address, registers,
                  link_->read_input_registers(address, registers), time_us, start);
}

ModbusResult RecordingModbusLink::write_coils(uint16_t address, std::span<const uint8_t> bits) {
  const int64_t time_us = msgs::wall_us();
  const auto start = Clock::now();
  return transact(ModbusFunction::WriteMultipleCoils, address, bits, link_->write_coils(address, bits), time_us,
                  start);
}

ModbusResult RecordingModbusLink::write_registers(uint16_t address, std::span<const uint16_t> registers) {
  const int64_t time_us = msgs::wall_us();
  const auto start = Clock::now();
  return transact(ModbusFunction::WriteMultipleRegisters, address, registers,
                  link_->write_registers(address, registers), time_us, start);
}

ModbusStatus RecordingModbusLink::reopen() {
  const int64_t time_us = msgs::wall_us();
  const ModbusStatus st = link_->reopen();
  if (st == ModbusStatus::Ok) ++counters_.reopens;
  line_.clear();
  append_modbus_event(line_, time_us, source_, ModbusTraceRecord::Kind::Reopen, st == ModbusStatus::Ok);
  file_.write_line(line_);
  return st;
}

void RecordingModbusLink::close() {
  line_.clear();
  append_modbus_event(line_, msgs::wall_us(), source_, ModbusTraceRecord::Kind::Close, false);
  file_.write_line(line_);
  link_->close();
}

}  // namespace rise::hil::io
