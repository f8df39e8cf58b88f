#include "hil/replay_verify.hpp"

#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <stdexcept>

#include "hil/io/can_log.hpp"
#include "hil/io/hid_recording.hpp"
#include "hil/io/modbus_trace.hpp"
#include "hil/j1939_input.hpp"
#include "hil/panel_state_message.hpp"
#include "hil/source_input.hpp"
#include "msgs/failsafe.hpp"
#include "msgs/lcm_decode.hpp"

namespace rise::hil {

// One capture being read: the time of its next record (nullopt at the end)
// and how that record acts on the mapper.
struct CaptureReplay::Feed {
  explicit Feed(std::size_t s) : source(s) {}
  virtual ~Feed() = default;
  /// Applies the pending record, then reads the next one.
  virtual void apply(PanelMapper& mapper) = 0;
  virtual bool records_link() const = 0;
  std::size_t source;
  std::optional<int64_t> time_us;
};

namespace {

bool ends_with(std::string_view text, std::string_view tail) {
  return text.size() >= tail.size() && text.substr(text.size() - tail.size()) == tail;
}

// A CAN log: every frame the recorder received, at its timestamp. A j1939
// source's go through J1939Input as live (our claim starts at the first
// frame; what we would answer is in the log as sent, so it is not sent).
class CanFeed final : public CaptureReplay::Feed {
 public:
  CanFeed(const std::string& path, const panels::SourceDefinition& definition, std::size_t source)
      : Feed(source), reader_(path) {
    if (definition.is_j1939()) j1939_.emplace(definition);
    fetch();
  }
  void apply(PanelMapper& mapper) override {
    if (j1939_) {
      J1939Replies unsent;
      if (!j1939_started_) j1939_->start(*time_us / 1000, unsent);
      j1939_started_ = true;
      j1939_->tick(*time_us / 1000, unsent);
      j1939_->on_frame(mapper, source, record_.frame, *time_us, unsent);
    } else {
      apply_can_frame(mapper, source, record_.frame, *time_us);
    }
    fetch();
  }
  bool records_link() const override { return false; }

 private:
  void fetch() {
    time_us.reset();
    while (reader_.next(record_)) {
      check();
      if (record_.tx) continue;  // the daemon's own feedback frames
      time_us = record_.frame.timestamp_us;
      return;
    }
    check();
  }
  // The reader skips what it cannot read; a verification must not.
  void check() {
    if (reader_.malformed_count() == 0) return;
    const auto& lines = reader_.malformed_lines();
    throw std::runtime_error(reader_.path() + ":" + std::to_string(lines.empty() ? 0 : lines.front()) +
                             ": not a " + io::to_string(reader_.format()) + " frame line");
  }

  io::CanLogReader reader_;
  io::CanLogRecord record_;
  std::optional<J1939Input> j1939_;
  bool j1939_started_ = false;
};

// A Modbus trace, replayed as the bridge's poll cycle (modbus_source_loop)
// went: the reads of one poll (modbus_poll_reads: rise-modbus-v1's input
// registers then discrete inputs, a modbus device's tables) are applied
// when the last one's answer came; a failed request is counted when its
// answer (or timeout) came; reopens connect or disconnect the source.
class ModbusFeed final : public CaptureReplay::Feed {
 public:
  ModbusFeed(const std::string& path, std::size_t source, std::vector<ModbusRead> reads)
      : Feed(source), reader_(path), poll_(std::move(reads)) {
    fetch();
  }
  void apply(PanelMapper& mapper) override {
    const int64_t now = *time_us;
    switch (action_) {
      case Action::Poll:
        if (apply_modbus_result(mapper, source, record_.result, !record_.closed, now)) {
          mapper.on_connection(source, true, now);
          if (record_.result.ok()) apply_modbus_poll(mapper, source, poll_, last_counter_, now);
        }
        break;
      case Action::Write: apply_modbus_result(mapper, source, record_.result, !record_.closed, now); break;
      case Action::Reopen: mapper.on_connection(source, record_.open, now); break;
    }
    if (record_.closed) last_counter_.reset();
    fetch();
  }
  bool records_link() const override { return true; }

