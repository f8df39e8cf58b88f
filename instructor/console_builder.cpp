#include "instructor/console_builder.hpp"

#include <httplib.h>

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <filesystem>
#include <memory>
#include <mutex>
#include <regex>
#include <sstream>
#include <tuple>

#include "firmware_protocol/console_can.hpp"
#include "firmware_protocol/dbc.hpp"
#include "firmware_protocol/hid_descriptor.hpp"
#include "firmware_protocol/hid_report.hpp"
#include "hil/bridge.hpp"
#include "hil/io/input_device.hpp"
#include "hil/source_factory.hpp"
#include "instructor/design_files.hpp"
#include "instructor/design_routes.hpp"
#include "instructor/web_json.hpp"
#include "instructor/web_requests.hpp"
#include "msgs/clock.hpp"

namespace rise::instructor {

namespace fs = std::filesystem;
using panels::ControlEntry;
using panels::FieldValue;

namespace {

// Whether the live view opens a source: one that only listens.
bool passive(const panels::SourceDefinition& s) { return !s.is_j1939() && !s.is_canopen(); }

FieldValue scalar(std::string s) { return FieldValue{false, std::move(s), {}}; }

std::string number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// A hid source's input signals, from its device's report descriptor (the
// device opened once, then closed for the bridge): a gamepad's buttons the
// definition does not bind show too. Axes, buttons and hats (as switches:
// the direction index); relative fields and array slots are left out.
std::vector<RawSignal> hid_raw_signals(const panels::PanelDefinition& def, std::size_t source, const std::string& url) {
  const std::string device_url = url == "-" ? def.sources[source].device : url;
  auto device = hil::io::open_input_device(device_url);
  if (device->reopen() != hil::io::IoStatus::Ok)
    throw std::runtime_error("source '" + def.sources[source].name + "': " + device_url + ": cannot open: " +
                             device->last_error());
  const auto parsed = firmware_protocol::parse_hid_descriptor(device->report_descriptor());
  device->close();
  if (!parsed) throw std::runtime_error("source '" + def.sources[source].name + "': its report descriptor does not parse");
  std::vector<RawSignal> out;
  for (const auto& sig : firmware_protocol::hid_signals(parsed.descriptor, firmware_protocol::HidReportKind::Input)) {
    using K = firmware_protocol::HidSignalKind;
    if (sig.name == "padding" || (sig.kind != K::Axis && sig.kind != K::Button && sig.kind != K::Hat)) continue;
    RawSignal r{source, sig.name, sig.kind == K::Axis ? "axis" : sig.kind == K::Button ? "button" : "switch"};
    for (const auto& c : def.controls) r.bound = r.bound || (c.source == source && c.hid_signal == sig.name);
    char usage[32];
    std::snprintf(usage, sizeof usage, "usage 0x%04X:0x%04X", firmware_protocol::hid_usage_page(sig.usage),
                  static_cast<unsigned>(sig.usage & 0xffff));
    r.wire = usage;
    out.push_back(r);
  }
  return out;
}

constexpr int kSwitchPositions = 256;  // a switch signal is one byte

// The wide definition's control reading signal `i`.
ControlEntry wide_entry(const panels::PanelDefinition& def, const RawSignal& r, std::size_t i,
                        const std::vector<ControlEntry>& controls) {
  ControlEntry e;
  const auto& source = def.sources[r.source];
  const bool named = source.is_hid() || source.is_generic_modbus() || source.is_canopen();
  bool copied = false;
  if (named) {
    // The definition's own entry, less what makes it more than a reading.
    for (const auto& c : controls) {
      const FieldValue* signal = c.find("signal");
      const FieldValue* src = c.find("source");
      const std::string src_name = src ? src->scalar : def.sources[0].name;
      if (!signal || signal->scalar != r.signal || src_name != source.name) continue;
      for (const auto& [k, v] : c.fields)
        if (k != "name" && k != "role" && k != "motion" && k != "source") e.fields.emplace_back(k, v);
      copied = true;
      break;
    }
  }
  if (!copied) {  // a signal of its own: a reading of it at the mapper's defaults
    e.fields = {{"kind", scalar(r.kind)}, {"signal", scalar(r.signal)}};
    if (r.kind == "axis") e.fields.emplace_back("safe", scalar("0.0"));
    if (r.kind == "button") e.fields.emplace_back("safe", scalar("false"));
    if (r.kind == "switch") {
      FieldValue positions{true, "", {}};
      for (int p = 0; p < kSwitchPositions; ++p) positions.items.push_back(scalar("p" + std::to_string(p)));
      e.fields.emplace_back("positions", positions);
      e.fields.emplace_back("safe", scalar("p0"));
    }
    if (source.is_dbc() && r.kind == "axis")
      e.fields.emplace_back("range", FieldValue{true, "", {scalar(number(r.lo)), scalar(number(r.hi))}});
  }
  e.fields.insert(e.fields.begin(), {{"name", scalar("raw_" + std::to_string(i))}, {"source", scalar(source.name)}});
  return e;
}

// The value a control of the wide definition shows for its signal.
double raw_value(const RawSignal& r, const hil::ControlValue& v, bool dbc) {
  if (r.kind == "button") return v.pressed ? 1.0 : 0.0;
  if (r.kind == "switch") return v.position;
  return dbc ? r.lo + (v.axis + 1.0) / 2.0 * (r.hi - r.lo) : v.axis;
}

double round_to(double v, double step) { return std::round(v / step) * step; }

// ---- The live view -------------------------------------------------------

struct LearnStats {
  bool seen = false;
  double rest = 0, min = 0, max = 0;  // rest: the first value (the user moves it after the window opens)
  int samples = 0, nonzero = 0;       // a button rests in the state it was in longer
};

class LiveView {
 public:
  LiveView(std::string file, const std::string& text, const std::string& path, const std::vector<std::string>& urls) :
      file_(std::move(file)), urls_(urls) {
    const panels::PanelDefinition def = panels::parse_panel_definition(text, path);
    for (const auto& s : def.sources)
      if (!passive(s))
        throw std::runtime_error("source '" + s.name + "' (" + s.protocol +
                                 ") is not opened by the builder: it takes part in its bus; read it through rise-hild");
    if (urls.size() != def.sources.size())
      throw std::runtime_error(file_ + " has " + std::to_string(def.sources.size()) + " source(s), the server " +
                               std::to_string(urls.size()) +
                               " --console-source URL(s): give one per source, in the definition's order");
    const auto controls = panels::read_panel_controls(text, path);
    signals_ = raw_signals(def, controls);
    for (std::size_t i = 0; i < def.sources.size(); ++i) {
      if (!def.sources[i].is_hid() || def.sources[i].mapping == "sdl" || urls[i].rfind("evdev:", 0) == 0) continue;
      std::erase_if(signals_, [i](const RawSignal& r) { return r.source == i; });
      for (auto& r : hid_raw_signals(def, i, urls[i])) signals_.push_back(std::move(r));
    }
    std::vector<ControlEntry> wide;
    for (std::size_t i = 0; i < signals_.size(); ++i) wide.push_back(wide_entry(def, signals_[i], i, controls));
    wide_definition_ = panels::parse_panel_definition(panels::write_panel_controls(text, wide), path);
    values_.assign(signals_.size(), 0.0);
    stats_.assign(signals_.size(), {});
    raw_ = start_bridge(wide_definition_, [this](const hil::PanelSnapshot& s) { on_raw(s); });
  }
  ~LiveView() {
    if (preview_) preview_->stop();
    if (raw_) raw_->stop();
  }

