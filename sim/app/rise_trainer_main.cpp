// rise-trainer: the task engine and the training manager as LCM nodes, and
// the instructor's classroom view.
//
//   rise-trainer run-task TASK.yaml --id ID      executor beside a running rise-sim
//   rise-trainer train TRAINING.yaml --id ID --out DIR [--resume]
//   rise-trainer status                          every trainee's progress
//   rise-trainer check TRAINING.yaml|TASK.yaml   load and validate
//   rise-trainer check TRAINING.yaml --walk "score=10,success=1" --walk ...
//                                                and print the graph's walk
//                                                for those task results
//
// The executor listens on rise/<id>/sim_event and rise/<id>/robot_state,
// publishes TaskEvent on rise/<id>/task_event and TaskStatus on
// rise/<id>/task_status. The manager starts rise-sim per task node as a
// child process with the task's robot, world and start pose, follows the
// graph, and keeps a journal (DIR/journal.jsonl) it resumes from after a
// kill -9 of the simulator or of itself.

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "cli/command_line.hpp"
#include "msgs/channels.hpp"
#include "msgs/clock.hpp"
#include "msgs/lcm_decode.hpp"
#include "msgs/publisher_session.hpp"
#include "panels/data_path.hpp"
#include "process/child_process.hpp"
#include "rise_msgs/PanelState.hpp"
#include "rise_msgs/RobotState.hpp"
#include "rise_msgs/SimEvent.hpp"
#include "rise_msgs/TaskEvent.hpp"
#include "rise_msgs/TaskStatus.hpp"
#include "sim/app/scripted_console.hpp"
#include "sim/training/report.hpp"
#include "sim/training/task_executor.hpp"
#include "sim/training/training_graph.hpp"
#include "panels/yaml_reader.hpp"

namespace {
namespace tr = rise::sim::training;
namespace fs = std::filesystem;

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

double yaw_of(const double q[4]) {
  return std::atan2(2.0 * (q[0] * q[3] + q[1] * q[2]), 1.0 - 2.0 * (q[2] * q[2] + q[3] * q[3]));
}

tr::RobotSample sample_from(const rise_msgs::RobotState& m) {
  tr::RobotSample s;
  s.time_s = m.sim_time_s;
  for (std::size_t k = 0; k < 3; ++k) {
    s.position_m[k] = m.position_m[k];
    s.gripper_position_m[k] = m.gripper_position_m[k];
  }
  s.yaw_rad = yaw_of(m.orientation_wxyz);
  s.damage = m.damage;
  for (std::size_t i = 0; i < m.object_names.size() && i < m.object_positions_m.size(); ++i) {
    const auto& p = m.object_positions_m[i];
    if (p.size() == 3) s.objects.push_back({m.object_names[i], {p[0], p[1], p[2]}});
  }
  return s;
}

// Where a training stands, for TaskStatus.
struct Progress {
  std::string training;
  std::string node;
  int attempt = 1;
  int tasks_done = 0;
  int training_score = 0;
};

// One task's executor on LCM: feeds it, publishes what it fires and its
// status, drives the scripted console on the sim's clock.
class TaskRun {
 public:
  TaskRun(lcm::LCM& lcm, std::string id, tr::TaskDescription task, rise::sim::WorldDescription world,
          std::optional<rise::trainer::ScriptedConsole> console, Progress progress, bool fresh_sim)
      : lcm_(lcm),
        id_(std::move(id)),
        executor_(std::move(task), std::move(world)),
        console_(std::move(console)),
        progress_(std::move(progress)),
        fresh_sim_(fresh_sim) {}

  void on_state(const rise_msgs::RobotState& m) {
    // A fresh simulator starts at 0 s: anything later is the previous one's.
    if (!started_ && fresh_sim_ && m.sim_time_s > 0.5) return;
    if (!started_) {
      started_ = true;
      t0_s_ = m.sim_time_s;
      spdlog::info("{}: task {} started at sim time {:.3f} s", id_, executor_.task().name, m.sim_time_s);
    }
    last_state_ = std::chrono::steady_clock::now();
    executor_.on_state(sample_from(m));
    if (console_) {
      console_->advance(m.sim_time_s - t0_s_);
      if (!console_->silent()) {
        auto ps = console_->panel_state(id_, ++panel_seq_, rise::msgs::wall_us());
        ps.publisher = rise::msgs::this_publisher();
        lcm_.publish(rise::msgs::panel_state_channel(id_), &ps);
      }
    }
    publish_fired();
  }

