#include "instructor/app/instructor_commands.hpp"

#include <json/json.h>
#include <lcm/lcm-cpp.hpp>
#include <poll.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>

#include "instructor/scenario.hpp"
#include "instructor/scenario_runner.hpp"
#include "instructor/trainee_directory.hpp"
#include "msgs/channels.hpp"
#include "msgs/clock.hpp"
#include "msgs/clock_offset.hpp"
#include "msgs/command_auth.hpp"
#include "msgs/lcm_decode.hpp"
#include "msgs/publisher_session.hpp"
#include "rise_msgs/FaultCommand.hpp"
#include "rise_msgs/PanelState.hpp"
#include "rise_msgs/RobotState.hpp"
#include "rise_msgs/SimEvent.hpp"
#include "rise_msgs/TrainingControl.hpp"
#include "sim/training/task_description.hpp"

namespace rise::instructor {
namespace {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

[[noreturn]] void fail(int code) { throw CLI::RuntimeError(code); }

void setup_logging() { spdlog::set_level(spdlog::level::from_str(common_options().log_level)); }

std::unique_ptr<lcm::LCM> open_lcm() {
  auto lcm = std::make_unique<lcm::LCM>(common_options().lcm_url);
  if (!lcm->good()) {
    spdlog::error("cannot open LCM at {}", common_options().lcm_url);
    fail(2);
  }
  return lcm;
}

// The instructor's key: required to send anything (a trainee station has none).
msgs::InstructorKey instructor_key() {
  const std::string path = msgs::instructor_key_path(common_options().key_file);
  try {
    return msgs::load_instructor_key(path);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    fail(2);
  }
}

// Handles LCM messages until `done` says so or the timeout; false on timeout.
bool handle_until(lcm::LCM& lcm, double timeout_s, const std::function<bool()>& done) {
  const auto deadline = Clock::now() + std::chrono::microseconds(static_cast<int64_t>(timeout_s * 1e6));
  while (!done()) {
    if (g_stop || Clock::now() >= deadline) return false;
    pollfd pfd{lcm.getFileno(), POLLIN, 0};
    if (::poll(&pfd, 1, 10) > 0) lcm.handle();
  }
  return true;
}

// Raw LCM handler: forwards (channel, bytes) to a function.
struct RawHandler {
  std::function<void(const std::string&, const lcm::ReceiveBuffer*)> fn;
  void on(const lcm::ReceiveBuffer* rbuf, const std::string& channel) { fn(channel, rbuf); }
};

template <class Message>
std::optional<Message> decode(const lcm::ReceiveBuffer* rbuf) {
  Message m;
  if (!msgs::decode_message(rbuf->data, rbuf->data_size, m)) return std::nullopt;
  return m;
}

bool is_daemon_kind(const std::string& kind) {
  static const char* sim_kinds[] = {"motor_failure", "motor_weakness", "track_slip", "weak_joint",
                                    "camera_blackout", "scanner_noise", "scanner_dropout"};
  for (const char* k : sim_kinds)
    if (kind == k) return false;
  return true;
}

// The receiver's clock − ours, measured once per trainee (msgs/clock_offset.hpp),
// so that a command is stamped in its receiver's clock; 0 when no station
// process answers (the command then carries this host's clock).
int64_t receiver_offset_us(lcm::LCM& lcm, const std::string& trainee) {
  static std::map<std::string, int64_t> measured;
  if (const auto it = measured.find(trainee); it != measured.end()) return it->second;
  const auto s = msgs::measure_clock_offset(lcm, trainee);
  if (s)
    spdlog::info("{}'s clock: {:+.1f} ms from this host's (round trip {:.1f} ms)", trainee,
                 static_cast<double>(s->offset_us) / 1e3, static_cast<double>(s->delay_us) / 1e3);
  else
    spdlog::info("{}: no clock echo (rise-hild, rise-sim): commands carry this host's clock", trainee);
  return measured[trainee] = s ? s->offset_us : 0;
}

// What the receivers answered to one fault command.
struct Answer {
  bool confirmed = false;
  std::string refusal;  // non-empty: refused or rejected, with why
};

// Publishes a signed FaultCommand and waits up to confirm_s for its effect:
// an inject of a daemon kind shows in PanelState.active_faults, one of a sim
// kind as a fault_injected SimEvent; a clear as its absence / fault_cleared;
// a refusal or rejection as fault_refused / command_rejected (sim) or a
// "command_rejected" PanelState entry (daemon).
Answer send_fault(lcm::LCM& lcm, rise_msgs::FaultCommand c, double confirm_s) {
  c.utime = msgs::wall_us() + receiver_offset_us(lcm, c.trainee_id);
  msgs::sign(c, instructor_key());
  Answer answer;
  const bool daemon = c.action == "inject" ? is_daemon_kind(c.kind) : false;
  const int64_t sent_us = c.utime;
  RawHandler h{[&](const std::string& channel, const lcm::ReceiveBuffer* rbuf) {
    if (channel == msgs::panel_state_channel(c.trainee_id)) {
      const auto m = decode<rise_msgs::PanelState>(rbuf);
      if (!m || m->utime < sent_us) return;
      bool present = false;
      for (const auto& f : m->active_faults) {
        present = present || f.rfind(c.fault_id + ":", 0) == 0;
        if (f.rfind("command_rejected", 0) == 0 && f.find("from '" + c.issuer + "'") != std::string::npos &&
            answer.refusal.empty() && daemon)
          answer.refusal = f;
      }
      if (c.action == "inject" && daemon && present) answer.confirmed = true;
    } else if (channel == msgs::sim_event_channel(c.trainee_id)) {
      const auto m = decode<rise_msgs::SimEvent>(rbuf);
      if (!m || m->utime < sent_us) return;
      if ((m->kind == "fault_injected" && c.action == "inject") || (m->kind == "fault_cleared" && c.action == "clear"))
        answer.confirmed = answer.confirmed || c.fault_id.empty() || m->b == c.fault_id;
      if (m->kind == "fault_refused" && m->b == c.fault_id) answer.refusal = m->detail;
      if (m->kind == "command_rejected" && m->b == msgs::fault_command_channel(c.trainee_id)) answer.refusal = m->detail;
    }
  }};
  lcm::Subscription* s1 = lcm.subscribe(msgs::panel_state_channel(c.trainee_id), &RawHandler::on, &h);
  lcm::Subscription* s2 = lcm.subscribe(msgs::sim_event_channel(c.trainee_id), &RawHandler::on, &h);
  lcm.publish(msgs::fault_command_channel(c.trainee_id), &c);
  // One UDP datagram can be lost (a receiver's socket buffer full under
  // load): an inject not confirmed within a second goes again, signed afresh
  // (the same signature again would be a replay). Receivers replace a fault of
  // the same id, so a second copy of one that did arrive changes nothing.
  const auto answered = [&] { return answer.confirmed || !answer.refusal.empty(); };
  const auto deadline = Clock::now() + std::chrono::microseconds(static_cast<int64_t>(confirm_s * 1e6));
  const auto seconds_left = [&] { return std::chrono::duration<double>(deadline - Clock::now()).count(); };
  const double resend_s = c.action == "inject" ? 1.0 : confirm_s;
  for (int copies = 2; confirm_s > 0; ++copies) {
    if (handle_until(lcm, std::min(resend_s, seconds_left()), answered) || seconds_left() <= 0 || g_stop) break;
    c.utime = msgs::wall_us() + receiver_offset_us(lcm, c.trainee_id);
    msgs::sign(c, instructor_key());
    spdlog::info("inject {}: no confirmation within a second, sent again (copy {})", c.fault_id, copies);
    lcm.publish(msgs::fault_command_channel(c.trainee_id), &c);
  }
  lcm.unsubscribe(s1);
  lcm.unsubscribe(s2);
  return answer;
}

int report_answer(const rise_msgs::FaultCommand& c, const Answer& a, double confirm_s) {
  const std::string what = c.action + " " + (c.fault_id.empty() ? "*" : c.fault_id);
  if (!a.refusal.empty()) {
    std::printf("%s on %s: refused: %s\n", what.c_str(), c.trainee_id.c_str(), a.refusal.c_str());
    return 1;
  }
  if (a.confirmed) {
    std::printf("%s on %s: confirmed\n", what.c_str(), c.trainee_id.c_str());
    return 0;
  }
  if (confirm_s <= 0 || c.action == "clear") {
    std::printf("%s on %s: sent\n", what.c_str(), c.trainee_id.c_str());
    return 0;
  }
  std::printf("%s on %s: no confirmation within %.1f s\n", what.c_str(), c.trainee_id.c_str(), confirm_s);
  return 1;
}

// Newest file with extension `ext` in dir (not recursive); "" when none.
fs::path newest(const fs::path& dir, const std::string& ext) {
  fs::path best;
  fs::file_time_type best_time{};
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    if (!e.is_regular_file() || e.path().extension() != ext) continue;
    const auto t = e.last_write_time();
    if (best.empty() || t > best_time || (t == best_time && e.path() > best)) {
      best = e.path();
      best_time = t;
    }
  }
  return best;
}

}  // namespace

