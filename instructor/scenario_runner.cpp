#include "instructor/scenario_runner.hpp"

#include "hil/io/seeded_draw.hpp"

namespace rise::instructor {
namespace {

uint64_t draw(uint64_t seed, uint64_t index) { return hil::io::seeded_bits(seed, index); }
double uniform(uint64_t seed, uint64_t index) { return hil::io::seeded_uniform(seed, index); }

}  // namespace

ScenarioRunner::ScenarioRunner(Scenario scenario, uint64_t seed) : scenario_(std::move(scenario)), seed_(seed) {
  slots_.resize(scenario_.faults.size());
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    const ScenarioFault& f = scenario_.faults[i];
    Slot& s = slots_[i];
    const uint64_t base = i * 4;
    s.fires = uniform(seed_, base) < f.probability || f.probability >= 1.0;
    s.jitter_s = f.jitter_s * uniform(seed_, base + 1);
    s.value = f.value_range ? (*f.value_range)[0] + ((*f.value_range)[1] - (*f.value_range)[0]) * uniform(seed_, base + 2)
                            : f.value;
    s.seed = draw(seed_, base + 3) >> 1;  // fits the message's int64
    if (!s.fires) s.state = State::Done;
  }
}

void ScenarioRunner::trigger(std::size_t i, double t_s) {
  Slot& s = slots_[i];
  if (s.state != State::Waiting) return;
  s.state = State::Scheduled;
  s.due_s = t_s + scenario_.faults[i].delay_s + s.jitter_s;
}

ScenarioAction ScenarioRunner::inject_action(std::size_t i, double t_s) const {
  const ScenarioFault& f = scenario_.faults[i];
  return {t_s, true, f.id, f.kind, f.target, slots_[i].value, f.rate, f.duration_s, slots_[i].seed};
}

ScenarioAction ScenarioRunner::clear_action(std::size_t i, double t_s) const {
  const ScenarioFault& f = scenario_.faults[i];
  ScenarioAction a;
  a.time_s = t_s;
  a.inject = false;
  a.id = f.id;
  a.kind = f.kind;
  a.target = f.target;
  return a;
}

std::vector<ScenarioAction> ScenarioRunner::advance(double t_s) {
  now_s_ = t_s;
  std::vector<ScenarioAction> out;
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    const ScenarioFault& f = scenario_.faults[i];
    Slot& s = slots_[i];
    if (s.state == State::Waiting && f.trigger.kind == Trigger::Kind::At && t_s >= f.trigger.at_s)
      trigger(i, f.trigger.at_s);
    if (s.state == State::Scheduled && t_s >= s.due_s) {
      s.state = State::Active;
      s.end_s = f.duration_s > 0.0 ? s.due_s + f.duration_s : 0.0;
      out.push_back(inject_action(i, s.due_s));
    }
    if (s.state == State::Active && f.clear_on.kind == Trigger::Kind::At && t_s >= f.clear_on.at_s) {
      s.state = State::Done;
      out.push_back(clear_action(i, t_s));
    }
    // A duration ends on the receivers' own clocks; here it only counts as done.
    if (s.state == State::Active && s.end_s > 0.0 && t_s >= s.end_s) s.state = State::Done;
  }
  return out;
}

std::vector<ScenarioAction> ScenarioRunner::on_event(double t_s, const std::string& kind, const std::string& a,
                                                     const std::string& b) {
  const auto hit = [&](const Trigger& t) {
    return t.kind == Trigger::Kind::Event && t.event == kind && (t.a.empty() || t.a == a) && (t.b.empty() || t.b == b);
  };
  std::vector<ScenarioAction> out;
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    const ScenarioFault& f = scenario_.faults[i];
    if (slots_[i].state == State::Waiting && hit(f.trigger)) trigger(i, t_s);
    else if (slots_[i].state == State::Active && hit(f.clear_on)) {
      slots_[i].state = State::Done;
      out.push_back(clear_action(i, t_s));
    }
  }
  for (auto& a2 : advance(t_s)) out.push_back(std::move(a2));
  return out;
}

bool ScenarioRunner::matches(const Trigger& t, const Observation& o) {
  const auto it = o.find(t.field);
  if (it == o.end()) return false;
  return (!t.above || it->second > *t.above) && (!t.below || it->second < *t.below);
}

std::vector<ScenarioAction> ScenarioRunner::on_observation(double t_s, const Observation& observation) {
  std::vector<ScenarioAction> out;
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    const ScenarioFault& f = scenario_.faults[i];
    Slot& s = slots_[i];
    if (f.trigger.kind == Trigger::Kind::Condition) {
      const bool now = matches(f.trigger, observation);
      if (now && !s.condition_was && s.state == State::Waiting) trigger(i, t_s);
      s.condition_was = now;
    }
    if (f.clear_on.kind == Trigger::Kind::Condition) {
      const bool now = matches(f.clear_on, observation);
      if (now && !s.clear_condition_was && s.state == State::Active) {
        s.state = State::Done;
        out.push_back(clear_action(i, t_s));
      }
      s.clear_condition_was = now;
    }
  }
  for (auto& a : advance(t_s)) out.push_back(std::move(a));
  return out;
}

std::vector<ScenarioAction> ScenarioRunner::finish(double t_s) {
  std::vector<ScenarioAction> out;
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    Slot& s = slots_[i];
    const bool active = s.state == State::Active && (s.end_s == 0.0 || t_s < s.end_s);
    if (active && scenario_.faults[i].auto_clear) out.push_back(clear_action(i, t_s));
    s.state = State::Done;
  }
  return out;
}

bool ScenarioRunner::finished(double t_s) const {
  for (const Slot& s : slots_) {
    if (s.state == State::Done) continue;
    if (s.state == State::Active && s.end_s > 0.0 && t_s >= s.end_s) continue;
    return false;
  }
  return true;
}

rise_msgs::FaultCommand to_command(const ScenarioAction& a, const std::string& trainee_id, const std::string& issuer) {
  rise_msgs::FaultCommand c{};
  c.issuer = issuer;
  c.trainee_id = trainee_id;
  c.action = a.inject ? "inject" : "clear";
  c.fault_id = a.id;
  c.kind = a.kind;
  c.target = a.target;
  c.value = a.value;
  c.rate = a.rate;
  c.duration_s = a.duration_s;
  c.seed = static_cast<int64_t>(a.seed);
  c.signature_len = 0;
  return c;
}

}  // namespace rise::instructor
