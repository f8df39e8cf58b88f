// The whole chain for a long time under faults (issue 19): the split
// console's two boards emulated on real transports on loopback (sticks on
// CAN through socketcand, buttons on Modbus/TCP; rise-panel emulate) →
// rise-hild → rise-sim (tracked EOD robot, building world) → rise-trainer
// run-task (scoring a drive in circles), with rise-instructor scenario
// injecting every fault kind, in a seeded random order at seeded times, and
// the boards killed (SIGKILL) and restarted now and then: a lost device.
// rise-hild reads the boards in real time, so the chain runs at a real-time
// factor of 1 (rise-sim paces to it): a simulated hour takes an hour.
//
// Measured, and printed as tables: RSS and open file descriptors of every
// process each second; PanelStates lost (gaps in seq; those next to an
// lcm_loss fault, which drops them on purpose, counted apart); RobotStates
// lost (gaps in sim time); PanelStates not failsafe while a board was down
// (from the kill + the board's timeout + two publish periods + 20 ms to its
// restart) or while the PanelState's own SourceHealth said a source was
// stale or disconnected (both must be 0); the time from each fault's end
// (its id gone from PanelState/RobotState.active_faults) to a healthy chain
// (PanelState not failsafe, every source connected and fresh, no fault
// active), for faults that ended with no other fault or down board.
// Exit 1 when a bound below is broken or a process died; 2 on bad usage.
//
// Usage: bench_soak [--minutes M (60)] [--seed N (1)] [--keep]
// (bench/soak runs the full hour; ctest's soak_2min runs two minutes.)

#include <lcm/lcm-cpp.hpp>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "instructor/scenario.hpp"
#include "msgs/channels.hpp"
#include "msgs/lcm_decode.hpp"
#include "process/child_process.hpp"
#include "rise_msgs/PanelState.hpp"
#include "rise_msgs/RobotState.hpp"

namespace fs = std::filesystem;
using rise::process::ChildProcess;

namespace {

// The bounds (README "Reliability"): growth from the warm baseline (the
// median over 20..30 % of the run) to the end (the median over its last
// 10 %) of each process that runs throughout.
constexpr double kRssGrowthMb = 8.0;        // plus ...
constexpr double kRssGrowthFraction = 0.10;  // ... of the baseline
constexpr double kFdGrowth = 2.0;
constexpr double kLostFraction = 0.001;  // PanelStates / RobotStates lost outside lcm_loss
constexpr double kRecoveryBoundMs = 2000;

double wall_s() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

// ------------------------------------------------------------- faults ----

struct KindSpec {
  const char* kind;
  const char* target;
  double value, rate;
};

// Every fault kind with a target of this chain and a parameter that bites.
const std::vector<KindSpec>& kind_specs() {
  static const std::vector<KindSpec> specs = {
      {"stuck_at", "drive_y", 0.3, 0},        {"offset", "drive_x", 0.2, 0},
      {"drift", "drive_x", 0, 0.05},          {"noise", "drive_y", 0.05, 0},
      {"out_of_range", "drive_y", 0, 0},      {"intermittent", "drive_x", 0.5, 0.1},
      {"disconnect", "drive_y", 0, 0},        {"can_drop", "sticks", 1.0, 0},
      {"can_delay", "sticks", 0, 30},         {"can_corrupt", "sticks", 0.2, 0},
      {"can_bus_off", "sticks", 0, 0},        {"modbus_exception", "buttons", 0.5, 4},
      {"modbus_timeout", "buttons", 0.5, 0},  {"lcm_loss", "panel_state", 0.2, 0},
      {"lcm_latency", "panel_state", 0, 80},  {"motor_failure", "left", 0, 0},
      {"motor_weakness", "right", 0.5, 0},    {"track_slip", "left", 0.2, 0},
      {"weak_joint", "shoulder_pitch", 0.3, 0}, {"camera_blackout", "front", 0, 0},
      {"scanner_noise", "laser", 0.05, 0},    {"scanner_dropout", "laser", 0.5, 0}};
  return specs;
}

// A fault scenario: one fault per slot, the kinds in a seeded shuffle per
// round so that each round has every kind, each at a seeded time and for a
// seeded duration inside its slot. Returns the number of faults.
int write_scenario(const fs::path& file, double total_s, double slot_s, uint64_t seed,
                   std::map<std::string, std::string>& kinds) {
  std::mt19937_64 rng(seed);
  std::vector<KindSpec> order;
  std::ofstream out(file);
  out << "scenario: soak\nseed: " << seed << "\nfaults:\n";
  int n = 0;
  for (double start = 2.0; start + slot_s <= total_s - 2.0; start += slot_s, ++n) {
    if (order.empty()) {
      order = kind_specs();
      std::shuffle(order.begin(), order.end(), rng);
    }
    const KindSpec k = order.back();
    order.pop_back();
    const double duration = std::uniform_real_distribution<double>(1.0, slot_s * 0.45)(rng);
    const double at = start + std::uniform_real_distribution<double>(0.0, slot_s * 0.45)(rng);
    kinds["soak-" + std::to_string(n)] = k.kind;
    out << "  - {id: soak-" << n << ", kind: " << k.kind << ", target: " << k.target << ", value: " << k.value
        << ", rate: " << k.rate << ", at: " << at << ", duration: " << duration << "}\n";
  }
  return n;
}

// ---------------------------------------------------------- processes ----

struct Sample {
  double t = 0;
  double rss_mb = 0;
  double fds = 0;
};

struct Proc {
  std::string name;
  std::vector<std::string> argv;
  std::string log;
  bool throughout = true;  // measured for growth (the boards are restarted)
  ChildProcess child;
  std::vector<Sample> samples;
  int restarts = 0;
  bool died = false, done = false;