CommonOptions& common_options() {
  static CommonOptions options;
  return options;
}

void add_common_options(CLI::App& app) {
  auto& o = common_options();
  app.fallthrough();
  app.add_option("--lcm", o.lcm_url, "LCM URL")->capture_default_str();
  app.add_option("--instructor-key", o.key_file,
                 "instructor key file (hex, mode 0600; default env RISE_INSTRUCTOR_KEY; `keygen` writes one)")
      ->type_name("FILE");
  app.add_option("--issuer", o.issuer, "name in the commands' issuer field")->capture_default_str();
  app.add_option("--log-level", o.log_level, "trace, debug, info, warn, error")->capture_default_str();
}

void add_keygen_command(CLI::App& app) {
  auto file = std::make_shared<std::string>();
  CLI::App* sub = app.add_subcommand("keygen", "write a new instructor key (32 random bytes, hex, mode 0600)");
  sub->add_option("FILE", *file, "where (must not exist)")->required();
  sub->callback([file] {
    setup_logging();
    try {
      msgs::write_new_instructor_key(*file);
    } catch (const std::exception& e) {
      spdlog::error("{}", e.what());
      fail(2);
    }
    std::printf("instructor key written to %s (mode 0600): give it to rise-hild/rise-sim with --instructor-key\n",
                file->c_str());
  });
}