  const std::string& file() const { return file_; }

  /// Runs `def` as rise-hild would, for the preview.
  void set_preview(panels::PanelDefinition def) {
    if (preview_) preview_->stop();
    preview_.reset();
    for (const auto& s : def.sources)
      if (!passive(s)) return;
    if (def.sources.size() != urls_.size()) return;
    preview_ = start_bridge(std::move(def), [](const hil::PanelSnapshot&) {});
  }

  void learn(double seconds) {
    std::lock_guard lock(mutex_);
    stats_.assign(signals_.size(), {});
    learn_samples_ = 0;
    learn_until_us_ = msgs::monotonic_us() + static_cast<int64_t>(seconds * 1e6);
    learning_ = true;
  }

  Json::Value signals_json() const {
    Json::Value out(Json::arrayValue);
    for (std::size_t i = 0; i < signals_.size(); ++i) {
      const auto& r = signals_[i];
      Json::Value j;
      j["id"] = static_cast<int>(i);
      j["source"] = wide_definition_.sources[r.source].name;
      j["protocol"] = wide_definition_.sources[r.source].protocol;
      j["signal"] = r.signal;
      j["kind"] = r.kind;
      j["lo"] = r.lo;
      j["hi"] = r.hi;
      j["bound"] = r.bound;
      j["wire"] = r.wire;
      out.append(j);
    }
    return out;
  }