  void start() { child = ChildProcess(argv, log); }
  void sample(double t) {
    if (!child.running()) return;
    Sample s{t, 0, 0};
    std::ifstream status("/proc/" + std::to_string(child.pid()) + "/status");
    for (std::string line; std::getline(status, line);)
      if (line.rfind("VmRSS:", 0) == 0) s.rss_mb = std::atof(line.c_str() + 6) / 1024.0;
    std::error_code ec;
    for (fs::directory_iterator it("/proc/" + std::to_string(child.pid()) + "/fd", ec), end; !ec && it != end;
         it.increment(ec))
      ++s.fds;
    samples.push_back(s);
  }
};

double median_in(const std::vector<Sample>& s, double from, double to, double Sample::*field) {
  std::vector<double> v;
  for (const auto& x : s)
    if (x.t >= from && x.t <= to) v.push_back(x.*field);
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// ------------------------------------------------------------ watching ----

struct Down {
  std::string source;
  double from = 0, to = 1e300;  // unsafe from (kill + grace) to the restart
};

struct Pending {
  std::string id, kind;
  double ended = 0;
  bool spoiled = false;  // another fault or a down board came while it recovered
};

struct Recovery {
  std::string kind;
  double ms = 0;
};

struct Watch {
  std::map<std::string, std::string> kinds;  // fault id → kind
  std::vector<Down> downs;
  // PanelState
  int64_t session = 0, last_seq = -1;
  bool last_lcm_loss = false;
  uint64_t panels = 0, panel_lost = 0, panel_lost_lcm_loss = 0;
  uint64_t unsafe_down = 0, unsafe_health = 0;
  std::set<std::string> panel_faults, robot_faults;
  bool healthy = false;
  // RobotState
  double last_sim = -1;
  uint64_t robots = 0, robot_lost = 0;
  // Recoveries
  std::vector<Pending> pending;
  std::vector<Recovery> recoveries;
  int spoiled = 0;

  static std::set<std::string> soak_faults(const std::vector<std::string>& active) {
    std::set<std::string> ids;
    for (const auto& a : active)
      if (a.rfind("soak-", 0) == 0) ids.insert(a.substr(0, a.find(':')));
    return ids;
  }

  bool board_down(double t) const {
    for (const auto& d : downs)
      if (t >= d.from - 1.0 && t <= d.to + 1.0) return true;
    return false;
  }

  // Faults gone from `before` to `after` start recovering at t.
  void update_faults(std::set<std::string>& held, std::set<std::string> now, double t) {
    for (const auto& id : held)
      if (!now.count(id)) {
        for (auto& p : pending) p.spoiled = true;  // another fault ended while they recovered
        pending.push_back({id, kinds[id], t, false});
      }
    for (const auto& id : now)
      if (!held.count(id))
        for (auto& p : pending) p.spoiled = true;
    held = std::move(now);
  }

  void settle(double t) {
    if (!healthy || !panel_faults.empty() || !robot_faults.empty()) return;
    for (const auto& p : pending) {
      if (p.spoiled || board_down(p.ended)) {
        ++spoiled;
        continue;
      }
      recoveries.push_back({p.kind, (t - p.ended) * 1000.0});
    }
    pending.clear();
  }

  void on_panel(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::PanelState* m) {
    const double t = static_cast<double>(m->utime) * 1e-6;
    ++panels;
    bool lcm_loss = false;
    for (const auto& a : m->active_faults) lcm_loss |= a.find(": lcm_loss") != std::string::npos;
    if (m->publisher.session_id == session && m->seq > last_seq + 1) {
      const auto gap = static_cast<uint64_t>(m->seq - last_seq - 1);
      ((lcm_loss || last_lcm_loss) ? panel_lost_lcm_loss : panel_lost) += gap;
    }
    session = m->publisher.session_id, last_seq = m->seq, last_lcm_loss = lcm_loss;
    bool sources_ok = true;
    for (const auto& s : m->sources) sources_ok &= s.connected && !s.stale;
    if (!sources_ok && !m->failsafe) ++unsafe_health;
    for (const auto& d : downs)
      if (t >= d.from && t <= d.to && !m->failsafe) ++unsafe_down;
    update_faults(panel_faults, soak_faults(m->active_faults), t);
    healthy = sources_ok && !m->failsafe;
    if (board_down(t))
      for (auto& p : pending) p.spoiled = true;
    settle(t);
  }

  void on_robot(const lcm::ReceiveBuffer*, const std::string&, const rise_msgs::RobotState* m) {
    ++robots;
    if (last_sim >= 0 && m->sim_time_s - last_sim > 1.5 / 50.0)
      robot_lost += static_cast<uint64_t>((m->sim_time_s - last_sim) * 50.0 + 0.5) - 1;
    last_sim = m->sim_time_s;
    update_faults(robot_faults, soak_faults(m->active_faults), static_cast<double>(m->utime) * 1e-6);
  }
};

// ------------------------------------------------------------- report ----

struct Options {
  double minutes = 60;
  uint64_t seed = 1;
  bool keep = false;
};

bool parse(int argc, char** argv, Options& o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--keep") {
      o.keep = true;
    } else if (a == "--minutes" && i + 1 < argc) {
      o.minutes = std::atof(argv[++i]);
    } else if (a == "--seed" && i + 1 < argc) {
      o.seed = std::strtoull(argv[++i], nullptr, 10);
    } else {
      return false;
    }
  }
  return o.minutes > 0.2;
}