void add_list_command(CLI::App& app) {
  auto wait_s = std::make_shared<double>(1.5);
  CLI::App* sub = app.add_subcommand("list", "trainees seen on rise/*/panel_state, robot_state, task_status");
  sub->add_option("--wait", *wait_s, "listen this long (s)")->capture_default_str();
  sub->callback([wait_s] {
    setup_logging();
    auto lcm = open_lcm();
    TraineeDirectory directory;
    std::set<std::string> heard;
    RawHandler h{[&](const std::string& channel, const lcm::ReceiveBuffer* rbuf) {
      directory.on_message(channel, rbuf->data, static_cast<int>(rbuf->data_size), msgs::wall_us());
      // Progress on stderr (the table is stdout's): who is heard, as they come.
      const std::string id = channel.substr(5, channel.find('/', 5) - 5);  // rise/ID/...
      if (heard.insert(id).second) std::fprintf(stderr, "hearing %s\n", id.c_str());
    }};
    lcm->subscribe("rise/[^/]+/(panel_state|robot_state|task_status)", &RawHandler::on, &h);
    handle_until(*lcm, *wait_s, [] { return false; });
    const auto rows = directory.rows();
    const int64_t now = msgs::wall_us();
    std::printf("%-10s %-28s %-22s %-24s %-20s %s\n", "trainee", "panel", "robot", "task", "faults", "publishers");
    for (const auto& r : rows) {
      std::string panel = "-", robot = "-", task = "-", faults;
      if (r.panel) {
        panel = r.panel->failsafe ? "failsafe: " + r.panel->failsafe_reason.substr(0, 18) : "ok";
        for (const auto& f : r.panel->active_faults) faults += (faults.empty() ? "" : ", ") + f;
      }
      if (r.robot) {
        char text[64];
        const double v = std::hypot(r.robot->linear_velocity_mps[0], r.robot->linear_velocity_mps[1]);
        std::snprintf(text, sizeof text, "(%.2f, %.2f) %.2f m/s", r.robot->position_m[0], r.robot->position_m[1], v);
        robot = text;
        for (const auto& f : r.robot->active_faults) faults += (faults.empty() ? "" : ", ") + f;
      }
      if (r.task) task = r.task->task + " " + r.task->state + " " + std::to_string(r.task->score);
      // Who publishes: "rise-hild 4242@lab3" per process, once.
      std::string publishers;
      std::set<int64_t> listed;
      for (const auto& p : r.publishers)
        if (listed.insert(p.publisher.session_id).second)
          publishers += (publishers.empty() ? "" : ", ") + p.publisher.program + " " + std::to_string(p.publisher.pid) +
                        "@" + p.publisher.host;
      std::printf("%-10s %-28s %-22s %-24s %-20s %s\n", r.id.c_str(), panel.c_str(), robot.c_str(), task.c_str(),
                  faults.empty() ? "-" : faults.c_str(), publishers.empty() ? "-" : publishers.c_str());
      if (r.lost(now))
        std::printf("  LOST: nothing from rise/%s/* for %.1f s\n", r.id.c_str(),
                    static_cast<double>(now - r.last_seen_us) / 1e6);
      for (const auto& what : r.duplicated(now)) {
        std::printf("  DUPLICATE: rise/%s/%s has more than one publisher:\n", r.id.c_str(), what.c_str());
        for (const auto& p : r.publishers)
          if (p.what == what && now - p.last_seen_us <= 2'000'000)
            std::printf("    %s\n", msgs::describe(p.publisher, now).c_str());
      }
    }
    if (rows.empty()) std::printf("no trainee seen within %.1f s\n", *wait_s);
  });
}