  Json::Value state_json() {
    Json::Value v;
    v["file"] = file_;
    {
      std::lock_guard lock(mutex_);
      Json::Value values(Json::arrayValue);
      for (double x : values_) values.append(x);
      v["values"] = values;
      Json::Value sources(Json::arrayValue);
      for (const auto& s : source_status_) {
        Json::Value j;
        j["name"] = s.name;
        j["connected"] = s.connected;
        j["stale"] = s.stale;
        j["frames_ok"] = static_cast<Json::Int64>(s.frames_ok);
        j["down_reason"] = s.down_reason;
        sources.append(j);
      }
      v["sources"] = sources;
      if (learning_ && msgs::monotonic_us() >= learn_until_us_) finish_learning();
      v["learning"] = learning_;
      v["learn_left_s"] = learning_ ? static_cast<double>(learn_until_us_ - msgs::monotonic_us()) / 1e6 : 0.0;
      v["learn_samples"] = learn_samples_;
      if (!proposal_.isNull()) v["proposal"] = proposal_;
    }
    if (preview_) v["preview"] = preview_json(preview_->snapshot(), preview_->definition());
    return v;
  }

 private:
  std::unique_ptr<hil::Bridge> start_bridge(panels::PanelDefinition def, hil::Bridge::PublishFn publish) {
    // No feedback: the console's LEDs stay rise-hild's.
    def.leds.clear();
    def.displays.clear();
    def.rumbles.clear();
    def.buzzer_source.reset();
    std::vector<std::unique_ptr<hil::SourceTransport>> transports;
    for (std::size_t i = 0; i < def.sources.size(); ++i) transports.push_back(hil::open_source(def, i, urls_[i]));
    auto bridge = std::make_unique<hil::Bridge>(std::move(def), std::move(transports), std::move(publish));
    bridge->start();
    return bridge;
  }

  static Json::Value preview_json(const hil::PanelSnapshot& snap, const panels::PanelDefinition& def) {
    Json::Value v;
    v["failsafe"] = snap.failsafe;
    v["failsafe_reason"] = snap.failsafe_reason;
    v["deadman"] = snap.deadman;
    Json::Value controls(Json::arrayValue);
    for (std::size_t i = 0; i < def.controls.size() && i < snap.controls.size(); ++i) {
      const auto& c = def.controls[i];
      const auto& x = snap.controls[i];
      Json::Value j;
      j["name"] = c.name;
      switch (c.kind) {
        case panels::ControlKind::Axis: j["kind"] = "axis"; j["value"] = x.axis; break;
        case panels::ControlKind::Button: j["kind"] = "button"; j["value"] = x.pressed; break;
        case panels::ControlKind::Switch:
          j["kind"] = "switch";
          j["value"] = x.position < c.positions.size() ? c.positions[x.position] : std::to_string(x.position);
          break;
      }
      j["forced_safe"] = x.forced_safe;
      controls.append(j);
    }
    v["controls"] = controls;
    return v;
  }

  // From the raw bridge's publisher thread, at the definition's rate and on change.
  void on_raw(const hil::PanelSnapshot& snap) {
    std::lock_guard lock(mutex_);
    source_status_ = snap.sources;  // as JSON when the page asks (state_json), not at 100 Hz
    learn_samples_ += learning_ ? 1 : 0;
    for (std::size_t i = 0; i < signals_.size() && i < snap.controls.size(); ++i) {
      if (snap.controls[i].forced_safe) continue;  // stale: not what the control does
      const double x = raw_value(signals_[i], snap.controls[i], wide_definition_.sources[signals_[i].source].is_dbc());
      values_[i] = x;
      if (!learning_) continue;
      LearnStats& st = stats_[i];
      if (!st.seen) st = {true, x, x, x, 0, 0};
      ++st.samples;
      st.nonzero += x != 0.0;
      st.min = std::min(st.min, x);
      st.max = std::max(st.max, x);
    }
    if (learning_ && snap.time_us >= learn_until_us_) finish_learning();
  }

