#include "hil/fault_injector.hpp"

#include <algorithm>
#include <cmath>

#include "hil/input_fault.hpp"

namespace rise::hil {
namespace {

int64_t end_time(int64_t now_us, double duration_s) {
  return duration_s > 0.0 ? now_us + static_cast<int64_t>(std::llround(duration_s * 1e6)) : 0;
}

constexpr std::string_view kPhysics[] = {"motor_failure", "motor_weakness", "track_slip", "weak_joint"};
constexpr std::string_view kSensor[] = {"camera_blackout", "scanner_noise", "scanner_dropout"};

}  // namespace

std::optional<FaultLayer> fault_layer(std::string_view kind) {
  if (parse_input_fault_kind(kind)) return FaultLayer::Input;
  if (io::parse_wire_fault_kind(kind)) return FaultLayer::Wire;
  if (kind == "lcm_loss" || kind == "lcm_latency") return FaultLayer::Transport;
  if (std::find(std::begin(kPhysics), std::end(kPhysics), kind) != std::end(kPhysics)) return FaultLayer::Physics;
  if (std::find(std::begin(kSensor), std::end(kSensor), kind) != std::end(kSensor)) return FaultLayer::Sensor;
  return std::nullopt;
}

void TransportFaults::inject(Fault fault) {
  std::lock_guard lock(mutex_);
  std::erase_if(faults_, [&](const Fault& f) { return f.id == fault.id; });
  faults_.push_back(std::move(fault));
}

std::size_t TransportFaults::clear(const std::string& id, int64_t now_us) {
  std::lock_guard lock(mutex_);
  const std::size_t named = std::erase_if(faults_, [&](const Fault& f) { return id.empty() || f.id == id; });
  std::erase_if(faults_, [&](const Fault& f) { return f.end_us != 0 && f.end_us <= now_us; });
  return named;
}

std::vector<TransportFaults::Fault> TransportFaults::active(int64_t now_us) const {
  std::lock_guard lock(mutex_);
  std::vector<Fault> out;
  for (const auto& f : faults_)
    if (f.active(now_us)) out.push_back(f);
  return out;
}

int64_t TransportFaults::lost() const {
  std::lock_guard lock(mutex_);
  return lost_;
}

std::vector<rise_msgs::PanelState> TransportFaults::pass(rise_msgs::PanelState message, int64_t now_us) {
  std::vector<rise_msgs::PanelState> out;
  {
    std::lock_guard lock(mutex_);
    const uint64_t n = messages_++;
    double delay_ms = 0.0;
    bool lost = false;
    for (const auto& f : faults_) {
      if (!f.active(now_us)) continue;
      if (f.loss)
        lost = lost || f.value <= 0.0 || f.value >= 1.0 || seeded_uniform(f.seed, n) < f.value;
      else
        delay_ms = std::max(delay_ms, f.rate > 0.0 ? f.rate : 100.0);
    }
    if (lost) {
      ++lost_;
    } else {
      held_.emplace_back(now_us + static_cast<int64_t>(delay_ms * 1000.0), std::move(message));
    }
  }
  return due(now_us);
}

std::vector<rise_msgs::PanelState> TransportFaults::due(int64_t now_us) {
  std::lock_guard lock(mutex_);
  std::vector<rise_msgs::PanelState> out;
  while (!held_.empty() && held_.front().first <= now_us) {
    out.push_back(std::move(held_.front().second));
    held_.pop_front();
  }
  return out;
}

FaultInjector::FaultInjector(Bridge& bridge, std::vector<io::WireFaultSet*> wires, TransportFaults* transport)
    : bridge_(bridge), wires_(std::move(wires)), transport_(transport) {}

std::string FaultInjector::inject(const FaultSpec& spec, int64_t now_us) {
  if (spec.id.empty()) return "a fault needs an id";
  const auto layer = fault_layer(spec.kind);
  if (!layer) return "unknown fault kind '" + spec.kind + "'";
  const auto& def = bridge_.definition();
  switch (*layer) {
    case FaultLayer::Input: {
      const auto control = def.find_control(spec.target);
      if (!control) return "no control '" + spec.target + "' in panel '" + def.name + "'";
      InputFault f;
      f.id = spec.id;
      f.kind = *parse_input_fault_kind(spec.kind);
      f.control = *control;
      f.value = spec.value;
      f.rate = spec.rate;
      f.seed = spec.seed;
      f.start_us = now_us;
      f.end_us = end_time(now_us, spec.duration_s);
      return bridge_.inject_input_fault(std::move(f));
    }
    case FaultLayer::Wire: {
      std::size_t source = def.sources.size();
      for (std::size_t i = 0; i < def.sources.size(); ++i)
        if (def.sources[i].name == spec.target || (spec.target.empty() && def.sources.size() == 1)) source = i;
      if (source == def.sources.size()) return "no source '" + spec.target + "' in panel '" + def.name + "'";
      const io::WireFaultKind kind = *io::parse_wire_fault_kind(spec.kind);
      const bool can_source = !def.sources[source].is_modbus() && !def.sources[source].is_hid();
      if (io::is_can_fault(kind) != can_source || def.sources[source].is_hid())
        return spec.kind + " does not apply to source '" + def.sources[source].name + "' (" +
               def.sources[source].protocol + ")";
      if (source >= wires_.size() || !wires_[source]) return "source '" + spec.target + "' has no fault decorator";
      io::WireFault f{spec.id, kind, spec.value, spec.rate, spec.seed, now_us, end_time(now_us, spec.duration_s)};
      wires_[source]->inject(std::move(f));
      return {};
    }
    case FaultLayer::Transport: {
      if (!transport_) return "no transport faults here";
      if (!spec.target.empty() && spec.target != "panel_state")
        return "transport faults act on panel_state, not '" + spec.target + "'";
      transport_->inject({spec.id, spec.kind == "lcm_loss", spec.value, spec.rate, spec.seed, now_us,
                          end_time(now_us, spec.duration_s)});
      return {};
    }
    case FaultLayer::Physics:
    case FaultLayer::Sensor: return spec.kind + " is a sim fault (rise-sim applies it)";
  }
  return "?";
}

std::size_t FaultInjector::clear(const std::string& id, int64_t now_us) {
  (void)now_us;
  std::size_t n = bridge_.clear_input_faults(id);
  for (io::WireFaultSet* w : wires_)
    if (w) n += w->clear(id, now_us);
  if (transport_) n += transport_->clear(id, now_us);
  return n;
}

std::vector<std::string> FaultInjector::active(int64_t now_us) const {
  std::vector<std::string> out;
  const auto& def = bridge_.definition();
  for (std::size_t i = 0; i < wires_.size(); ++i) {
    if (!wires_[i]) continue;
    for (const auto& f : wires_[i]->active(now_us))
      out.push_back(f.id + ": " + io::to_string(f.kind) + " " + def.sources[i].name);
  }
  if (transport_)
    for (const auto& f : transport_->active(now_us))
      out.push_back(f.id + ": " + (f.loss ? "lcm_loss" : "lcm_latency") + " panel_state");
  return out;
}

}  // namespace rise::hil