 private:
  enum class Action { Poll, Write, Reopen };
  using Fn = io::ModbusFunction;

  void fetch() {
    time_us.reset();
    std::size_t answered = 0;  // reads of the poll answered so far
    while (reader_.next(record_)) {
      using Kind = io::ModbusTraceRecord::Kind;
      switch (record_.kind) {
        case Kind::Link:
        case Kind::Close:
          if (!(record_.kind == Kind::Link && record_.open)) last_counter_.reset();
          continue;
        case Kind::Reopen:
          // The bridge forgets the alive counter whenever it finds the link closed.
          last_counter_.reset();
          action_ = Action::Reopen;
          time_us = record_.time_us;
          return;
        case Kind::Transaction: break;
      }
      const bool write = record_.function == Fn::WriteMultipleCoils || record_.function == Fn::WriteMultipleRegisters;
      if (write) {
        if (record_.result.ok()) continue;  // nothing for the mapper
        action_ = Action::Write;
      } else {
        const auto i = poll_.find(record_.function, record_.address, record_.count);
        if (!i) throw bad_line("is not a read of this source's poll (" + describe_reads() + ")");
        if (*i == 0) answered = 0;  // a poll begins
        if (record_.result.ok()) {
          if (*i != answered) throw bad_line("without the reads before it in the poll (" + describe_reads() + ")");
          poll_.store(*i, record_.values);
          if (++answered < poll_.reads().size()) continue;  // the next read completes the poll
        }
        action_ = Action::Poll;  // complete, or a failed read
      }
      time_us = record_.answer_us();
      return;
    }
  }

  // "fc=04 addr=0 count=18", as the trace writes a request.
  static std::string request_text(Fn function, uint16_t address, uint16_t count) {
    const auto fc = static_cast<int>(function);
    return std::string("fc=") + (fc < 10 ? "0" : "") + std::to_string(fc) + " addr=" + std::to_string(address) +
           " count=" + std::to_string(count);
  }
  std::runtime_error bad_line(const std::string& what) const {
    return std::runtime_error(reader_.path() + ":" + std::to_string(record_.line) + ": " +
                              request_text(record_.function, record_.address, record_.count) + " " + what);
  }
  std::string describe_reads() const {
    std::string text;
    for (const ModbusRead& r : poll_.reads())
      text += (text.empty() ? "" : ", ") + request_text(r.function, r.address, r.count);
    return text;
  }

  io::ModbusTraceReader reader_;
  io::ModbusTraceRecord record_;
  Action action_ = Action::Poll;
  ModbusPoll poll_;
  std::optional<uint16_t> last_counter_;
};

// A HID recording, replayed as the bridge's HID loop went: each plug
// attaches its descriptor and connects the source, each report is decoded,
// each unplug disconnects it. The recording's end (the daemon stopped) is
// after every message.
class HidFeed final : public CaptureReplay::Feed {
 public:
  HidFeed(const std::string& path, std::size_t source) : Feed(source), reader_(path) { fetch(); }
  void apply(PanelMapper& mapper) override {
    using Kind = io::HidRecordingRecord::Kind;
    switch (record_.kind) {
      case Kind::Plug:
        mapper.attach_hid(source, record_.bytes);
        mapper.on_connection(source, true, *time_us);
        break;
      case Kind::Report: mapper.on_hid_report(source, record_.bytes, *time_us); break;
      case Kind::Unplug: mapper.on_connection(source, false, *time_us); break;
      case Kind::End: break;
    }
    fetch();
  }
  bool records_link() const override { return true; }