// Prints the process table; false when one grew beyond the bounds or died.
bool report_processes(const std::vector<Proc*>& procs, double total_s) {
  bool ok = true;
  std::printf("\n%-22s %9s %22s %14s %9s %s\n", "process", "peak MB", "RSS warm -> end MB", "fds warm->end",
              "restarts", "verdict");
  for (const Proc* p : procs) {
    double peak = 0;
    for (const auto& s : p->samples) peak = std::max(peak, s.rss_mb);
    const double rss0 = median_in(p->samples, 0.2 * total_s, 0.3 * total_s, &Sample::rss_mb);
    const double rss1 = median_in(p->samples, 0.9 * total_s, total_s + 5, &Sample::rss_mb);
    const double fd0 = median_in(p->samples, 0.2 * total_s, 0.3 * total_s, &Sample::fds);
    const double fd1 = median_in(p->samples, 0.9 * total_s, total_s + 5, &Sample::fds);
    const bool grew = p->throughout && (rss1 - rss0 > kRssGrowthMb + kRssGrowthFraction * rss0 || fd1 - fd0 > kFdGrowth);
    const bool bad = grew || p->died;
    ok = ok && !bad;
    std::printf("%-22s %9.1f %10.1f -> %-9.1f %6.0f -> %-5.0f %9d %s\n", p->name.c_str(), peak, rss0, rss1, fd0, fd1,
                p->restarts, p->died ? "DIED" : grew ? "GREW" : p->throughout ? "ok" : "ok (restarted: peak only)");
  }
  return ok;
}

