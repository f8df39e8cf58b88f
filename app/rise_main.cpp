// rise: the front door. `rise demo` starts the whole chain as separate
// processes — console emulator → socketcand (TCP loopback) → rise-hild →
// LCM multicast → rise-sim — plays a scripted drive and reports what the
// safety rules did.

#include <CLI/CLI.hpp>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <random>
#include <set>
#include <thread>

#include "cli/command_line.hpp"
#include "msgs/channels.hpp"
#include "msgs/clock.hpp"
#include "msgs/failsafe.hpp"
#include "msgs/lcm_decode.hpp"
#include "msgs/publisher_session.hpp"
#include "panels/data_path.hpp"
#include "panels/panel_definition.hpp"
#include "process/chain_monitor.hpp"
#include "process/child_process.hpp"
#include "rise_msgs/PanelState.hpp"
#include "sim/simulation.hpp"
#include "sim/training/report.hpp"

namespace {
volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

uint16_t free_tcp_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof a;
  uint16_t port = 29536;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0 &&
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) == 0)
    port = ntohs(a.sin_port);
  ::close(fd);
  return port;
}

// printf into a std::string.
template <typename... Args>
std::string fmt_text(const char* format, Args... args) {
  char buf[256];
  std::snprintf(buf, sizeof buf, format, args...);
  return buf;
}

// The last `n` lines of a child's log, indented, for a report of its exit.
std::string last_lines(const std::string& file, std::size_t n) {
  std::ifstream in(file);
  std::deque<std::string> lines;
  for (std::string line; std::getline(in, line);) {
    lines.push_back(std::move(line));
    if (lines.size() > n) lines.pop_front();
  }
  std::string out;
  for (const auto& l : lines) out += "    " + l + "\n";
  return out.empty() ? "    (its log is empty)\n" : out;
}

// Station ids that some process publishes on now: every rise/<id>/ heard
// within wait_ms.
std::set<std::string> busy_station_ids(lcm::LCM& lcm, int wait_ms) {
  struct Heard {
    std::set<std::string> ids;
    void on(const lcm::ReceiveBuffer*, const std::string& channel) {
      const auto slash = channel.find('/', 5);
      if (slash != std::string::npos) ids.insert(channel.substr(5, slash - 5));
    }
  } heard;
  auto* sub = lcm.subscribe("rise/[^/]+/(panel_state|robot_state|task_status)", &Heard::on, &heard);  // channels only
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(wait_ms);
  while (std::chrono::steady_clock::now() < deadline) lcm.handleTimeout(20);
  lcm.unsubscribe(sub);
  return heard.ids;
}

struct DemoOptions {
  std::string id;  ///< "" → the first free one of demo, demo-2, demo-3, ...
  std::string lcm_url = rise::msgs::kDefaultLcmUrl;
  std::string script = "panels/scripts/demo_drive.txt";
  std::string panel = "panels/definitions/rise_console.yaml";
  std::string robot = "sim/robots/skid4.yaml";
  std::string log_dir;
  std::string record_dir;  ///< passed to rise-hild --record
  uint16_t port = 0;
  double timeout_s = 45.0;
  bool view = false;  ///< also run rise-instructor serve and print the trainee page's URL
};

// The web server of `rise demo --view`: loopback, a free port, a fresh token.
struct DemoView {
  uint16_t port = 0;
  std::string token;
  std::string token_file;
  std::string url(const std::string& id) const {
    return "http://127.0.0.1:" + std::to_string(port) + "/trainee.html?id=" + id + "&token=" + token;
  }
};

// A token nobody guesses: 128 bits from the kernel's random source, in hex.
std::string random_token() {
  std::random_device rd;
  std::string t;
  for (int i = 0; i < 4; ++i) t += fmt_text("%08x", static_cast<unsigned>(rd()));
  return t;
}

// The view server's port and token; the token goes into a file only its
// owner reads, so that it is not on the server's command line.
DemoView make_demo_view(const std::string& log_dir) {
  DemoView v{free_tcp_port(), random_token(), log_dir + "/view.token"};
  std::ofstream(v.token_file) << v.token << "\n";
  std::filesystem::permissions(v.token_file, std::filesystem::perms::owner_read | std::filesystem::perms::owner_write);
  return v;
}