  void on_event(const rise_msgs::SimEvent& m) {
    if (!started_) return;
    executor_.on_sim_event({m.sim_time_s, m.kind, m.a, m.b, m.detail});
    publish_fired();
  }

  void publish_status(bool force = false) {
    const auto now = std::chrono::steady_clock::now();
    if (!force && now < next_status_) return;
    next_status_ = now + std::chrono::milliseconds(500);
    const auto& r = executor_.result();
    rise_msgs::TaskStatus s;
    s.utime = rise::msgs::wall_us();
    s.trainee_id = id_;
    s.publisher = rise::msgs::this_publisher();
    s.training = progress_.training;
    s.node = progress_.node;
    s.task = executor_.task().name;
    s.attempt = progress_.attempt;
    s.tasks_done = progress_.tasks_done + (r.finished ? 1 : 0);
    s.state = r.finished ? "finished" : started_ ? "running" : "waiting";
    s.task_time_s = r.time_s;
    s.time_limit_s = r.time_limit_s;
    s.score = r.score;
    s.events_fired = static_cast<int32_t>(r.events.size());
    s.success = r.success;
    s.end_reason = r.end_reason;
    s.training_score = progress_.training_score + (r.finished ? r.score : 0);
    lcm_.publish(rise::msgs::task_status_channel(id_), &s);
  }

  bool started() const { return started_; }
  bool finished() const { return executor_.finished(); }
  void abort(const std::string& why) { executor_.abort(why); }
  tr::TaskResult result() const { return executor_.result(); }
  double seconds_since_state() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - last_state_).count();
  }

 private:
  void publish_fired() {
    for (const auto& f : executor_.take_fired()) {
      rise_msgs::TaskEvent e;
      e.utime = rise::msgs::wall_us();
      e.trainee_id = id_;
      e.training = progress_.training;
      e.task = executor_.task().name;
      e.attempt = progress_.attempt;
      e.task_time_s = f.time_s;
      e.name = f.name;
      e.kind = f.kind;
      e.points = f.points;
      e.score = f.score;
      e.detail = f.detail;
      lcm_.publish(rise::msgs::task_event_channel(id_), &e);
      spdlog::info("{}: {:.2f} s {} {:+d} → {} ({})", id_, f.time_s, f.name, f.points, f.score, f.detail);
    }
    if (executor_.finished() && !announced_end_) {
      announced_end_ = true;
      publish_status(true);
    }
  }

  lcm::LCM& lcm_;
  std::string id_;
  tr::TaskExecutor executor_;
  std::optional<rise::trainer::ScriptedConsole> console_;
  Progress progress_;
  bool fresh_sim_;
  bool started_ = false;
  bool announced_end_ = false;
  double t0_s_ = 0.0;
  int64_t panel_seq_ = 0;
  std::chrono::steady_clock::time_point last_state_ = std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point next_status_{};
};

// Routes the trainee's sim channels to the task running now.
struct Router {
  TaskRun* run = nullptr;
  void on_state(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::RobotState* m) {
    if (run) run->on_state(*m);
  }
  void on_event(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::SimEvent* m) {
    if (run) run->on_event(*m);
  }
};

void subscribe(lcm::LCM& lcm, const std::string& id, Router& router) {
  // Events come in bursts (a track on step noses); states at 50 Hz.
  rise::msgs::subscribe<&Router::on_state>(lcm, rise::msgs::robot_state_channel(id), &router)->setQueueCapacity(500);
  rise::msgs::subscribe<&Router::on_event>(lcm, rise::msgs::sim_event_channel(id), &router)->setQueueCapacity(2000);
}

// One trainer per station: another process on the channels this one
// publishes (TaskStatus; PanelState too with a scripted console) is refused
// at start-up and reported while it runs.
struct PublisherGuard {
  static void report(const rise::msgs::PublisherWatch::Other& o) {
    spdlog::warn("another publisher on {}: {}", o.channel, rise::msgs::describe(o.publisher, rise::msgs::wall_us()));
  }
  rise::msgs::PublisherListener<rise_msgs::TaskStatus> status{rise::msgs::this_publisher().session_id, report};
  rise::msgs::PublisherListener<rise_msgs::PanelState> panel{rise::msgs::this_publisher().session_id, report};
};