void add_inject_command(CLI::App& app) {
  struct Options {
    std::string trainee, kind, target, id;
    double value = 0.0, rate = 0.0, duration_s = 0.0, confirm_s = 2.0;
    int64_t seed = 1;
  };
  auto o = std::make_shared<Options>();
  CLI::App* sub = app.add_subcommand("inject", "inject a fault into a trainee's session (signed FaultCommand)");
  sub->add_option("--trainee", o->trainee, "trainee id")->required();
  sub->add_option("KIND", o->kind, "fault kind (README \"Faults\")")->required();
  sub->add_option("TARGET", o->target, "control, source, panel_state, left/right, joint, camera, laser")->required();
  sub->add_option("--value", o->value, "the kind's parameter");
  sub->add_option("--rate", o->rate, "the kind's second parameter");
  sub->add_option("--duration", o->duration_s, "seconds; 0 = until cleared")->capture_default_str();
  sub->add_option("--id", o->id, "fault id (default KIND-TARGET)");
  sub->add_option("--seed", o->seed, "seed of the fault's randomness")->capture_default_str();
  sub->add_option("--confirm", o->confirm_s, "wait this long for the receiver's confirmation (0: do not wait)")
      ->capture_default_str();
  sub->callback([o] {
    setup_logging();
    const auto& kinds = fault_kinds();
    if (std::find(kinds.begin(), kinds.end(), o->kind) == kinds.end()) {
      spdlog::error("unknown fault kind '{}'", o->kind);
      fail(2);
    }
    auto lcm = open_lcm();
    ScenarioAction a{0.0, true, o->id.empty() ? o->kind + "-" + o->target : o->id, o->kind, o->target, o->value,
                     o->rate, o->duration_s, static_cast<uint64_t>(o->seed)};
    const auto c = to_command(a, o->trainee, common_options().issuer);
    const int rc = report_answer(c, send_fault(*lcm, c, o->confirm_s), o->confirm_s);
    if (rc != 0) fail(rc);
  });
}