  // The signal that moved most for its range; its rest, min and max set what is proposed.
  void finish_learning() {
    learning_ = false;
    proposal_ = Json::Value(Json::objectValue);
    double best = 0.0;
    std::size_t best_i = 0;
    for (std::size_t i = 0; i < signals_.size(); ++i) {
      const LearnStats& st = stats_[i];
      if (!st.seen) continue;
      const RawSignal& r = signals_[i];
      const double span = r.kind == "axis" ? r.hi - r.lo : 1.0;
      const double score = std::min(1.0, (st.max - st.min) / span);
      if (score > best) best = score, best_i = i;
    }
    if (best < 0.05) {
      proposal_["none"] = "nothing moved in the learn window";
      return;
    }
    const RawSignal& r = signals_[best_i];
    const LearnStats& st = stats_[best_i];
    proposal_["id"] = static_cast<int>(best_i);
    proposal_["source"] = wide_definition_.sources[r.source].name;
    proposal_["signal"] = r.signal;
    proposal_["kind"] = r.kind;
    proposal_["bound"] = r.bound;
    proposal_["rest"] = st.rest;
    proposal_["min"] = st.min;
    proposal_["max"] = st.max;
    proposal_["score"] = best;
    if (r.kind == "button") {
      const bool rests_pressed = 2 * st.nonzero > st.samples;
      proposal_["rest"] = rests_pressed ? 1 : 0;
      proposal_["pressed_value"] = rests_pressed ? 0 : 1;
    } else if (r.kind == "switch") {
      proposal_["positions"] = static_cast<int>(st.max) + 1;
    } else {
      // Moved to its positive end first: the side it went further from rest.
      proposal_["invert"] = (st.rest - st.min) > (st.max - st.rest);
      const bool physical = wide_definition_.sources[r.source].is_dbc() ||
                            wide_definition_.sources[r.source].is_generic_modbus();
      const double lo = physical ? st.min : -1.0, hi = physical ? st.max : 1.0;
      const double rest_norm = hi > lo ? 2.0 * (st.rest - lo) / (hi - lo) - 1.0 : 0.0;
      // A centred stick rests near 0: its offset plus a margin is the deadband;
      // a lever resting at an end needs only the margin.
      const double deadband = std::fabs(rest_norm) < 0.5 ? std::fabs(rest_norm) + 0.03 : 0.03;
      proposal_["deadband"] = round_to(std::min(deadband, 0.3), 0.01);
      if (physical) {
        Json::Value range(Json::arrayValue);
        range.append(st.min);
        range.append(st.max);
        proposal_["range"] = range;
      }
    }
  }

  std::string file_;
  std::vector<std::string> urls_;
  std::vector<RawSignal> signals_;
  panels::PanelDefinition wide_definition_;
  std::mutex mutex_;  // guards what follows
  std::vector<double> values_;
  std::vector<hil::SourceStatus> source_status_;
  std::vector<LearnStats> stats_;
  bool learning_ = false;
  int learn_samples_ = 0;  // snapshots the learn window has read (the first is each signal's rest)
  int64_t learn_until_us_ = 0;
  Json::Value proposal_;
  std::unique_ptr<hil::Bridge> raw_;  // after what its callback uses: stopped first
  std::unique_ptr<hil::Bridge> preview_;
};

// ---- Routes --------------------------------------------------------------

using Req = httplib::Request;
using Res = httplib::Response;

struct ConsoleBuilder {
  ConsoleBuilder(const std::string& dir, std::vector<std::string> u)
      : folder(std::make_shared<DesignFolder>(dir)), urls(std::move(u)) {}
  std::shared_ptr<DesignFolder> folder;
  DesignKind kind;
  std::vector<std::string> urls;
  std::mutex live_mutex;
  std::unique_ptr<LiveView> live;

