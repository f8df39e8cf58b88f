#include "hil/io/replay_modbus_link.hpp"

#include "hil/io/modbus_capture.hpp"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <thread>
#include <variant>

#include "msgs/clock.hpp"

namespace rise::hil::io {
namespace {

// Time between two passes of a window that holds at most one request.
constexpr int64_t kSingleRequestLoopGapUs = 100'000;

int64_t seconds_to_us(double s) { return static_cast<int64_t>(std::llround(s * 1e6)); }

// The records of a trace file, or of a pcap/pcapng's Modbus/TCP transactions.
std::vector<ModbusTraceRecord> load_records(const std::string& path) {
  if (looks_like_modbus_capture(path)) return modbus_trace_from_capture(read_modbus_capture(path), "capture");
  std::vector<ModbusTraceRecord> records;
  ModbusTraceReader reader(path);
  ModbusTraceRecord r;
  while (reader.next(r)) records.push_back(std::move(r));
  return records;
}

}  // namespace

bool is_replay_url(std::string_view url) { return url.rfind("replay://", 0) == 0; }

ReplayModbusLink::ReplayModbusLink(std::string url, ReplayAddress address)
    : url_(std::move(url)), address_(std::move(address)) {
  const std::string& path = address_.path;
  std::string source;
  int64_t first_us = std::numeric_limits<int64_t>::max(), last_us = std::numeric_limits<int64_t>::min();
  std::vector<int64_t> request_times;
  for (const ModbusTraceRecord& r : load_records(path)) {
    if (source.empty()) source = r.source;
    if (r.source != source)
      throw std::runtime_error(path + ":" + std::to_string(r.line) + ": the traffic of another source ('" + r.source +
                               "' after '" + source + "'): a replay is of one source");
    first_us = std::min(first_us, r.time_us);
    last_us = std::max(last_us, r.kind == ModbusTraceRecord::Kind::Transaction ? r.answer_us() : r.time_us);
    using Kind = ModbusTraceRecord::Kind;
    if (r.kind == Kind::Link || r.kind == Kind::Reopen) {
      link_events_.push_back({r.time_us, r.open});
      continue;
    }
    if (r.kind == Kind::Close) {
      link_events_.push_back({r.time_us, false});
      continue;
    }
    request_times.push_back(r.time_us);
    // A slave that went away (not the clean restart after a TCP timeout).
    if (r.closed && r.result.status != ModbusStatus::Timeout) link_events_.push_back({r.answer_us(), false});
    const bool write = r.function == ModbusFunction::WriteMultipleCoils ||
                       r.function == ModbusFunction::WriteMultipleRegisters;
    if (write) continue;  // writes are dropped, their answers not needed
    auto it = std::find_if(requests_.begin(), requests_.end(), [&](const Request& q) {
      return q.function == r.function && q.address == r.address && q.count == r.count;
    });
    if (it == requests_.end()) it = requests_.insert(requests_.end(), Request{r.function, r.address, r.count, {}});
    Answer a{r.time_us, r.rtt_us, r.result, r.closed, values_.size()};
    if (r.result.ok()) values_.insert(values_.end(), r.values.begin(), r.values.end());
    it->answers.push_back(a);
  }
  if (request_times.empty()) throw std::runtime_error(path + ": no Modbus transaction to replay");
  for (auto& q : requests_)
    std::stable_sort(q.answers.begin(), q.answers.end(),
                     [](const Answer& a, const Answer& b) { return a.time_us < b.time_us; });
  std::stable_sort(link_events_.begin(), link_events_.end(),
                   [](const LinkEvent& a, const LinkEvent& b) { return a.time_us < b.time_us; });
  window_begin_us_ = first_us + seconds_to_us(address_.start_s);
  window_end_us_ = address_.stop_s < 0.0 ? last_us : std::min(last_us, first_us + seconds_to_us(address_.stop_s));
  if (window_end_us_ < window_begin_us_)
    throw std::runtime_error(path + ": start=" + std::to_string(address_.start_s) + " s is past the trace's end");
  const auto in_window = std::count_if(request_times.begin(), request_times.end(), [&](int64_t t) {
    return t >= window_begin_us_ && t <= window_end_us_;
  });
  const int64_t span = window_end_us_ - window_begin_us_;
  const int64_t gap = in_window > 1 ? span / (in_window - 1) : kSingleRequestLoopGapUs;
  period_us_ = span + std::max<int64_t>(gap, 1);
  open_ = link_up(window_begin_us_);
  last_request_us_ = window_begin_us_;
}

bool ReplayModbusLink::link_up(int64_t trace_us) const {
  const auto it = std::upper_bound(link_events_.begin(), link_events_.end(), trace_us,
                                   [](int64_t t, const LinkEvent& e) { return t < e.time_us; });
  return it == link_events_.begin() || std::prev(it)->up;
}

int64_t ReplayModbusLink::in_pass(int64_t elapsed) const {
  if (past_end(elapsed)) return window_end_us_;
  const int64_t offset = elapsed % period_us_;
  return window_begin_us_ + std::min(offset, window_end_us_ - window_begin_us_);
}

bool ReplayModbusLink::past_end(int64_t elapsed) const { return address_.loop >= 0 && elapsed >= beyond_end(); }

int64_t ReplayModbusLink::beyond_end() const {
  return std::max(address_.loop, 0) * period_us_ + (window_end_us_ - window_begin_us_) + 1;
}

bool ReplayModbusLink::reach(int64_t elapsed, int64_t& trace_us) {
  trace_us = in_pass(elapsed);
  last_request_us_ = trace_us;
  if (past_end(elapsed)) ended_ = true;
  const bool up = !ended_ && link_up(trace_us);
  if (!up) open_ = false;
  return up;
}

int64_t ReplayModbusLink::elapsed_now() {
  if (!anchored_) {
    anchored_ = true;
    t0_steady_us_ = msgs::monotonic_us();
  }
  if (address_.fast) return fast_elapsed_us_;
  return static_cast<int64_t>(
      std::llround(static_cast<double>(msgs::monotonic_us() - t0_steady_us_.load()) * address_.speed));
}

std::optional<int64_t> ReplayModbusLink::trace_time_us(int64_t steady_us) const {
  if (t0_steady_us_.load() == 0) return std::nullopt;
  if (address_.fast) return last_request_us_.load();
  const auto elapsed =
      static_cast<int64_t>(std::llround(static_cast<double>(steady_us - t0_steady_us_.load()) * address_.speed));
  return in_pass(std::max<int64_t>(elapsed, 0));
}

const ReplayModbusLink::Request* ReplayModbusLink::find(ModbusFunction function, uint16_t address,
                                                        std::size_t count) const {
  for (const Request& q : requests_)
    if (q.function == function && q.address == address && q.count == count) return &q;
  return nullptr;
}

const ReplayModbusLink::Answer& ReplayModbusLink::latest(const Request& request, int64_t trace_us) const {
  const auto it = std::upper_bound(request.answers.begin(), request.answers.end(), trace_us,
                                   [](int64_t t, const Answer& a) { return t < a.time_us; });
  return it == request.answers.begin() ? *it : *std::prev(it);
}

template <typename Times>
std::optional<int64_t> ReplayModbusLink::fast_next(const Times& time_of, std::size_t size) {
  const int64_t pass = fast_elapsed_us_ / period_us_;
  const int64_t now = in_pass(fast_elapsed_us_);
  for (std::size_t i = 0; i < size; ++i) {
    const int64_t t = time_of(i);
    if ((fast_started_ ? t > now : t >= now) && t <= window_end_us_) return pass * period_us_ + (t - window_begin_us_);
  }
  // None left in this pass: the next one, from its start.
  if (address_.loop >= 0 && pass >= address_.loop) return std::nullopt;
  for (std::size_t i = 0; i < size; ++i) {
    const int64_t t = time_of(i);
    if (t >= window_begin_us_ && t <= window_end_us_) return (pass + 1) * period_us_ + (t - window_begin_us_);
  }
  return (pass + 1) * period_us_;
}

template <typename T>
ModbusResult ReplayModbusLink::read(ModbusFunction function, uint16_t address, std::span<T> out) {
  int64_t elapsed = elapsed_now();
  if (ended_ || !open_) return count({ModbusStatus::Disconnected, 0});
  const Request* request = find(function, address, out.size());
  if (address_.fast && request) {
    const auto next = fast_next([&](std::size_t i) { return request->answers[i].time_us; }, request->answers.size());
    fast_elapsed_us_ = elapsed = next.value_or(beyond_end());
    fast_started_ = true;
  }
  int64_t t = 0;
  if (!reach(elapsed, t)) return count({ModbusStatus::Disconnected, 0});
  if (!request) {
    ++unknown_requests_;
    return count({ModbusStatus::Exception, 2});
  }
  const Answer& a = latest(*request, t);
  // fast=1: the replay is at the answer now (after a lost slave's, the link is down).
  if (address_.fast) fast_elapsed_us_ = elapsed + std::clamp<int64_t>(a.time_us + a.rtt_us - t, 0, window_end_us_ - t);
  if (a.result.status == ModbusStatus::Timeout && !address_.fast)
    std::this_thread::sleep_for(std::chrono::microseconds(
        static_cast<int64_t>(std::llround(static_cast<double>(a.rtt_us) / address_.speed))));
  if (a.result.ok())
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = static_cast<T>(values_[a.first_value + i]);
  if (a.closed) open_ = false;
  return count(a.result);
}

ModbusResult ReplayModbusLink::write() {
  const int64_t elapsed = elapsed_now();
  int64_t t = 0;
  if (ended_ || !open_ || !reach(elapsed, t)) return count({ModbusStatus::Disconnected, 0});
  ++writes_dropped_;
  return count({});
}

ModbusResult ReplayModbusLink::read_coils(uint16_t address, std::span<uint8_t> bits) {
  return read(ModbusFunction::ReadCoils, address, bits);
}
ModbusResult ReplayModbusLink::read_discrete_inputs(uint16_t address, std::span<uint8_t> bits) {
  return read(ModbusFunction::ReadDiscreteInputs, address, bits);
}
ModbusResult ReplayModbusLink::read_holding_registers(uint16_t address, std::span<uint16_t> registers) {
  return read(ModbusFunction::ReadHoldingRegisters, address, registers);
}
ModbusResult ReplayModbusLink::read_input_registers(uint16_t address, std::span<uint16_t> registers) {
  return read(ModbusFunction::ReadInputRegisters, address, registers);
}
ModbusResult ReplayModbusLink::write_coils(uint16_t, std::span<const uint8_t>) { return write(); }
ModbusResult ReplayModbusLink::write_registers(uint16_t, std::span<const uint16_t>) { return write(); }

ModbusStatus ReplayModbusLink::reopen() {
  int64_t elapsed = elapsed_now();
  if (ended_) return ModbusStatus::Disconnected;
  if (address_.fast && !link_up(in_pass(elapsed))) {
    // Jump to when the recorded link came up again (a down event is past
    // the window for fast_next: never taken).
    const auto next = fast_next(
        [&](std::size_t i) { return link_events_[i].up ? link_events_[i].time_us : window_end_us_ + 1; },
        link_events_.size());
    fast_elapsed_us_ = elapsed = next.value_or(beyond_end());
  }
  int64_t t = 0;
  if (!reach(elapsed, t)) return ModbusStatus::Disconnected;
  open_ = true;
  ++counters_.reopens;
  return ModbusStatus::Ok;
}

std::unique_ptr<ReplayModbusLink> open_modbus_replay(std::string_view url) {
  CanAddress parsed = parse_can_url(url);
  auto* address = std::get_if<ReplayAddress>(&parsed);
  if (address == nullptr) throw std::invalid_argument("modbus replay: '" + std::string(url) + "' is not a replay:// URL");
  if (!address->ids.empty() || !address->channel.empty() || address->step)
    throw std::invalid_argument("modbus replay '" + std::string(url) +
                                "': ids=, channel= and step= are for CAN logs, not a Modbus trace");
  if (!std::filesystem::exists(address->path))
    throw std::runtime_error(address->path + ": cannot open: " + std::strerror(ENOENT));
  if (!looks_like_modbus_trace(address->path) && !looks_like_modbus_capture(address->path))
    throw std::runtime_error(address->path + ": not a Modbus trace or capture (a CAN log replays on a CAN source)");
  return std::make_unique<ReplayModbusLink>(std::string(url), std::move(*address));
}

}  // namespace rise::hil::io