bool report_chain(const Watch& w) {
  std::printf("\nPanelStates: %llu received, %llu lost (%.4f %%), %llu more lost next to an lcm_loss fault (on purpose)\n",
              static_cast<unsigned long long>(w.panels), static_cast<unsigned long long>(w.panel_lost),
              w.panels ? 100.0 * static_cast<double>(w.panel_lost) / static_cast<double>(w.panels) : 0.0,
              static_cast<unsigned long long>(w.panel_lost_lcm_loss));
  std::printf("RobotStates: %llu received, %llu lost (%.4f %%)\n", static_cast<unsigned long long>(w.robots),
              static_cast<unsigned long long>(w.robot_lost),
              w.robots ? 100.0 * static_cast<double>(w.robot_lost) / static_cast<double>(w.robots) : 0.0);
  std::printf("PanelStates not failsafe while a board was down: %llu; while their own SourceHealth said stale or "
              "disconnected: %llu (both must be 0)\n",
              static_cast<unsigned long long>(w.unsafe_down), static_cast<unsigned long long>(w.unsafe_health));
  std::map<std::string, std::vector<double>> by_kind;
  for (const auto& r : w.recoveries) by_kind[r.kind].push_back(r.ms);
  std::printf("\n%-18s %6s %14s %12s\n", "fault kind", "ended", "median rec. ms", "max rec. ms");
  double worst = 0;
  for (auto& [kind, v] : by_kind) {
    std::sort(v.begin(), v.end());
    worst = std::max(worst, v.back());
    std::printf("%-18s %6zu %14.0f %12.0f\n", kind.c_str(), v.size(), v[v.size() / 2], v.back());
  }
  std::printf("(%zu recoveries measured; %d not, overlapping another fault or a down board)\n", w.recoveries.size(),
              w.spoiled);
  const bool lost_ok = static_cast<double>(w.panel_lost) <= kLostFraction * static_cast<double>(w.panels) &&
                       static_cast<double>(w.robot_lost) <= kLostFraction * static_cast<double>(w.robots);
  return lost_ok && w.unsafe_down == 0 && w.unsafe_health == 0 && worst <= kRecoveryBoundMs && w.panels > 0 &&
         w.robots > 0;
}


// ---------------------------------------------------------------- run ----

struct Chain {
  std::string id, lcm_url;
  fs::path dir;
  std::vector<Proc> procs;  // sticks, buttons, hild, sim, trainer, scenario
  Proc& at(const std::string& name) {
    for (auto& p : procs)
      if (p.name == name) return p;
    throw std::logic_error(name);
  }
};

// The files the chain reads: the instructor key, the boards' timeline (a
// drive in circles, the dead-man held), the trainer's task.
void write_files(const Chain& c) {
  const std::string src = RISE_SOURCE_DIR;
  ChildProcess keygen({std::string(RISE_BINARY_DIR) + "/bin/rise-instructor", "keygen", (c.dir / "key").string()},
                      (c.dir / "keygen.log").string());
  keygen.wait_for(10000);
  std::ofstream(c.dir / "circles.txt") << "0.0 mode drive\n0.0 speed medium\n0.2 deadman pressed\n0.5 drive_y 0.5\n"
                                          "0.5 drive_x 0.3\n8.0 drive_x -0.3\n16.0 drive_x -0.3\n";
  std::ofstream(c.dir / "circles.yaml")
      << "task: circles\nrobot: " << src << "/sim/robots/tracked_eod.yaml\nworld: " << src
      << "/sim/worlds/building.yaml\npanel: " << src << "/panels/definitions/rise_console_split.yaml\n"
      << "time_limit_s: 1000000\nevents:\n"
      << "  - {name: area, kind: reach_region, region: neutralization_area, points: 1}\n"
      << "  - {name: bump, kind: collision, per: second, points: -1}\n";
}