void add_clear_command(CLI::App& app) {
  struct Options {
    std::string trainee, id;
    double confirm_s = 1.0;
  };
  auto o = std::make_shared<Options>();
  CLI::App* sub = app.add_subcommand("clear", "clear one fault (or every fault) of a trainee");
  sub->add_option("--trainee", o->trainee, "trainee id")->required();
  sub->add_option("FAULT", o->id, "fault id (default: every fault)");
  sub->add_option("--confirm", o->confirm_s, "wait this long for an answer")->capture_default_str();
  sub->callback([o] {
    setup_logging();
    auto lcm = open_lcm();
    ScenarioAction a;
    a.inject = false;
    a.id = o->id;
    const auto c = to_command(a, o->trainee, common_options().issuer);
    const int rc = report_answer(c, send_fault(*lcm, c, o->confirm_s), o->confirm_s);
    if (rc != 0) fail(rc);
  });
}

// A scenario's injects until their receiver shows them (as send_fault
// confirms one): a UDP datagram can be lost, and a scenario's fault that
// never arrived would be a lesson that never happened. One not shown within
// half a second goes again, signed afresh, until it shows, is cleared, or
// its time is over.
class PendingInjects {
 public:
  void sent(const rise_msgs::FaultCommand& c, double now_s) {
    forget(c.fault_id);  // a clear, or a new inject of the same id, ends the wait for the earlier one
    if (c.action != "inject") return;
    pending_.push_back({c, now_s + kResendS, now_s + std::max(c.duration_s, 3.0)});
  }
  /// A PanelState's or RobotState's active faults ("ID: ..."), a SimEvent fault_injected's ID.
  void shown(const std::vector<std::string>& active_faults) {
    for (const auto& f : active_faults) forget(f.substr(0, f.find(':')));
  }
  void forget(const std::string& id) {
    std::erase_if(pending_, [&](const Pending& p) { return p.command.fault_id == id; });
  }
  /// The injects to send again now (their `next` moved on); drops those whose time is over.
  std::vector<rise_msgs::FaultCommand> due(double now_s) {
    std::erase_if(pending_, [&](const Pending& p) { return now_s >= p.until_s; });
    std::vector<rise_msgs::FaultCommand> out;
    for (auto& p : pending_)
      if (now_s >= p.next_s) {
        out.push_back(p.command);
        p.next_s = now_s + kResendS;
      }
    return out;
  }

 private:
  static constexpr double kResendS = 0.5;
  struct Pending {
    rise_msgs::FaultCommand command;
    double next_s, until_s;
  };
  std::vector<Pending> pending_;
};