// False (logged) when another process already publishes there.
bool claim_station(lcm::LCM& lcm, const std::string& id, bool scripted_console, bool allow_duplicate_id,
                   PublisherGuard& guard) {
  const std::string status_channel = rise::msgs::task_status_channel(id), panel_channel = rise::msgs::panel_state_channel(id);
  if (!allow_duplicate_id) {
    std::optional<rise::msgs::ChannelPublisher> other;
    if (scripted_console)
      other = rise::msgs::probe_channels<rise_msgs::PanelState>(lcm, {panel_channel}, rise::msgs::kProbeMs);
    if (!other)
      other = rise::msgs::probe_channels<rise_msgs::TaskStatus>(lcm, {status_channel}, rise::msgs::kSlowProbeMs);
    if (other) {
      spdlog::error("{} is already published by {}: refusing to start a second trainer for station '{}' (give "
                    "another --id, or --allow-duplicate-id)",
                    other->channel, rise::msgs::describe(other->publisher, rise::msgs::wall_us()), id);
      return false;
    }
  }
  guard.status.listen(lcm, status_channel);
  if (scripted_console) guard.panel.listen(lcm, panel_channel);
  return true;
}

std::optional<rise::trainer::ScriptedConsole> console_for(const tr::TaskDescription& t, bool scripted) {
  if (!scripted) return std::nullopt;
  if (t.console_script.empty() || t.panel_file.empty())
    throw std::runtime_error(t.file + ": --scripted-console needs the task's panel: and console_script:");
  return rise::trainer::ScriptedConsole(t.panel_file, t.console_script);
}

std::string stem_of(int index, const std::string& node, int attempt) {
  char buf[160];
  std::snprintf(buf, sizeof buf, "%02d_%s_%d", index, node.c_str(), attempt);
  return buf;
}

void write_task_report(const std::string& out_dir, const std::string& stem, const tr::TaskResult& r,
                       const rise::sim::WorldDescription& world) {
  tr::write_file_atomically((fs::path(out_dir) / (stem + ".json")).string(), tr::task_result_json(r));
  tr::write_file_atomically((fs::path(out_dir) / (stem + ".html")).string(), tr::task_report_html(r, world));
}

void print_result(const std::string& id, const tr::TaskResult& r) {
  std::printf("%s: task %s%s: score %d, %s, %.1f s, ended by %s\n", id.c_str(), r.task.c_str(),
              r.node.empty() ? "" : (" (" + r.node + " attempt " + std::to_string(r.attempt) + ")").c_str(), r.score,
              r.success ? "success" : "not achieved", r.time_s, r.end_reason.c_str());
  std::fflush(stdout);
}

// ---- run-task ------------------------------------------------------------

struct RunTaskOptions {
  std::string task_file, id = "t1", lcm_url = rise::msgs::kDefaultLcmUrl, out_dir = ".";
  bool scripted_console = false, allow_duplicate_id = false;
  double sim_timeout_s = 5.0;
};

