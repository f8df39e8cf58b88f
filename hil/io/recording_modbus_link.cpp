#include "hil/io/recording_modbus_link.hpp"

#include <stdexcept>

namespace rise::io {
namespace {
int64_t wall_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}
}  // namespace

RecordingModbusLink::RecordingModbusLink(std::unique_ptr<ModbusLink> link, const std::string& path,
                                         std::string source, int unit)
    : link_(std::move(link)), out_(path, std::ios::trunc), source_(std::move(source)), unit_(unit),
      last_flush_(Clock::now()) {
  if (!out_) throw std::runtime_error(path + ": cannot create the Modbus trace");
  // The largest request of the map is 25 registers; 125 (the protocol's
  // limit) fit too without growing.
  line_.reserve(64 + source_.size() + 5 * 125);
  out_ << "# rise-hild modbus trace v1: (request time) source unit= fc= addr= count= rtt_us= result [closed] "
          "[values]; see hil/io/modbus_trace.hpp\n";
  line_.clear();
  append_modbus_event(line_, wall_us(), source_, ModbusTraceRecord::Kind::Link, link_->is_open());
  write_line();
}

RecordingModbusLink::~RecordingModbusLink() { out_.flush(); }

void RecordingModbusLink::write_line() {
  line_ += '\n';
  out_.write(line_.data(), static_cast<std::streamsize>(line_.size()));
  // Flushed at least every 100 ms: a killed daemon loses at most that much.
  const auto now = Clock::now();
  if (now - last_flush_ >= std::chrono::milliseconds(100)) {
    out_.flush();
    last_flush_ = now;
  }
  if (!out_) {
    ++write_errors_;
    out_.clear();
    return;
  }
  ++recorded_;
}

template <typename T>
ModbusResult RecordingModbusLink::transact(ModbusFunction function, uint16_t address, std::span<T> values,
                                           ModbusResult result, int64_t time_us, Clock::time_point start) {
  const int64_t rtt_us = std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - start).count();
  line_.clear();
  append_modbus_transaction(line_, time_us, source_, unit_, function, address, static_cast<uint16_t>(values.size()),
                            rtt_us, result, !link_->is_open(), std::span<const std::remove_const_t<T>>(values));
  write_line();
  return count(result);
}

ModbusResult RecordingModbusLink::read_discrete_inputs(uint16_t address, std::span<uint8_t> bits) {
  const int64_t time_us = wall_us();
  const auto start = Clock::now();
  return transact(ModbusFunction::ReadDiscreteInputs, address, bits, link_->read_discrete_inputs(address, bits),
                  time_us, start);
}

ModbusResult RecordingModbusLink::read_input_registers(uint16_t address, std::span<uint16_t> registers) {
  const int64_t time_us = wall_us();
  const auto start = Clock::now();
  return transact(ModbusFunction::ReadInputRegisters, address, registers,
                  link_->read_input_registers(address, registers), time_us, start);
}

ModbusResult RecordingModbusLink::write_coils(uint16_t address, std::span<const uint8_t> bits) {
  const int64_t time_us = wall_us();
  const auto start = Clock::now();
  return transact(ModbusFunction::WriteMultipleCoils, address, bits, link_->write_coils(address, bits), time_us,
                  start);
}

ModbusResult RecordingModbusLink::write_registers(uint16_t address, std::span<const uint16_t> registers) {
  const int64_t time_us = wall_us();
  const auto start = Clock::now();
  return transact(ModbusFunction::WriteMultipleRegisters, address, registers,
                  link_->write_registers(address, registers), time_us, start);
}

ModbusStatus RecordingModbusLink::reopen() {
  const int64_t time_us = wall_us();
  const ModbusStatus st = link_->reopen();
  if (st == ModbusStatus::Ok) ++counters_.reopens;
  line_.clear();
  append_modbus_event(line_, time_us, source_, ModbusTraceRecord::Kind::Reopen, st == ModbusStatus::Ok);
  write_line();
  return st;
}

void RecordingModbusLink::close() {
  line_.clear();
  append_modbus_event(line_, wall_us(), source_, ModbusTraceRecord::Kind::Close, false);
  write_line();
  link_->close();
}

}  // namespace rise::io