void add_scenario_command(CLI::App& app) {
  struct Options {
    std::string file, task, trainee;
    std::optional<uint64_t> seed;
    double duration_s = 0.0;
  };
  auto o = std::make_shared<Options>();
  CLI::App* sub = app.add_subcommand(
      "scenario", "run a fault scenario (YAML) against a trainee's session: triggers from time, SimEvents and "
                  "RobotState/PanelState, seeded; ends when every fault is done, at --duration or on SIGINT "
                  "(auto_clear faults are cleared then)");
  sub->add_option("FILE", o->file, "scenario file");
  sub->add_option("--task", o->task, "a task file: its `scenario:` is run");
  sub->add_option("--trainee", o->trainee, "trainee id")->required();
  sub->add_option("--seed", o->seed, "seed (default: the file's)");
  sub->add_option("--duration", o->duration_s, "stop after S seconds (0: when every fault is done)");
  sub->callback([o] {
    setup_logging();
    std::string file = o->file;
    try {
      if (file.empty() && !o->task.empty()) {
        // The task file's `scenario:` (resolved against the task's folder).
        const auto task = sim::training::load_task_description(o->task);
        if (task.scenario_file.empty()) throw std::runtime_error(o->task + ":1: scenario: the task names no scenario");
        file = task.scenario_file;
      }
      if (file.empty()) throw std::runtime_error("give a scenario FILE or --task TASK.yaml");
    } catch (const std::exception& e) {
      spdlog::error("{}", e.what());
      fail(2);
    }
    Scenario scenario;
    try {
      scenario = load_scenario(file);
    } catch (const std::exception& e) {
      spdlog::error("{}", e.what());
      fail(2);
    }
    const uint64_t seed = o->seed ? *o->seed : scenario.seed;
    const auto key = instructor_key();
    auto lcm = open_lcm();
    const int64_t offset_us = receiver_offset_us(*lcm, o->trainee);  // before the scenario's clock starts
    ScenarioRunner runner(scenario, seed);
    const auto start = Clock::now();
    const auto now_s = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
    int sent = 0;
    PendingInjects pending;
    const auto publish = [&](rise_msgs::FaultCommand& c) {
      c.utime = msgs::wall_us() + offset_us;
      msgs::sign(c, key);
      lcm->publish(msgs::fault_command_channel(o->trainee), &c);
    };
    const auto send = [&](const std::vector<ScenarioAction>& actions) {
      for (const auto& a : actions) {
        auto c = to_command(a, o->trainee, common_options().issuer);
        publish(c);
        pending.sent(c, now_s());
        ++sent;
        spdlog::info("{:.3f} s: {} {} {} {} value {:.3f} for {} s", now_s(), c.action, c.fault_id, c.kind, c.target,
                     c.value, c.duration_s);
      }
    };
    const auto send_again = [&] {
      for (auto& c : pending.due(now_s())) {
        publish(c);
        spdlog::info("{:.3f} s: inject {} not shown yet, sent again", now_s(), c.fault_id);
      }
    };
    Observation seen;
    RawHandler h{[&](const std::string& channel, const lcm::ReceiveBuffer* rbuf) {
      if (channel == msgs::sim_event_channel(o->trainee)) {
        if (const auto e = decode<rise_msgs::SimEvent>(rbuf)) {
          if (e->kind == "fault_injected" || e->kind == "fault_refused") pending.forget(e->b);  // shown, or never will be
          send(runner.on_event(now_s(), e->kind, e->a, e->b));
        }
      } else if (channel == msgs::robot_state_channel(o->trainee)) {
        if (const auto r = decode<rise_msgs::RobotState>(rbuf)) {
          pending.shown(r->active_faults);
          seen["speed_mps"] = std::hypot(r->linear_velocity_mps[0], r->linear_velocity_mps[1]);
          seen["x_m"] = r->position_m[0];
          seen["y_m"] = r->position_m[1];
          seen["damage"] = r->damage;
          seen["sim_time_s"] = r->sim_time_s;
          send(runner.on_observation(now_s(), seen));
        }
      } else if (channel == msgs::panel_state_channel(o->trainee)) {
        if (const auto p = decode<rise_msgs::PanelState>(rbuf)) {
          pending.shown(p->active_faults);
          seen["failsafe"] = p->failsafe ? 1.0 : 0.0;
          send(runner.on_observation(now_s(), seen));
        }
      }
    }};
    for (const std::string& channel : {msgs::sim_event_channel(o->trainee), msgs::robot_state_channel(o->trainee),
                                       msgs::panel_state_channel(o->trainee)})
      lcm->subscribe(channel, &RawHandler::on, &h);
    std::signal(SIGINT, on_signal);
    std::signal(SIGTERM, on_signal);
    spdlog::info("scenario '{}' ({}, seed {}): {} faults against {}", scenario.name, file, seed,
                 scenario.faults.size(), o->trainee);
    while (!g_stop && !runner.finished(now_s()) && (o->duration_s <= 0 || now_s() < o->duration_s)) {
      send(runner.advance(now_s()));
      send_again();
      pollfd pfd{lcm->getFileno(), POLLIN, 0};
      if (::poll(&pfd, 1, 5) > 0) lcm->handle();
    }
    send(runner.finish(now_s()));
    std::printf("scenario %s on %s: %d commands in %.1f s\n", scenario.name.c_str(), o->trainee.c_str(), sent, now_s());
  });
}