// A child that is stopped when the guard goes (an exception, an early return).
struct ChildProcessGuard {
  explicit ChildProcessGuard(const std::vector<std::string>& argv) : child(argv, "") {}
  ~ChildProcessGuard() { child.stop(3000); }
  rise::process::ChildProcess child;
};

// The station id of a demo: "demo", or "demo-N" when another demo (or a
// classroom) on this LCM network uses it, so that none mixes into another's
// measurements. nullopt when LCM cannot be opened.
std::optional<std::string> demo_station_id(const DemoOptions& o) {
  if (!o.id.empty()) return o.id;
  lcm::LCM probe(o.lcm_url);
  if (!probe.good()) return std::nullopt;
  const auto busy = busy_station_ids(probe, rise::msgs::kProbeMs);
  std::string id = "demo";
  for (int n = 2; busy.count(id) > 0; ++n) id = "demo-" + std::to_string(n);
  if (id != "demo") std::printf("rise demo: station 'demo' is in use, taking '%s'\n", id.c_str());
  return id;
}

// rise-sim, rise-hild and the console emulator of one demo (and with
// --view rise-instructor serve), each logging into log_dir.
std::vector<rise::process::ChildProcess> start_demo_chain(const DemoOptions& o, const std::string& id,
                                                          const std::string& bus, const std::string& log_dir,
                                                          const std::optional<DemoView>& view) {
  const std::string bin = rise::process::executable_dir();
  std::vector<rise::process::ChildProcess> children;
  children.emplace_back(std::vector<std::string>{bin + "/rise-sim", "--id", id, "--lcm", o.lcm_url, "--robot",
                                                 rise::panels::find_data_file(o.robot)},
                        log_dir + "/rise-sim.log");
  std::vector<std::string> hild{bin + "/rise-hild", "--panel", rise::panels::find_data_file(o.panel),
                                "--can", "socketcand://" + bus, "--id", id, "--lcm", o.lcm_url};
  if (!o.record_dir.empty()) hild.insert(hild.end(), {"--record", o.record_dir});
  children.emplace_back(hild, log_dir + "/rise-hild.log");
  children.emplace_back(
      std::vector<std::string>{bin + "/rise-panel", "emulate", "--panel", rise::panels::find_data_file(o.panel),
                               "--can", "socketcand+listen://" + bus, "--script",
                               rise::panels::find_data_file(o.script), "--hold", "--start-on-feedback"},
      log_dir + "/rise-panel.log");
  if (view)
    children.emplace_back(
        std::vector<std::string>{bin + "/rise-instructor", "serve", "--listen", "127.0.0.1:" + std::to_string(view->port),
                                 "--token-file", view->token_file, "--lcm", o.lcm_url, "--robot",
                                 rise::panels::find_data_file(o.robot)},
        log_dir + "/rise-instructor.log");
  return children;
}

// One demo run: the chain's children and the monitor that measures them.
class DemoRun {
 public:
  DemoRun(const DemoOptions& o, std::string id, std::string log_dir, std::vector<rise::process::ChildProcess> children,
          rise::process::ChainMonitor& monitor)
      : o_(o), id_(std::move(id)), log_dir_(std::move(log_dir)), children_(std::move(children)), monitor_(monitor) {}

  /// Until the chain publishes a healthy panel and the robot: 0, or the exit code.
  int wait_until_up() {
    const auto up_since = std::chrono::steady_clock::now();
    bool ready = false;
    while (!ready && !g_stop) {
      ready = monitor_.wait_until(
          [](const rise::process::ChainView& v) { return v.have_robot && v.have_panel && !v.panel.failsafe; }, 50);
      if (!ready && child_died()) return 1;
      if (!ready && std::chrono::steady_clock::now() - up_since > std::chrono::seconds(15)) {
        std::fprintf(stderr, "rise demo: the chain did not come up within 15 s: %s\n", monitor_.live_line().c_str());
        return 1;
      }
    }
    return g_stop ? 130 : 0;
  }