 private:
  void fetch() {
    time_us.reset();
    if (reader_.next(record_)) time_us = record_.time_us;
  }
  io::HidRecordingReader reader_;
  io::HidRecordingRecord record_;
};

std::vector<std::string> control_names(const rise_msgs::PanelState& m) {
  std::vector<std::string> names;
  for (const auto& a : m.axes) names.push_back(a.name);
  for (const auto& b : m.buttons) names.push_back(b.name);
  for (const auto& s : m.switches) names.push_back(s.name);
  return names;
}

std::string axis_text(float v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4f", static_cast<double>(v));
  return text;
}

// Reasons are equal when their text is, but a number of milliseconds in them
// ("stale (no valid Buttons frame for 53 ms)") may differ by the time
// tolerance: it is an age, measured a few microseconds apart.
bool same_reason(std::string_view a, std::string_view b, int64_t tolerance_ms) {
  std::size_t i = 0, j = 0;
  auto digit = [](char c) { return c >= '0' && c <= '9'; };
  while (i < a.size() && j < b.size()) {
    if (digit(a[i]) && digit(b[j])) {
      int64_t x = 0, y = 0;
      while (i < a.size() && digit(a[i])) x = x * 10 + (a[i++] - '0');
      while (j < b.size() && digit(b[j])) y = y * 10 + (b[j++] - '0');
      const bool ms = a.substr(i).starts_with(" ms") && b.substr(j).starts_with(" ms");
      if (x != y && !(ms && std::llabs(x - y) <= tolerance_ms)) return false;
      continue;
    }
    if (a[i++] != b[j++]) return false;
  }
  return i == a.size() && j == b.size();
}

}  // namespace

Capture capture_for(const panels::PanelDefinition& definition, const std::string& path) {
  std::string name = path;
  std::string file = path;
  if (const auto eq = path.find('='); eq != std::string::npos && !std::filesystem::exists(path)) {
    name = path.substr(0, eq);
    file = path.substr(eq + 1);
  } else {
    name = std::filesystem::path(path).filename().string();
    name = name.substr(0, name.find('.'));
  }
  Capture c;
  c.path = file;
  if (const auto s = definition.find_source(name)) {
    c.source = *s;
  } else if (definition.sources.size() == 1) {
    c.source = 0;
  } else {
    std::string known;
    for (const auto& s : definition.sources) known += (known.empty() ? "" : ", ") + s.name;
    throw std::invalid_argument(path + ": no source of " + definition.file + " is named '" + name +
                                "' (sources: " + known + "; name the file SOURCE.log or SOURCE.modbus.log, "
                                "or pass SOURCE=FILE)");
  }
  const auto& source = definition.sources[c.source];
  if (!std::filesystem::exists(file)) throw std::invalid_argument(file + ": cannot open: " + std::strerror(ENOENT));
  if (io::looks_like_hid_recording(file) != source.is_hid())
    throw std::invalid_argument(file + ": source '" + source.name + "' speaks " + source.protocol + " but the file is " +
                                (source.is_hid() ? "not a hid-recorder file" : "a hid-recorder file"));
  if (source.is_hid()) return c;
  const bool modbus = io::looks_like_modbus_trace(file);
  if (modbus != source.is_modbus())
    throw std::invalid_argument(file + ": source '" + source.name + "' speaks " + source.protocol + " but the file is " +
                                (modbus ? "a Modbus trace" : "not a Modbus trace"));
  return c;
}

std::vector<Capture> captures_in(const panels::PanelDefinition& definition, const std::string& dir) {
  std::error_code ec;
  std::filesystem::directory_iterator readable(dir, ec);
  if (ec) throw std::invalid_argument(dir + ": cannot open: " + ec.message());
  std::vector<Capture> captures;
  for (std::size_t i = 0; i < definition.sources.size(); ++i) {
    const auto& s = definition.sources[i];
    const std::string path = dir + "/" + s.name + (s.is_modbus() ? ".modbus.log" : s.is_hid() ? ".hid" : ".log");
    if (!std::filesystem::exists(path))
      throw std::invalid_argument(path + ": no capture of source '" + s.name + "' in " + dir);
    captures.push_back(capture_for(definition, path));
  }
  return captures;
}

CaptureReplay::CaptureReplay(const panels::PanelDefinition& definition, std::vector<Capture> captures)
    : mapper_(definition), connected_(definition.sources.size(), false), started_(definition.sources.size(), false) {
  for (const Capture& c : captures) {
    if (c.source >= definition.sources.size())
      throw std::invalid_argument(c.path + ": source index " + std::to_string(c.source) + " is not in the panel");
    const auto& s = definition.sources[c.source];
    if (s.is_hid())
      feeds_.push_back(std::make_unique<HidFeed>(c.path, c.source));
    else if (s.is_modbus())
      feeds_.push_back(std::make_unique<ModbusFeed>(c.path, c.source, modbus_poll_reads(definition, c.source)));
    else
      feeds_.push_back(std::make_unique<CanFeed>(c.path, s, c.source));
  }
  bool any = false;
  for (const auto& f : feeds_) {
    if (!f->time_us) continue;
    start_us_ = any ? std::min(start_us_, *f->time_us) : *f->time_us;
    any = true;
  }
}

CaptureReplay::~CaptureReplay() = default;

CaptureReplay::Feed* CaptureReplay::next_feed() const {
  Feed* best = nullptr;
  for (const auto& f : feeds_)
    if (f->time_us && (!best || *f->time_us < *best->time_us)) best = f.get();
  return best;
}

std::optional<int64_t> CaptureReplay::next_time_us() const {
  const Feed* f = next_feed();
  return f ? f->time_us : std::nullopt;
}

void CaptureReplay::apply_next() {
  Feed* f = next_feed();
  if (!f) return;
  // A CAN log starts when its bus was open.
  if (!started_[f->source] && !f->records_link() && !connected_[f->source])
    set_connected(f->source, true, *f->time_us);
  started_[f->source] = true;
  f->apply(mapper_);
  ++applied_;
}

void CaptureReplay::advance_to(int64_t t_us) {
  for (auto next = next_time_us(); next && *next <= t_us; next = next_time_us()) apply_next();
}

void CaptureReplay::set_connected(std::size_t source, bool connected, int64_t now_us) {
  if (source >= connected_.size()) return;
  connected_[source] = connected;
  mapper_.on_connection(source, connected, now_us);
}

bool CaptureReplay::connected(std::size_t source) const {
  return source < connected_.size() && connected_[source];
}

bool CaptureReplay::records_link(std::size_t source) const {
  for (const auto& f : feeds_)
    if (f->source == source) return f->records_link();
  return false;
}

std::optional<VerifyDifference> compare_panel_states(const rise_msgs::PanelState& expected,
                                                     const rise_msgs::PanelState& got, const VerifySettings& settings) {
  VerifyDifference d;
  auto differ = [&](const std::string& field, std::string e, std::string g) {
    if (d.field.empty()) {
      d.field = field;
      d.expected = std::move(e);
      d.got = std::move(g);
    } else if (field != d.field && std::find(d.also.begin(), d.also.end(), field) == d.also.end()) {
      d.also.push_back(field);  // the dead-man flag and the dead-man button share a name
    }
  };
  auto yes_no = [](bool b) { return std::string(b ? "true" : "false"); };
  if (expected.failsafe != got.failsafe)
    differ("failsafe", yes_no(expected.failsafe) + " (\"" + expected.failsafe_reason + "\")",
           yes_no(got.failsafe) + " (\"" + got.failsafe_reason + "\")");
  else if (expected.failsafe_causes != got.failsafe_causes)
    differ("failsafe_causes", "\"" + msgs::to_string(msgs::FailsafeCauses{expected.failsafe_causes}) + "\"",
           "\"" + msgs::to_string(msgs::FailsafeCauses{got.failsafe_causes}) + "\"");
  else if (!same_reason(expected.failsafe_reason, got.failsafe_reason, settings.time_tolerance_us / 1000 + 1))
    differ("failsafe_reason", "\"" + expected.failsafe_reason + "\"", "\"" + got.failsafe_reason + "\"");
  if (expected.deadman != got.deadman) differ("deadman", yes_no(expected.deadman), yes_no(got.deadman));
  if (control_names(expected) != control_names(got)) {
    differ("controls", std::to_string(expected.axes.size()) + " axes, " + std::to_string(expected.buttons.size()) +
                           " buttons, " + std::to_string(expected.switches.size()) + " switches",
           "other controls");
    return d;
  }
  for (std::size_t i = 0; i < expected.axes.size(); ++i)
    if (!(std::fabs(expected.axes[i].value - got.axes[i].value) <= settings.axis_tolerance))
      differ(expected.axes[i].name, axis_text(expected.axes[i].value), axis_text(got.axes[i].value));
  for (std::size_t i = 0; i < expected.buttons.size(); ++i)
    if (expected.buttons[i].pressed != got.buttons[i].pressed)
      differ(expected.buttons[i].name, expected.buttons[i].pressed ? "pressed" : "released",
             got.buttons[i].pressed ? "pressed" : "released");
  for (std::size_t i = 0; i < expected.switches.size(); ++i) {
    const auto& e = expected.switches[i];
    const auto& g = got.switches[i];
    if (e.position != g.position || e.label != g.label)
      differ(e.name, std::to_string(e.position) + " (" + e.label + ")", std::to_string(g.position) + " (" + g.label + ")");
  }
  // A corrupt frame that heals within recovery_frames between two publishes
  // leaves its trace only in the error counters; they move only on errors,
  // so comparing them adds no timing race (frames_ok, reconnects and ages
  // would: they are not compared).
  if (expected.sources.size() == got.sources.size()) {
    for (std::size_t i = 0; i < expected.sources.size(); ++i) {
      const auto& e = expected.sources[i];
      const auto& g = got.sources[i];
      auto counter = [&](const char* name, int64_t a, int64_t b) {
        if (a != b) differ(e.name + "." + name, std::to_string(a), std::to_string(b));
      };
      counter("crc_errors", e.crc_errors, g.crc_errors);
      counter("counter_errors", e.counter_errors, g.counter_errors);
      counter("length_errors", e.length_errors, g.length_errors);
      counter("unknown_ids", e.unknown_ids, g.unknown_ids);
      counter("timeouts", e.timeouts, g.timeouts);
      counter("exceptions", e.exceptions, g.exceptions);
      counter("error_frames", e.error_frames, g.error_frames);
      counter("bus_offs", e.bus_offs, g.bus_offs);
      if (e.bus_state != g.bus_state) differ(e.name + ".bus_state", e.bus_state, g.bus_state);
    }
  } else {
    differ("sources", std::to_string(expected.sources.size()), std::to_string(got.sources.size()));
  }
  if (d.field.empty()) return std::nullopt;
  return d;
}

std::string describe(const VerifyDifference& d) {
  char head[128];
  std::snprintf(head, sizeof head, "t=%.6f s (message %zu, seq %lld): ", d.time_s, d.message,
                static_cast<long long>(d.seq));
  std::string out = head + d.field + ": expected " + d.expected + ", got " + d.got;
  if (!d.also.empty()) {
    out += "; also differ:";
    for (const auto& f : d.also) out += " " + f;
  }
  return out;
}

VerifyReport verify_replay(const panels::PanelDefinition& definition, std::vector<Capture> captures,
                           std::span<const rise_msgs::PanelState> golden, const VerifySettings& settings) {
  CaptureReplay replay(definition, std::move(captures));
  VerifyReport report;
  report.start_us = replay.start_us();
  const panels::PanelDefinition& def = replay.definition();
  if (!golden.empty() && golden.front().panel_id != def.name)
    throw std::invalid_argument("the golden log is of panel '" + golden.front().panel_id + "', " + def.file +
                                " defines '" + def.name + "'");
  const int64_t tol = settings.time_tolerance_us;
  for (std::size_t k = 0; k < golden.size(); ++k) {
    const rise_msgs::PanelState& g = golden[k];
    const int64_t u = g.utime;
    const int64_t lo = u - tol, hi = u + tol;
    // A source whose capture does not record its link follows the golden:
    // connected before the records since the last message, closed after them.
    auto golden_connected = [&](std::size_t s) -> std::optional<bool> {
      for (const auto& h : g.sources)
        if (h.name == def.sources[s].name) return h.connected;
      return std::nullopt;
    };
    for (std::size_t s = 0; s < def.sources.size(); ++s)
      if (!replay.records_link(s) && golden_connected(s) == true && !replay.connected(s))
        replay.set_connected(s, true, lo);
    replay.advance_to(lo);
    for (std::size_t s = 0; s < def.sources.size(); ++s)
      if (!replay.records_link(s) && golden_connected(s) == false && replay.connected(s))
        replay.set_connected(s, false, lo);

    // Candidates: the records inside ±tol applied one by one, each at the
    // message's time and at the window's ends; the nominal one (every record
    // up to utime, at utime) is reported when none matches.
    std::optional<VerifyDifference> nominal;
    bool matched = false;
    for (;;) {
      const std::optional<int64_t> next = replay.next_time_us();
      const bool at_nominal = !next || *next > u;
      for (const int64_t t : {u, lo, hi}) {
        const PanelSnapshot snap = replay.mapper().preview(t);
        const rise_msgs::PanelState got = to_message(def, snap, g.trainee_id, g.seq, t, {});
        std::optional<VerifyDifference> diff = compare_panel_states(g, got, settings);
        if (!diff) {
          replay.mapper().evaluate(t);  // advances the filters as the live evaluation did
          matched = true;
          if (t != u) ++report.off_time;
          break;
        }
        if (at_nominal && t == u) nominal = std::move(diff);
      }
      if (matched || !next || *next > hi) break;
      replay.apply_next();
    }
    report.records = replay.records_applied();
    if (!matched) {
      VerifyDifference d = std::move(*nominal);
      d.message = k;
      d.seq = g.seq;
      d.utime = u;
      d.time_s = static_cast<double>(u - report.start_us) * 1e-6;
      report.difference = std::move(d);
      return report;
    }
    ++report.messages;
  }
  report.records = replay.records_applied();
  return report;
}

PanelStateLog read_panel_state_log(const std::string& path, const std::string& channel) {
  if (!std::filesystem::exists(path)) throw std::runtime_error(path + ": cannot open: " + std::strerror(ENOENT));
  lcm::LogFile log(path, "r");
  if (!log.good()) throw std::runtime_error(path + ": cannot read as an LCM log");
  PanelStateLog out;
  out.channel = channel;
  std::vector<std::string> channels;
  int64_t event = 0;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    ++event;
    if (channel.empty()) {
      if (!ends_with(e->channel, "/panel_state")) continue;
      if (std::find(channels.begin(), channels.end(), e->channel) == channels.end()) channels.push_back(e->channel);
      if (channels.size() > 1)
        throw std::runtime_error(path + ": PanelState on several channels (" + channels[0] + ", " + channels[1] +
                                 "): name one (--id)");
      out.channel = e->channel;
    } else if (e->channel != channel) {
      continue;
    }
    rise_msgs::PanelState m;
    if (!msgs::decode_message(e->data, e->datalen, m))
      throw std::runtime_error(path + ": event " + std::to_string(event) + " on " + e->channel +
                               " does not decode as rise_msgs.PanelState");
    out.messages.push_back(std::move(m));
  }
  if (out.messages.empty())
    throw std::runtime_error(path + ": no PanelState on " +
                             (channel.empty() ? std::string("a */panel_state channel") : channel));
  return out;
}

}  // namespace rise::hil