void add_task_command(CLI::App& app) {
  struct Options {
    std::string command, trainee, task;
    double confirm_s = 2.0;
  };
  auto o = std::make_shared<Options>();
  CLI::App* sub = app.add_subcommand(
      "task", "start, stop or restart a trainee's task (signed TrainingControl to rise-sim: start = resume, "
              "stop = pause, restart = reset to the start pose)");
  sub->add_option("COMMAND", o->command, "start, stop or restart")->required()->check(CLI::IsMember({"start", "stop", "restart"}));
  sub->add_option("--trainee", o->trainee, "trainee id")->required();
  sub->add_option("--task", o->task, "task name, for the log");
  sub->add_option("--confirm", o->confirm_s, "wait this long for rise-sim's answer (0: do not wait)")->capture_default_str();
  sub->callback([o] {
    setup_logging();
    const auto key = instructor_key();
    auto lcm = open_lcm();
    rise_msgs::TrainingControl c{};
    c.issuer = common_options().issuer;
    c.trainee_id = o->trainee;
    c.command = o->command;
    c.task = o->task;
    c.utime = msgs::wall_us() + receiver_offset_us(*lcm, o->trainee);
    msgs::sign(c, key);
    std::string answer;
    RawHandler h{[&](const std::string&, const lcm::ReceiveBuffer* rbuf) {
      const auto e = decode<rise_msgs::SimEvent>(rbuf);
      if (!e || e->utime < c.utime) return;
      if (e->kind == "command_rejected" && e->b == msgs::training_control_channel(o->trainee)) answer = "refused: " + e->detail;
      if (e->kind.rfind("training_", 0) == 0) answer = e->kind;
    }};
    lcm->subscribe(msgs::sim_event_channel(o->trainee), &RawHandler::on, &h);
    lcm->publish(msgs::training_control_channel(o->trainee), &c);
    if (o->confirm_s > 0) handle_until(*lcm, o->confirm_s, [&] { return !answer.empty(); });
    std::printf("task %s on %s: %s\n", o->command.c_str(), o->trainee.c_str(),
                answer.empty() ? (o->confirm_s > 0 ? "no answer" : "sent") : answer.c_str());
    if ((answer.empty() && o->confirm_s > 0) || answer.rfind("refused", 0) == 0) fail(1);
  });
}

void add_report_command(CLI::App& app) {
  struct Options {
    std::string trainee, dir;
    bool html = false;
  };
  auto o = std::make_shared<Options>();
  CLI::App* sub = app.add_subcommand(
      "report", "print the latest task report rise-trainer wrote for a trainee (DIR/<ID>/ or DIR: its --out)");
  sub->add_option("--trainee", o->trainee, "trainee id")->required();
  sub->add_option("--reports-dir", o->dir, "where the trainer writes reports (--out, or a folder of one per trainee)")
      ->required();
  sub->add_flag("--html", o->html, "print the HTML report's path instead of a summary");
  sub->callback([o] {
    setup_logging();
    // No such folder is bad input (2); a folder without a report is "no" (1).
    std::error_code ec;
    fs::directory_iterator readable(o->dir, ec);
    if (ec) {
      std::fprintf(stderr, "%s: cannot open: %s\n", o->dir.c_str(), ec.message().c_str());
      fail(2);
    }
    fs::path dir = fs::path(o->dir) / o->trainee;
    if (!fs::is_directory(dir)) dir = o->dir;
    // training.json is the training's summary; the newest task report is the latest result.
    fs::path json = newest(dir, ".json");
    if (json.empty()) {
      std::fprintf(stderr, "%s: no report (*.json) for trainee %s\n", dir.c_str(), o->trainee.c_str());
      fail(1);
    }
    if (o->html) {
      fs::path html = json;
      html.replace_extension(".html");
      std::printf("%s\n", html.c_str());
      return;
    }
    Json::Value v;
    std::ifstream in(json);
    Json::CharReaderBuilder b;
    std::string errors;
    if (!Json::parseFromStream(b, in, &v, &errors)) {
      std::fprintf(stderr, "%s: %s\n", json.c_str(), errors.c_str());
      fail(2);
    }
    std::printf("report %s\n", json.c_str());
    for (const char* key : {"training", "task", "score", "total_score", "success", "end_reason", "time_s"})
      if (v.isMember(key)) std::printf("  %-12s %s\n", key, Json::writeString(Json::StreamWriterBuilder(), v[key]).c_str());
  });
}

}  // namespace rise::instructor