Chain make_chain(double total_s) {
  Chain c;
  const int pid = static_cast<int>(::getpid());
  c.id = "soak" + std::to_string(pid);
  c.lcm_url = "udpm://239.255.76.67:" + std::to_string(8600 + pid % 300) + "?ttl=0";
  c.dir = fs::temp_directory_path() / ("rise-soak-" + std::to_string(pid));
  fs::create_directories(c.dir);
  write_files(c);
  const std::string bin = std::string(RISE_BINARY_DIR) + "/bin/", src = RISE_SOURCE_DIR;
  const std::string panel = src + "/panels/definitions/rise_console_split.yaml", key = (c.dir / "key").string();
  const std::string can = "127.0.0.1:" + std::to_string(20000 + pid % 20000) + "/can0";
  const std::string modbus = "127.0.0.1:" + std::to_string(20000 + pid % 20000 + 1) + "?unit=1";
  const std::string script = (c.dir / "circles.txt").string();
  const auto add = [&](const std::string& name, std::vector<std::string> argv, bool throughout) {
    c.procs.push_back(Proc{name, std::move(argv), (c.dir / (name + ".log")).string(), throughout, {}, {}, 0, false, false});
  };
  add("rise-panel (sticks)", {bin + "rise-panel", "emulate", "--panel", panel, "--source", "sticks", "--can",
                              "socketcand+listen://" + can, "--script", script, "--loop"}, false);
  add("rise-panel (buttons)", {bin + "rise-panel", "emulate", "--panel", panel, "--source", "buttons", "--modbus",
                               "modbus+tcp-listen://" + modbus, "--script", script, "--loop"}, false);
  add("rise-hild", {bin + "rise-hild", "--panel", panel, "--source", "socketcand://" + can, "--source",
                    "modbus+tcp://" + modbus, "--id", c.id, "--lcm", c.lcm_url, "--instructor-key", key,
                    "--log-level", "warn"}, true);
  add("rise-sim", {bin + "rise-sim", "--id", c.id, "--lcm", c.lcm_url, "--robot", src + "/sim/robots/tracked_eod.yaml",
                   "--world", src + "/sim/worlds/building.yaml", "--instructor-key", key, "--log-level", "warn"}, true);
  add("rise-trainer", {bin + "rise-trainer", "--log-level", "warn", "run-task", (c.dir / "circles.yaml").string(),
                       "--id", c.id, "--lcm", c.lcm_url, "--out", c.dir.string()}, true);
  add("rise-instructor", {bin + "rise-instructor", "scenario", (c.dir / "scenario.yaml").string(), "--trainee", c.id,
                          "--duration", std::to_string(total_s), "--instructor-key", key, "--lcm", c.lcm_url}, true);
  return c;
}

// Kills one board (SIGKILL) every `every` seconds, alternately, and starts
// it again 3 s later; the Watch learns when PanelStates must be failsafe.
struct BoardKiller {
  double every = 0, next = 0, restart_at = -1;
  int turn = 0, losses = 0;
  Proc* down = nullptr;
  void tick(double t, Chain& c, Watch& w) {
    if (down && t >= restart_at) {
      w.downs.back().to = wall_s();
      down->start();
      ++down->restarts;
      down = nullptr;
    }
    if (!down && t >= next) {
      down = &c.procs[static_cast<size_t>(turn % 2)];
      const double grace = (turn % 2 == 0 ? 0.050 : 0.100) + 2 * 0.010 + 0.020;  // timeout_ms, 2 periods, slack
      down->child.signal(SIGKILL);
      down->child.wait_for(2000);
      w.downs.push_back({turn % 2 == 0 ? "sticks" : "buttons", wall_s() + grace, 1e300});
      restart_at = t + 3.0, next += every, ++turn, ++losses;
    }
  }
};

bool chain_up(lcm::LCM& lcm, const Watch& w, double timeout_s) {
  const double end = wall_s() + timeout_s;
  while (wall_s() < end) {
    lcm.handleTimeout(50);
    if (w.healthy && w.robots > 0) return true;
  }
  return false;
}