  /// Runs `check`'s definition in the live view's preview when the view
  /// shows the file at `path`; says so in `reply`.
  void preview(const std::string& path, ConsoleCheck& check, Json::Value* reply) {
    std::lock_guard lock(live_mutex);
    if (!live || folder->path(live->file()) != path || !check.definition) return;
    try {
      live->set_preview(std::move(*check.definition));
      (*reply)["preview"] = true;
    } catch (const std::exception& e) {
      (*reply)["preview_error"] = e.what();
    }
  }
};

// The Console Builder's kind of file: the panel definitions of --consoles
// DIR, whose `controls:` list the page rewrites in the file on disk. A check
// of the file the live view shows also runs the edited definition in its
// preview.
DesignKind console_kind(const std::shared_ptr<ConsoleBuilder>& b) {
  DesignKind kind;
  kind.plural = "consoles";
  kind.singular = "console";
  kind.flag = "--consoles DIR";
  kind.list = [urls = b->urls](const DesignFolder& folder) {
    Json::Value v, files(Json::arrayValue), u(Json::arrayValue);
    for (const auto& f : folder.list(".yaml")) files.append(f);
    for (const auto& url : urls) u.append(url);
    v["dir"] = folder.dir();
    v["files"] = files;
    v["urls"] = u;
    return v;
  };
  kind.read = [](const std::string& text, const std::string& path) {
    const auto controls = panels::read_panel_controls(text, path);
    const ConsoleCheck check = check_console(text, controls, path);
    Json::Value v, sources(Json::arrayValue);
    v["controls"] = controls_json(controls);
    v["check"] = check_json(check);
    if (check.definition)
      for (const auto& s : check.definition->sources) {
        Json::Value j;
        j["name"] = s.name;
        j["protocol"] = s.protocol;
        sources.append(j);
      }
    v["sources"] = sources;
    return v;
  };
  std::weak_ptr<ConsoleBuilder> weak = b;
  kind.check = [weak](const Json::Value& body, const std::string& path, const std::string& disk,
                      std::string* error) -> std::optional<DesignCheck> {
    const auto controls = controls_from_json(body["controls"], error);
    if (!controls) return *error = "controls: " + *error, std::nullopt;
    ConsoleCheck check = check_console(disk, *controls, path);
    Json::Value extra = check_json(check);
    if (auto b = weak.lock()) b->preview(path, check, &extra);
    return DesignCheck{std::move(check.yaml), std::move(check.errors), extra};
  };
  return kind;
}

void handle_live_start(ConsoleBuilder& b, const Req& req, Res& res) {
  const std::string name = design_name(*b.folder, b.kind, req, res);
  if (name.empty()) return;
  DesignText file;
  try {
    file = b.folder->read(name);
  } catch (const std::exception& e) {
    return reply_json_error(res, 404, e.what());
  }
  std::lock_guard lock(b.live_mutex);
  b.live.reset();  // one live view: its sources closed before another opens them
  try {
    b.live = std::make_unique<LiveView>(name, file.text, b.folder->path(name), b.urls);
  } catch (const std::exception& e) {
    return reply_json_error(res, 422, e.what());
  }
  Json::Value v;
  v["file"] = name;
  v["signals"] = b.live->signals_json();
  reply_json(res, v);
}

void handle_live_state(ConsoleBuilder& b, Res& res) {
  std::lock_guard lock(b.live_mutex);
  if (!b.live) return reply_json_error(res, 404, "no live view: open one (POST /api/builder/console/NAME/live)");
  reply_json(res, b.live->state_json());
}

void handle_learn(ConsoleBuilder& b, const Req& req, Res& res) {
  std::string error;
  const auto body = parse_json_object(req.body, &error);
  if (!body) return reply_json_error(res, 400, error);
  const double seconds = (*body)["seconds"].isNumeric() ? (*body)["seconds"].asDouble() : 3.0;
  if (!(seconds > 0.2 && seconds <= 30.0)) return reply_json_error(res, 400, "seconds: 0.2 < s <= 30");
  std::lock_guard lock(b.live_mutex);
  if (!b.live) return reply_json_error(res, 404, "no live view: open one (POST /api/builder/console/NAME/live)");
  b.live->learn(seconds);
  Json::Value v;
  v["learning"] = true;
  v["seconds"] = seconds;
  reply_json(res, v);
}

}  // namespace

void add_console_builder_routes(httplib::Server& http, const std::string& dir, const std::vector<std::string>& urls) {
  auto b = std::make_shared<ConsoleBuilder>(dir, urls);
  b->kind = console_kind(b);
  http.Post(R"(/api/builder/console/([^/]+)/live)", [b](const Req& req, Res& res) { handle_live_start(*b, req, res); });
  add_design_routes(http, b->folder, b->kind);
  http.Get("/api/builder/console_live", [b](const Req&, Res& res) { handle_live_state(*b, res); });
  http.Post("/api/builder/console_learn", [b](const Req& req, Res& res) { handle_learn(*b, req, res); });
}

}  // namespace rise::instructor