int run_task(const RunTaskOptions& o) {
  lcm::LCM lcm(o.lcm_url);
  if (!lcm.good()) {
    spdlog::error("cannot open LCM at {}", o.lcm_url);
    return 2;
  }
  std::optional<TaskRun> run;
  rise::sim::WorldDescription world;
  try {
    const auto task = tr::load_task_description(o.task_file);
    world = rise::sim::load_world_description(task.world_file);
    fs::create_directories(o.out_dir);
    run.emplace(lcm, o.id, task, world, console_for(task, o.scripted_console), Progress{}, false);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
  PublisherGuard guard;
  if (!claim_station(lcm, o.id, o.scripted_console, o.allow_duplicate_id, guard)) return 2;
  Router router{&*run};
  subscribe(lcm, o.id, router);
  spdlog::info("{}: waiting for rise-sim on rise/{}/robot_state", o.id, o.id);
  while (!g_stop && !run->finished()) {
    lcm.handleTimeout(50);
    run->publish_status();
    if (run->started() && run->seconds_since_state() > o.sim_timeout_s) run->abort("simulator lost");
  }
  if (!run->finished()) run->abort("interrupted");
  run->publish_status(true);
  auto r = run->result();
  const std::string stem = "task_" + r.task;
  try {
    write_task_report(o.out_dir, stem, r, world);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
  print_result(o.id, r);
  std::printf("report: %s/%s.json, %s.html\n", o.out_dir.c_str(), stem.c_str(), stem.c_str());
  return r.end_reason == "interrupted" ? 130 : 0;
}

// ---- train ----------------------------------------------------------------

struct TrainOptions {
  std::string training_file, id = "t1", lcm_url = rise::msgs::kDefaultLcmUrl, out_dir;
  bool resume = false, scripted_console = false, fast = false, allow_duplicate_id = false;
  double sim_timeout_s = 5.0;
  double ready_timeout_s = 20.0;
};

// The training file with every task checked against its world, and the
// output folder made. Throws naming the file and what is wrong.
tr::TrainingGraph load_checked_training(const TrainOptions& o) {
  tr::TrainingGraph graph = tr::load_training_graph(o.training_file);
  for (const auto& n : graph.nodes) {
    const auto world = rise::sim::load_world_description(n.task->world_file);
    tr::check_against_world(*n.task, world);
  }
  fs::create_directories(o.out_dir);
  return graph;
}

// One attempt at a node of the graph, and its files' stem in --out.
struct Attempt {
  std::string node;
  int attempt = 1;
  std::string stem;
};

// A training on LCM: the graph, its journal in --out, and one rise-sim per
// task attempt.
class Trainer {
 public:
  Trainer(const TrainOptions& o, const tr::TrainingGraph& graph)
      : o_(o),
        graph_(graph),
        journal_((fs::path(o.out_dir) / "journal.jsonl").string()),
        walker_(graph),
        report_{graph.name, graph.title, graph.file, o.id, {}, false, "", 0, {}} {}

  void resume();
  bool ended() const { return walker_.ended(); }
  std::optional<int> run_next_task(lcm::LCM& lcm, Router& router);
  int finish(lcm::LCM& lcm);

 private:
  enum class AttemptEnd { Finished, SimulatorLost, Interrupted, NotReady };
  std::vector<std::string> simulator_argv(const tr::TaskDescription& task) const;
  AttemptEnd wait_for_task(lcm::LCM& lcm, TaskRun& run, rise::process::ChildProcess& sim, const Attempt& a) const;
  int abort_attempt(TaskRun& run, rise::process::ChildProcess& sim, const Attempt& a, bool sim_died);
  std::optional<int> record_attempt(TaskRun& run, const rise::sim::WorldDescription& world, const Attempt& a);
  void write_training_report();

  const TrainOptions& o_;
  const tr::TrainingGraph& graph_;
  const std::string journal_;
  tr::TrainingWalker walker_;
  tr::TrainingReport report_;
  bool already_finished_ = false;
  const std::string bin_ = rise::process::executable_dir();
};

// Replays the journal of an earlier run (--resume), or starts a new one.
// Throws naming the journal and what does not fit.
void Trainer::resume() {
  const auto entries = tr::read_journal(journal_);
  if (!entries.empty() && !o_.resume)
    throw std::runtime_error(journal_ + " exists: resume it with --resume, or use another --out");
  for (const auto& e : entries) {
    if (e.type == "training_started" && e.training != graph_.name)
      throw std::runtime_error(journal_ + ": journal of training '" + e.training + "', not '" + graph_.name + "'");
    if (e.type == "training_started" && e.trainee_id != o_.id)
      throw std::runtime_error(journal_ + ": journal of trainee '" + e.trainee_id + "': resume it with --id " +
                               e.trainee_id);
    if (e.type == "training_finished") {
      spdlog::info("{}: the training is already finished", journal_);
      already_finished_ = true;
    }
    if (e.type != "task_finished" || !e.result) continue;
    const auto cur = walker_.current();
    if (!cur || cur->first != e.node || cur->second != e.attempt)
      throw std::runtime_error(journal_ + ": task_finished " + e.node + " attempt " + std::to_string(e.attempt) +
                               " does not follow the graph (expected " +
                               (cur ? cur->first + " attempt " + std::to_string(cur->second) : "the end") + ")");
    walker_.record(*e.result);
    report_.task_report_files.push_back(stem_of(static_cast<int>(walker_.visits().size()), e.node, e.attempt) + ".html");
    spdlog::info("{}: resumed {} attempt {}: score {}", o_.id, e.node, e.attempt, e.result->score);
  }
  if (entries.empty()) tr::append_journal(journal_, {"training_started", graph_.name, o_.id, "", 0, std::nullopt, graph_.file});
}

void Trainer::write_training_report() {
  report_.visits = walker_.visits();
  report_.total_score = walker_.total_score();
  report_.finished = walker_.ended();
  report_.end_reason = walker_.end_reason();
  tr::write_file_atomically((fs::path(o_.out_dir) / "training.json").string(), tr::training_report_json(report_));
  tr::write_file_atomically((fs::path(o_.out_dir) / "training.html").string(), tr::training_report_html(report_));
}

// rise-sim's command line for a task: its robot at its start pose, its world.
std::vector<std::string> Trainer::simulator_argv(const tr::TaskDescription& task) const {
  std::string robot = task.robot_file;
  if (task.start) {
    char pose[96];
    std::snprintf(pose, sizeof pose, "@%.4f,%.4f,%.4f", task.start->xy_m[0], task.start->xy_m[1],
                  task.start->yaw_rad * 180.0 / M_PI);
    robot += pose;
  }
  std::vector<std::string> argv{bin_ + "/rise-sim", "--id", o_.id, "--lcm", o_.lcm_url, "--robot", robot,
                                "--world", task.world_file};
  if (o_.fast) argv.push_back("--fast");
  return argv;
}

// The graph's current node, one attempt: its own rise-sim and executor.
// An exit code when the training stops here; nullopt to go on.
std::optional<int> Trainer::run_next_task(lcm::LCM& lcm, Router& router) {
  const auto [node_name, attempt] = *walker_.current();
  const auto& task = *graph_.node(node_name)->task;
  const Attempt a{node_name, attempt, stem_of(static_cast<int>(walker_.visits().size()) + 1, node_name, attempt)};
  rise::sim::WorldDescription world;
  std::optional<TaskRun> run;
  try {
    world = rise::sim::load_world_description(task.world_file);
    Progress p{graph_.name, node_name, attempt, static_cast<int>(walker_.visits().size()), walker_.total_score()};
    run.emplace(lcm, o_.id, task, world, console_for(task, o_.scripted_console), p, true);
    tr::append_journal(journal_, {"task_started", graph_.name, o_.id, node_name, attempt, std::nullopt, task.file});
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
  // The previous simulator's last messages must not reach this task.
  router.run = nullptr;
  while (lcm.handleTimeout(0) > 0) {
  }
  router.run = &*run;
  std::optional<rise::process::ChildProcess> sim;
  try {
    sim.emplace(simulator_argv(task), (fs::path(o_.out_dir) / (a.stem + ".sim.log")).string());
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
  spdlog::info("{}: {} attempt {}: task {} on rise-sim pid {}", o_.id, node_name, attempt, task.name, sim->pid());
  const AttemptEnd end = wait_for_task(lcm, *run, *sim, a);
  if (end == AttemptEnd::NotReady) return 1;
  if (end != AttemptEnd::Finished) return abort_attempt(*run, *sim, a, end == AttemptEnd::SimulatorLost);
  sim->stop(2000);
  return record_attempt(*run, world, a);
}

// Runs the task until it finishes, the simulator dies or goes silent, or a
// signal stops the training.
Trainer::AttemptEnd Trainer::wait_for_task(lcm::LCM& lcm, TaskRun& run, rise::process::ChildProcess& sim,
                                           const Attempt& a) const {
  const auto launched = std::chrono::steady_clock::now();
  while (!g_stop && !run.finished()) {
    lcm.handleTimeout(50);
    run.publish_status();
    if (!sim.running()) return AttemptEnd::SimulatorLost;
    const double since_launch = std::chrono::duration<double>(std::chrono::steady_clock::now() - launched).count();
    if (!run.started() && since_launch > o_.ready_timeout_s) {
      spdlog::error("{}: rise-sim sent no RobotState within {:.0f} s (see {}.sim.log)", o_.id, o_.ready_timeout_s, a.stem);
      sim.stop(2000);
      return AttemptEnd::NotReady;
    }
    if (run.started() && run.seconds_since_state() > o_.sim_timeout_s) return AttemptEnd::SimulatorLost;
  }
  return g_stop ? AttemptEnd::Interrupted : AttemptEnd::Finished;
}

// The attempt did not finish: nothing of it goes into the results, so
// --resume runs it again. Returns the exit code.
int Trainer::abort_attempt(TaskRun& run, rise::process::ChildProcess& sim, const Attempt& a, bool sim_died) {
  sim.stop(1000);
  run.abort(sim_died ? "simulator lost" : "interrupted");
  run.publish_status(true);
  try {
    tr::append_journal(journal_, {"task_aborted", graph_.name, o_.id, a.node, a.attempt, std::nullopt,
                                  sim_died ? "simulator lost" : "interrupted"});
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
  }
  spdlog::error("{}: {} attempt {}: {}; the finished tasks are in {}: rerun with --resume", o_.id, a.node, a.attempt,
                sim_died ? "the simulator died" : "interrupted", journal_);
  try {
    write_training_report();
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
  }
  return sim_died ? 3 : 130;
}

// A finished attempt: its report, the journal, the walk on. An exit code
// when that fails.
std::optional<int> Trainer::record_attempt(TaskRun& run, const rise::sim::WorldDescription& world, const Attempt& a) {
  auto result = run.result();
  result.node = a.node;
  result.attempt = a.attempt;
  try {
    write_task_report(o_.out_dir, a.stem, result, world);
    tr::append_journal(journal_, {"task_finished", graph_.name, o_.id, a.node, a.attempt, result, ""});
    walker_.record(result);
    report_.task_report_files.push_back(a.stem + ".html");
    write_training_report();
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
  print_result(o_.id, result);
  std::printf("%s:   → %s\n", o_.id.c_str(), walker_.visits().back().transition.c_str());
  return std::nullopt;
}

// The graph has ended: the training report, the journal's end, a last
// TaskStatus. Returns the exit code.
int Trainer::finish(lcm::LCM& lcm) {
  try {
    write_training_report();
    if (!already_finished_)
      tr::append_journal(journal_, {"training_finished", graph_.name, o_.id, "", 0, std::nullopt, walker_.end_reason()});
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
  rise_msgs::TaskStatus s{};
  s.utime = rise::msgs::wall_us();
  s.trainee_id = o_.id;
  s.publisher = rise::msgs::this_publisher();
  s.training = graph_.name;
  s.tasks_done = static_cast<int32_t>(walker_.visits().size());
  s.state = "training_finished";
  s.end_reason = walker_.end_reason();
  s.training_score = walker_.total_score();
  lcm.publish(rise::msgs::task_status_channel(o_.id), &s);
  std::printf("%s: training %s finished (%s): %zu tasks, total score %d\nreport: %s/training.html, training.json\n",
              o_.id.c_str(), graph_.name.c_str(), walker_.end_reason().c_str(), walker_.visits().size(),
              walker_.total_score(), o_.out_dir.c_str());
  return 0;
}

int train(const TrainOptions& o) {
  tr::TrainingGraph graph;
  try {
    graph = load_checked_training(o);
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
  Trainer trainer(o, graph);
  try {
    trainer.resume();
  } catch (const std::exception& e) {
    spdlog::error("{}", e.what());
    return 2;
  }
  lcm::LCM lcm(o.lcm_url);
  if (!lcm.good()) {
    spdlog::error("cannot open LCM at {}", o.lcm_url);
    return 2;
  }
  PublisherGuard guard;
  if (!claim_station(lcm, o.id, o.scripted_console, o.allow_duplicate_id, guard)) return 2;
  Router router;
  subscribe(lcm, o.id, router);
  while (!g_stop && !trainer.ended())
    if (const auto code = trainer.run_next_task(lcm, router)) return *code;
  router.run = nullptr;
  if (g_stop) return 130;
  return trainer.finish(lcm);
}

// ---- status ---------------------------------------------------------------

int status(const std::string& lcm_url, double every_s, int count, int min_trainees) {
  struct Latest {
    std::map<std::string, rise_msgs::TaskStatus> by_trainee;
    void on(const lcm::ReceiveBuffer*, const std::string& channel, const rise_msgs::TaskStatus* m) {
      // The channel names the trainee; a message claiming another id is shown under the channel's.
      static const std::regex re("rise/([^/]+)/task_status");
      std::smatch match;
      auto s = *m;
      if (std::regex_match(channel, match, re)) s.trainee_id = match[1];
      by_trainee[s.trainee_id] = s;
    }
  } latest;
  lcm::LCM lcm(lcm_url);
  if (!lcm.good()) {
    std::fprintf(stderr, "rise-trainer status: cannot open LCM at %s\n", lcm_url.c_str());
    return 2;
  }
  rise::msgs::subscribe<&Latest::on>(lcm, "rise/.*/task_status", &latest)->setQueueCapacity(1000);
  for (int shown = 0; (count <= 0 || shown < count) && !g_stop;) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::microseconds(static_cast<int64_t>(every_s * 1e6));
    while (std::chrono::steady_clock::now() < until && !g_stop) lcm.handleTimeout(50);
    if (static_cast<int>(latest.by_trainee.size()) < min_trainees) continue;
    std::printf("%-10s %-14s %-10s %-18s %3s %-17s %8s %6s %6s %6s  %s\n", "trainee", "training", "node", "task", "try",
                "state", "time s", "limit", "score", "total", "ended by");
    for (const auto& [id, s] : latest.by_trainee)
      std::printf("%-10s %-14s %-10s %-18s %3d %-17s %8.1f %6.0f %6d %6d  %s\n", id.c_str(), s.training.c_str(),
                  s.node.c_str(), s.task.c_str(), s.attempt, s.state.c_str(), s.task_time_s, s.time_limit_s, s.score,
                  s.training_score, s.end_reason.c_str());
    std::printf("\n");
    std::fflush(stdout);
    ++shown;
  }
  return 0;
}

// One task's result for --walk: "score=10,success=1,events.neutralized=1"
// (score, time_s, success, damage, collisions, events.<name>). Throws
// std::invalid_argument naming the bad part.
tr::TaskResult walk_result(const std::string& spec) {
  tr::TaskResult r;
  r.finished = true;
  std::stringstream in(spec);
  std::string part;
  while (std::getline(in, part, ',')) {
    const auto eq = part.find('=');
    const std::string key = part.substr(0, eq);
    char* end = nullptr;
    const std::string text = eq == std::string::npos ? "" : part.substr(eq + 1);
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size())
      throw std::invalid_argument("--walk '" + spec + "': '" + part + "': expected NAME=NUMBER");
    if (key == "score") r.score = static_cast<int>(v);
    else if (key == "time_s") r.time_s = v;
    else if (key == "success") r.success = v != 0.0;
    else if (key == "damage") r.damage = v;
    else if (key == "collisions") r.collisions = static_cast<int>(v);
    else if (key.rfind("events.", 0) == 0 && key.size() > 7) r.counts[key.substr(7)] = static_cast<int>(v);
    else
      throw std::invalid_argument("--walk '" + spec + "': unknown field '" + key +
                                  "' (score, time_s, success, damage, collisions, events.<name>)");
  }
  return r;
}

// The walk the graph takes for these results, one line per task run:
// "walk: mission2 #1: score GE 5 → drill", then how it ended.
void print_walk(const tr::TrainingGraph& g, const std::vector<std::string>& walk) {
  tr::TrainingWalker w(g);
  for (const auto& spec : walk) {
    if (w.ended()) break;
    w.record(walk_result(spec));
    const auto& v = w.visits().back();
    std::printf("walk: %s #%d: %s\n", v.node.c_str(), v.attempt, v.transition.c_str());
  }
  if (w.ended()) std::printf("walk: ended: %s\n", w.end_reason().c_str());
  else std::printf("walk: next: %s #%d\n", w.current()->first.c_str(), w.current()->second);
}

int check(const std::string& file, const std::vector<std::string>& walk) {
  try {
    // A training file has a top-level `training:` key, a task file `task:`.
    static const std::regex training_key("(^|\n)training:");
    if (std::regex_search(rise::panels::read_text_file(file), training_key)) {
      const auto g = tr::load_training_graph(file);
      std::printf("%s: training %s, %zu nodes, %zu transitions: ok\n", file.c_str(), g.name.c_str(), g.nodes.size(),
                  g.transitions.size());
      if (!walk.empty()) print_walk(g, walk);
    } else {
      if (!walk.empty()) throw std::invalid_argument(file + ": --walk needs a training file");
      const auto t = tr::load_task_description(file);
      tr::check_against_world(t, rise::sim::load_world_description(t.world_file));
      std::printf("%s: task %s, %zu events: ok\n", file.c_str(), t.name.c_str(), t.events.size());
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rise-trainer: tasks with scored events, trainings, the classroom view"};
  app.require_subcommand(1);
  std::string log_level = "info";
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error")->capture_default_str();

  RunTaskOptions rt;
  CLI::App* r = app.add_subcommand("run-task", "run a task's executor beside a running rise-sim (over LCM)");
  r->add_option("task", rt.task_file, "task file (YAML)")->required();
  r->add_option("--id", rt.id, "trainee id in the channel names")->capture_default_str();
  r->add_option("--lcm", rt.lcm_url, "LCM URL")->capture_default_str();
  r->add_option("--out", rt.out_dir, "where the task report goes")->capture_default_str();
  r->add_flag("--scripted-console", rt.scripted_console, "play the task's console_script as the panel");
  r->add_option("--sim-timeout", rt.sim_timeout_s, "abort when no RobotState comes for S seconds")->capture_default_str();
  r->add_flag("--allow-duplicate-id", rt.allow_duplicate_id,
              "start even when another process already publishes rise/<id>/task_status (or, with a scripted "
              "console, panel_state)");

  TrainOptions to;
  CLI::App* t = app.add_subcommand("train", "run a training: rise-sim per task, the executor, the graph, the journal");
  t->add_option("training", to.training_file, "training file (YAML)")->required();
  t->add_option("--id", to.id, "trainee id in the channel names")->capture_default_str();
  t->add_option("--lcm", to.lcm_url, "LCM URL")->capture_default_str();
  t->add_option("--out", to.out_dir, "reports and journal.jsonl go here")->required();
  t->add_flag("--resume", to.resume, "continue the training in --out from its journal");
  t->add_flag("--scripted-console", to.scripted_console, "play each task's console_script as the panel");
  t->add_flag("--fast", to.fast, "run the simulators as fast as possible (rise-sim --fast)");
  t->add_option("--sim-timeout", to.sim_timeout_s, "the simulator is lost when no RobotState comes for S seconds")
      ->capture_default_str();
  t->add_flag("--allow-duplicate-id", to.allow_duplicate_id,
              "start even when another process already publishes rise/<id>/task_status (or, with a scripted "
              "console, panel_state)");

  std::string status_lcm = rise::msgs::kDefaultLcmUrl;
  double status_every_s = 1.0;
  int status_count = 0, status_min = 0;
  CLI::App* s = app.add_subcommand("status", "the instructor's view: every trainee's task status on rise/*/task_status");
  s->add_option("--lcm", status_lcm, "LCM URL")->capture_default_str();
  s->add_option("--every", status_every_s, "refresh period in seconds")->capture_default_str();
  s->add_option("--count", status_count, "stop after N tables (0: until Ctrl-C)")->capture_default_str();
  s->add_option("--trainees", status_min, "print only once at least N trainees were heard")->capture_default_str();

  std::string check_file;
  CLI::App* c = app.add_subcommand("check", "load and validate a training or task file");
  c->add_option("file", check_file, "training or task file")->required();
  std::vector<std::string> check_walk;
  c->add_option("--walk", check_walk,
                "a task's result, e.g. score=10,success=1,events.neutralized=1 (repeat it): print the walk the "
                "training graph takes for these results");
  if (const auto code = rise::cli::parse_command_line(app, "rise-trainer", argc, argv)) return *code;
  spdlog::set_level(spdlog::level::from_str(log_level));
  spdlog::set_pattern("[%H:%M:%S.%e] [%^%l%$] %v");
  rise::msgs::init_publisher("rise-trainer");
  // A relative file is looked up as every program does (as given, $RISE_ROOT,
  // the installed share/rise, the source tree): panels/data_path.hpp.
  for (std::string* file : {&rt.task_file, &to.training_file, &check_file})
    if (!file->empty()) *file = rise::panels::find_data_file(*file);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  if (r->parsed()) return run_task(rt);
  if (t->parsed()) return train(to);
  if (s->parsed()) return status(status_lcm, status_every_s, status_count, status_min);
  if (c->parsed()) return check(check_file, check_walk);
  return 1;
}