  /// Plays the script until both stops are measured: 0, or the exit code.
  int play() {
    const auto start = std::chrono::steady_clock::now();
    auto next_line = start;
    int rc = 0;
    while (true) {
      if (g_stop) {
        std::printf("\nrise demo: interrupted, stopping every child\n");
        rc = 130;
        break;
      }
      const auto now = std::chrono::steady_clock::now();
      const double t = std::chrono::duration<double>(now - start).count();
      if (now >= next_line) {
        std::printf("t=%5.1fs %s\n", t, monitor_.live_line().c_str());
        std::fflush(stdout);
        next_line += std::chrono::milliseconds(500);
      }
      const auto v = monitor_.view();
      if (v.loss_stop.stopped && v.deadman_stop.stopped) break;
      if (child_died()) {
        rc = 1;
        break;
      }
      if (t > o_.timeout_s) {
        std::fprintf(stderr, "rise demo: timed out after %.0f s\n", o_.timeout_s);
        rc = 1;
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    for (auto& c : children_) c.stop(2000);
    return rc;
  }

  /// The summary of the measurements: 0 when both stops kept their bounds.
  int summary() const;

 private:
  // A child that ends is reported at once, with why (its log's last lines).
  bool child_died() {
    bool died = false;
    for (auto& c : children_) {
      if (c.running()) continue;
      const int status = c.wait_for(0);
      std::fprintf(stderr, "rise demo: %s exited with status %d; the end of %s/%s.log:\n%s", c.name().c_str(), status,
                   log_dir_.c_str(), c.name().c_str(), last_lines(log_dir_ + "/" + c.name() + ".log", 6).c_str());
      died = true;
    }
    return died;
  }

  const DemoOptions& o_;
  std::string id_;
  std::string log_dir_;
  std::vector<rise::process::ChildProcess> children_;
  rise::process::ChainMonitor& monitor_;
};

int DemoRun::summary() const {
  const DemoOptions& o = o_;
  const std::string& id = id_;
  int rc = 0;
  const auto v = monitor_.view();
  const double yaw =
      std::atan2(2.0 * (v.robot.orientation_wxyz[0] * v.robot.orientation_wxyz[3] +
                        v.robot.orientation_wxyz[1] * v.robot.orientation_wxyz[2]),
                 1.0 - 2.0 * (v.robot.orientation_wxyz[2] * v.robot.orientation_wxyz[2] +
                              v.robot.orientation_wxyz[3] * v.robot.orientation_wxyz[3])) *
      180.0 / M_PI;
  std::printf("\n=== rise demo summary ===\n");
  std::printf("messages              %lld PanelState, %lld RobotState on rise/%s/*\n",
              static_cast<long long>(v.panel_count), static_cast<long long>(v.robot_count), id.c_str());
  std::printf("distance driven       %.2f m\n", v.distance_m);
  std::printf("final pose            x=%.2f m y=%.2f m yaw=%.1f deg (sim time %.1f s)\n",
              v.robot.position_m[0], v.robot.position_m[1], yaw, v.robot.sim_time_s);
  // The promise: standstill within two publish periods plus the robot's own
  // braking time (simulated from the same speed), plus one RobotState period.
  double publish_period_s = 0.01;
  double source_timeout_s = 0.05;
  std::optional<rise::sim::RobotDescription> robot;
  try {
    const auto panel = rise::panels::load_panel_definition(rise::panels::find_data_file(o.panel));
    publish_period_s = 1.0 / panel.publish_hz;
    source_timeout_s = panel.sources.at(0).timeout_ms * 1e-3;
    robot = rise::sim::load_robot_description(rise::panels::find_data_file(o.robot));
  } catch (const std::exception&) {
  }
  if (v.foreign_count > 0)
    std::printf("other publishers      %lld messages on rise/%s/* from %s, not counted\n",
                static_cast<long long>(v.foreign_count), id.c_str(),
                rise::msgs::describe(v.foreign, rise::msgs::wall_us()).c_str());
  // A silent console is noticed after its timeout; a closed link at once.
  bool exceeded = false;
  auto report = [&](const char* what, const rise::process::StopMeasurement& s, double detect_s, const char* detect) {
    if (s.stopped && robot) {
      const double bound_s =
          detect_s + 2 * publish_period_s + rise::sim::stop_time_s(*robot, s.speed_at_trigger_mps) + 0.02;
      exceeded = exceeded || s.seconds() > bound_s;
      std::printf("%-21s %.0f ms to standstill from %.2f m/s (bound %.0f ms: %s2 publish periods + braking + "
                  "1 RobotState period)%s\n",
                  what, s.seconds() * 1e3, s.speed_at_trigger_mps, bound_s * 1e3, detect,
                  s.seconds() <= bound_s ? "" : " EXCEEDED");
    } else if (s.stopped)
      std::printf("%-21s %.0f ms to standstill from %.2f m/s\n", what, s.seconds() * 1e3,
                  s.speed_at_trigger_mps);
    else
      std::printf("%-21s not measured (%s)\n", what, s.triggered ? "robot never stopped" : "no event seen");
  };
  report("dead-man release", v.deadman_stop, 0.0, "");
  const bool silent = v.loss_causes.has(rise::msgs::FailsafeCause::SourceStale);
  report("source loss", v.loss_stop, silent ? source_timeout_s : 0.0, silent ? "source timeout + " : "");
  if (!v.loss_reason.empty()) std::printf("source loss seen as   %s\n", v.loss_reason.c_str());
  if (!o.record_dir.empty())
    std::printf("recorded into         %s (rise-hild verify --panel %s --record-dir %s)\n", o.record_dir.c_str(),
                o.panel.c_str(), o.record_dir.c_str());
  if (!v.deadman_stop.stopped || !v.loss_stop.stopped || exceeded) rc = 1;
  std::printf("result                %s\n", rc == 0 ? "ok" : "FAILED");
  return rc;
}

int run_demo(const DemoOptions& o) {
  const std::string log_dir = o.log_dir.empty() ? "/tmp/rise-demo-" + std::to_string(::getpid()) : o.log_dir;
  std::filesystem::create_directories(log_dir);
  const uint16_t port = o.port ? o.port : free_tcp_port();
  const std::string bus = "127.0.0.1:" + std::to_string(port) + "/can0";
  const std::optional<std::string> id = demo_station_id(o);
  if (!id) {
    std::fprintf(stderr, "rise demo: cannot open LCM at %s\n", o.lcm_url.c_str());
    return 2;
  }
  rise::process::ChainMonitor monitor(o.lcm_url, *id);
  if (!monitor.good()) {
    std::fprintf(stderr, "rise demo: cannot open LCM at %s\n", o.lcm_url.c_str());
    return 2;
  }
  std::printf("rise demo: station '%s', LCM %s, console on socketcand://%s, logs in %s\n",
              id->c_str(), o.lcm_url.c_str(), bus.c_str(), log_dir.c_str());
  std::vector<rise::process::ChildProcess> children;
  std::optional<DemoView> view;
  try {
    if (o.view) view = make_demo_view(log_dir);
    children = start_demo_chain(o, *id, bus, log_dir, view);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rise demo: %s\n", e.what());
    return 2;
  }
  std::vector<int32_t> pids;
  for (const auto& c : children) {
    std::printf("  started %-10s pid %d\n", c.name().c_str(), c.pid());
    pids.push_back(c.pid());
  }
  monitor.accept_only(pids);
  DemoRun run(o, *id, log_dir, std::move(children), monitor);
  if (const int rc = run.wait_until_up(); rc != 0) return rc;
  // Opens nothing: the URL is for a browser of the user's choice.
  if (view)
    std::printf("rise demo: trainee view (camera, HUD, sound) at %s\n", view->url(*id).c_str());
  std::printf("rise demo: chain up, playing %s\n", o.script.c_str());
  // The summary is printed after a failed run too: what was measured, and why not the rest.
  const int played = run.play();
  if (played == 130) return played;
  const int summarized = run.summary();
  return played != 0 ? played : summarized;
}
}  // namespace

// `rise demo training`: the example training (sim/training/examples,
// the seed's Fig. 10 graph ending in taskMETRO) end to end — rise-trainer
// train starts rise-sim for each task and plays each task's scripted
// console on LCM — then the summary from the journal and the reports.
struct TrainingDemoOptions {
  std::string id = "demo";
  std::string lcm_url = rise::msgs::kDefaultLcmUrl;
  std::string training = "sim/training/examples/fig10_training.yaml";
  std::string out_dir;
};

int run_training_demo(const TrainingDemoOptions& o) {
  const std::string bin = rise::process::executable_dir();
  const std::string out = o.out_dir.empty() ? "/tmp/rise-training-demo-" + std::to_string(::getpid()) : o.out_dir;
  std::printf("rise demo training: trainee '%s', LCM %s, %s → %s\n", o.id.c_str(), o.lcm_url.c_str(),
              o.training.c_str(), out.c_str());
  std::fflush(stdout);
  int rc = 1;
  try {
    ChildProcessGuard trainer({bin + "/rise-trainer", "train", rise::panels::find_data_file(o.training), "--id", o.id,
                               "--lcm", o.lcm_url, "--out", out, "--scripted-console"});
    while (rc = trainer.child.wait_for(100), rc < 0) {
      if (g_stop) {
        std::printf("\nrise demo training: interrupted; resume with rise-trainer train %s --out %s --resume\n",
                    o.training.c_str(), out.c_str());
        trainer.child.stop(3000);
        return 130;
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rise demo training: %s\n", e.what());
    return 2;
  }
  std::printf("\n=== rise demo training summary ===\n");
  int total = 0;
  bool all_ok = true;
  try {
    for (const auto& e : rise::sim::training::read_journal(out + "/journal.jsonl")) {
      if (e.type != "task_finished" || !e.result) continue;
      const auto& r = *e.result;
      total += r.score;
      all_ok = all_ok && r.success;
      std::printf("%-10s attempt %d  %-18s score %4d  %-13s %6.1f s  %s\n", e.node.c_str(), e.attempt, r.task.c_str(),
                  r.score, r.success ? "success" : "not achieved", r.time_s, r.end_reason.c_str());
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rise demo training: %s\n", e.what());
    return 1;
  }
  const bool report = std::filesystem::exists(out + "/training.html") && std::filesystem::exists(out + "/training.json");
  std::printf("total score           %d\n", total);
  std::printf("reports               %s/training.html (per task: %s/NN_<node>_<attempt>.html, .json)\n", out.c_str(),
              out.c_str());
  std::printf("result                %s\n", rc == 0 && report && all_ok ? "ok" : "FAILED");
  return rc == 0 && report && all_ok ? 0 : 1;
}

// `rise status`: the station's panel as rise-hild (or a virtual panel)
// publishes it: every control's value, the active faults, each source's
// health and why it is down, and who publishes (two publishers on one
// station are shown as such). One table per --every seconds.
struct StatusOptions {
  std::string id = "t1";
  std::string lcm_url = rise::msgs::kDefaultLcmUrl;
  double every_s = 1.0;
  int count = 0;          ///< stop after N tables (0: until Ctrl-C or --timeout)
  double timeout_s = 0.0; ///< give up when no PanelState came for this long (0: never)
};

void print_panel(const rise_msgs::PanelState& p, const std::vector<rise_msgs::Publisher>& publishers, int64_t now) {
  std::printf("panel %s (station %s) seq %lld: %s%s%s\n", p.panel_id.c_str(), p.trainee_id.c_str(),
              static_cast<long long>(p.seq), p.failsafe ? "FAILSAFE: " : "ok", p.failsafe_reason.c_str(),
              p.deadman ? ", dead-man held" : "");
  std::string line;
  for (const auto& a : p.axes) line += fmt_text("  %s %+.3f", a.name.c_str(), static_cast<double>(a.value));
  std::printf("  axes     %s\n", line.empty() ? " -" : line.c_str());
  line.clear();
  for (const auto& b : p.buttons) line += fmt_text("  %s %s", b.name.c_str(), b.pressed ? "PRESSED" : "off");
  std::printf("  buttons  %s\n", line.empty() ? " -" : line.c_str());
  line.clear();
  for (const auto& s : p.switches)
    line += fmt_text("  %s %s", s.name.c_str(), s.label.empty() ? std::to_string(s.position).c_str() : s.label.c_str());
  std::printf("  switches %s\n", line.empty() ? " -" : line.c_str());
  line.clear();
  for (const auto& f : p.active_faults) line += (line.empty() ? "  " : ", ") + f;
  std::printf("  faults   %s\n", line.empty() ? "  none" : line.c_str());
  std::printf("  %-10s %-5s %-5s %9s %10s %8s %6s %8s %6s %6s %6s  %s\n", "source", "conn", "stale", "age ms",
              "frames ok", "bad", "crc", "counter", "length", "unk id", "reconn", "status, bus, url");
  for (const auto& h : p.sources) {
    const std::string age = h.last_frame_age_us < 0 ? "-" : fmt_text("%.1f", static_cast<double>(h.last_frame_age_us) / 1e3);
    std::string detail = h.status.empty() ? "" : h.status + ", ";
    if (!h.bus_state.empty()) detail += h.bus_state + " (" + std::to_string(h.error_frames) + " error frames), ";
    detail += h.url;
    std::printf("  %-10s %-5s %-5s %9s %10lld %8lld %6d %8d %6d %6d %6d  %s\n", h.name.c_str(), h.connected ? "yes" : "NO",
                h.stale ? "YES" : "no", age.c_str(), static_cast<long long>(h.frames_ok),
                static_cast<long long>(h.frames_bad), h.crc_errors, h.counter_errors, h.length_errors, h.unknown_ids,
                h.reconnects, detail.c_str());
    if (!h.connected && !h.down_reason.empty()) std::printf("  %-10s down: %s\n", "", h.down_reason.c_str());
  }
  if (publishers.size() > 1) {
    std::printf("  DUPLICATE: %zu processes publish rise/%s/panel_state:\n", publishers.size(), p.trainee_id.c_str());
    for (const auto& q : publishers) std::printf("    %s\n", rise::msgs::describe(q, now).c_str());
  } else if (!publishers.empty()) {
    std::printf("  from     %s\n", rise::msgs::describe(publishers.front(), now).c_str());
  }
}

int run_status(const StatusOptions& o) {
  struct Latest {
    std::mutex m;
    rise_msgs::PanelState msg;
    bool fresh = false;  // a message since the last table
    std::map<int64_t, rise_msgs::Publisher> publishers;  // by session, since the last table
    void on(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::PanelState* p) {
      std::lock_guard lock(m);
      msg = *p;
      fresh = true;
      publishers[p->publisher.session_id] = p->publisher;
    }
  } latest;
  lcm::LCM lcm(o.lcm_url);
  if (!lcm.good()) {
    std::fprintf(stderr, "rise status: cannot open LCM at %s\n", o.lcm_url.c_str());
    return 2;
  }
  const std::string channel = rise::msgs::panel_state_channel(o.id);
  rise::msgs::subscribe<&Latest::on>(lcm, channel, &latest)->setQueueCapacity(200);
  const auto period = std::chrono::microseconds(static_cast<int64_t>(o.every_s * 1e6));
  auto last_message = std::chrono::steady_clock::now();
  bool last_fresh = false;
  for (int shown = 0; (o.count <= 0 || shown < o.count) && !g_stop; ++shown) {
    const auto until = std::chrono::steady_clock::now() + period;
    while (std::chrono::steady_clock::now() < until && !g_stop) lcm.handleTimeout(50);
    std::lock_guard lock(latest.m);
    last_fresh = latest.fresh;
    if (!latest.fresh) {
      const double quiet_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - last_message).count();
      std::printf("rise status: no PanelState on %s for %.1f s\n", channel.c_str(), quiet_s);
      std::fflush(stdout);
      if (o.timeout_s > 0 && quiet_s >= o.timeout_s) return 1;
      continue;
    }
    last_message = std::chrono::steady_clock::now();
    std::vector<rise_msgs::Publisher> publishers;
    for (const auto& [session, p] : latest.publishers) publishers.push_back(p);
    print_panel(latest.msg, publishers, rise::msgs::wall_us());
    std::fflush(stdout);
    latest.fresh = false;
    latest.publishers.clear();
  }
  // Nothing in the last table: the station is not there (exit 1).
  return g_stop || last_fresh ? 0 : 1;
}

int main(int argc, char** argv) {
  CLI::App app{"rise: the RISE console bridge and trainer"};
  app.require_subcommand(1);
  DemoOptions demo;
  CLI::App* d = app.add_subcommand(
      "demo", "run emulator → rise-hild → rise-sim as separate processes over socketcand and LCM "
              "multicast, play a scripted drive, print a summary");
  d->add_option("--id", demo.id, "station id in the channel names (default: the first free one of demo, demo-2, ...)");
  d->add_option("--lcm", demo.lcm_url, "LCM URL")->capture_default_str();
  d->add_option("--script", demo.script, "console timeline to play")->capture_default_str();
  d->add_option("--panel", demo.panel, "panel definition")->capture_default_str();
  d->add_option("--robot", demo.robot, "robot file for rise-sim")->capture_default_str();
  d->add_option("--port", demo.port, "socketcand TCP port (default: a free one)");
  d->add_option("--log-dir", demo.log_dir, "where the children's logs go (default /tmp/rise-demo-PID)");
  d->add_option("--timeout", demo.timeout_s, "give up after S seconds")->capture_default_str();
  d->add_flag("--view", demo.view,
              "also run rise-instructor serve (loopback, a free port, a fresh token) and print the trainee page's URL "
              "for the demo's robot; opens nothing");
  d->add_option("--record", demo.record_dir,
                "rise-hild records the session into DIR (rise-hild --record); replay it with "
                "`rise-hild verify --record-dir DIR`");
  TrainingDemoOptions training_demo;
  CLI::App* dt = d->add_subcommand(
      "training", "run the example training (Fig. 10 graph, taskMETRO) end to end with a scripted console: "
                  "rise-trainer train starts rise-sim per task; writes the reports");
  dt->add_option("--id", training_demo.id, "trainee id in the channel names")->capture_default_str();
  dt->add_option("--lcm", training_demo.lcm_url, "LCM URL")->capture_default_str();
  dt->add_option("--training", training_demo.training, "training file")->capture_default_str();
  dt->add_option("--out", training_demo.out_dir, "reports and journal (default /tmp/rise-training-demo-PID)");
  StatusOptions status;
  CLI::App* st = app.add_subcommand(
      "status", "show a station's panel: every control's value, the active faults, per-source health (and why a "
                "source is down), who publishes; exit 1 when no PanelState came in the last period");
  st->add_option("--id", status.id, "station id")->capture_default_str();
  st->add_option("--lcm", status.lcm_url, "LCM URL")->capture_default_str();
  st->add_option("--every", status.every_s, "refresh period in seconds")->capture_default_str()->check(CLI::Range(0.05, 3600.0));
  st->add_option("--count", status.count, "stop after N periods (0: until Ctrl-C or --timeout)")->capture_default_str();
  st->add_option("--timeout", status.timeout_s, "exit 1 when no PanelState came for S seconds (0: wait forever)")
      ->capture_default_str();
  if (const auto code = rise::cli::parse_command_line(app, "rise", argc, argv)) return *code;

  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  std::signal(SIGPIPE, SIG_IGN);  // a closed stdout must not skip stopping the children
  if (dt->parsed()) return run_training_demo(training_demo);
  if (d->parsed()) return run_demo(demo);
  if (st->parsed()) return run_status(status);
  return 1;
}