int run(const Options& o) {
  const double total_s = o.minutes * 60.0;
  Chain c = make_chain(total_s);
  Watch w;
  const int faults = write_scenario(c.dir / "scenario.yaml", total_s, total_s <= 600 ? 5.0 : 10.0, o.seed, w.kinds);
  lcm::LCM lcm(c.lcm_url);
  if (!lcm.good()) return std::fprintf(stderr, "bench_soak: cannot open LCM at %s\n", c.lcm_url.c_str()), 2;
  rise::msgs::subscribe<&Watch::on_panel>(lcm, rise::msgs::panel_state_channel(c.id), &w)->setQueueCapacity(100000);
  rise::msgs::subscribe<&Watch::on_robot>(lcm, rise::msgs::robot_state_channel(c.id), &w)->setQueueCapacity(100000);
  for (size_t i = 0; i + 1 < c.procs.size(); ++i) c.procs[i].start();
  if (!chain_up(lcm, w, 60.0)) {
    std::fprintf(stderr, "bench_soak: the chain did not come up in 60 s (logs in %s)\n", c.dir.c_str());
    return 1;
  }
  c.at("rise-instructor").start();
  std::printf("soak: %.1f min at real time (rise-hild reads the boards live), seed %llu, %d faults over %zu kinds, "
              "LCM %s, logs in %s\n", o.minutes, static_cast<unsigned long long>(o.seed), faults, kind_specs().size(),
              c.lcm_url.c_str(), c.dir.c_str());
  BoardKiller killer{total_s <= 600 ? total_s / 3.0 : 300.0, total_s <= 600 ? total_s / 3.0 : 300.0};
  const double t0 = wall_s();
  const double first_sim = w.last_sim;
  for (double next_sample = 0, t = 0; t < total_s; t = wall_s() - t0) {
    lcm.handleTimeout(20);
    killer.tick(t, c, w);
    if (t < next_sample) continue;
    next_sample += 1.0;
    for (auto& p : c.procs) {
      p.sample(t);
      if (&p == killer.down || p.died || p.done || p.child.running()) continue;
      // The scenario runner ends with exit 0 once its last fault is done.
      const int code = p.child.wait_for(0);
      (p.name == "rise-instructor" && code == 0 ? p.done : p.died) = true;
      std::printf("%.1f s: %s exited with %d (log %s)\n", t, p.name.c_str(), code, p.log.c_str());
    }
  }
  const double simulated_s = w.last_sim - first_sim;
  for (auto it = c.procs.rbegin(); it != c.procs.rend(); ++it) it->child.stop(5000);
  std::printf("simulated %.1f min; %d board losses (SIGKILL, 3 s down)\n", simulated_s / 60.0, killer.losses);
  std::vector<Proc*> procs;
  for (auto& p : c.procs) procs.push_back(&p);
  const bool procs_ok = report_processes(procs, total_s);
  const bool chain_ok = report_chain(w);
  const bool ok = procs_ok && chain_ok && killer.losses > 0;
  std::printf("\nbounds: RSS growth <= %.0f MB + %.0f %%, fds growth <= %.0f, lost <= %.1f %%, recovery <= %.0f ms, "
              "0 unsafe PanelStates: %s\n", kRssGrowthMb, kRssGrowthFraction * 100, kFdGrowth, kLostFraction * 100,
              kRecoveryBoundMs, ok ? "PASS" : "FAIL");
  if (ok && !o.keep) fs::remove_all(c.dir);
  return ok ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (!parse(argc, argv, o)) {
    std::fprintf(stderr, "usage: bench_soak [--minutes M (60, > 0.2)] [--seed N (1)] [--keep]\n");
    return 2;
  }
  // Every fault kind the instructor knows must be in the soak.
  for (const auto& k : rise::instructor::fault_kinds())
    if (std::none_of(kind_specs().begin(), kind_specs().end(), [&](const KindSpec& s) { return k == s.kind; })) {
      std::fprintf(stderr, "bench_soak: fault kind '%s' has no target here\n", k.c_str());
      return 2;
    }
  return run(o);
}
