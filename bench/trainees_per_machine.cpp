// How many trainees one machine holds at real time: for 1, 2, 4, 8, ...
// trainee stations — each a real-time paced rise-sim (tracked EOD robot,
// building world) plus a rise-trainer run-task executor whose scripted
// console drives it in circles — started at once on one LCM network (udpm,
// ttl=0, a port of its own), the real-time factor of every sim is its sim
// time advance over the wall time between two RobotStates ~8 s apart. A
// station "holds" when every sim keeps a factor >= 0.99 (rise-sim paces to
// 1.0). Prints the table and the answer: doubling until a level fails,
// then bisecting between the last level that held and that one.
//
// Usage: bench_trainees_per_machine [max_trainees=16] [window_s=8]

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
#include <memory>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "process/child_process.hpp"
#include "rise_msgs/RobotState.hpp"
#include "msgs/lcm_decode.hpp"

namespace {

using Clock = std::chrono::steady_clock;

struct Seen {
  double sim_s = 0;
  Clock::time_point wall{};
  bool any = false;
};

struct Listener {
  std::map<std::string, Seen> latest;
  void on(const lcm::ReceiveBuffer*, const std::string& ch, const rise_msgs::RobotState* m) {
    auto& s = latest[ch];
    s.sim_s = m->sim_time_s;
    s.wall = Clock::now();
    s.any = true;
  }
};

double load_average() {
  std::ifstream in("/proc/loadavg");
  double l = 0;
  in >> l;
  return l;
}

struct Level {
  int trainees = 0;
  int heard = 0;  // sims whose RobotState came in both at the window's start and end
  double min_factor = 0, mean_factor = 0, load = 0;
  bool holds = false;
};

}  // namespace

int main(int argc, char** argv) {
  const int max_trainees = argc > 1 ? std::atoi(argv[1]) : 16;
  const double window_s = argc > 2 ? std::atof(argv[2]) : 8.0;
  const std::string bin = std::string(RISE_BINARY_DIR) + "/bin/";
  const std::string src = RISE_SOURCE_DIR;
  const std::string lcm_url = "udpm://239.255.76.67:" + std::to_string(8300 + ::getpid() % 300) + "?ttl=0";
  const auto dir = std::filesystem::temp_directory_path() / ("rise-bench-trainees-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  // The trainee's task: drive in circles in room A for as long as the bench runs.
  {
    std::ofstream(dir / "circles.txt") << "0.0 mode drive\n0.0 speed medium\n0.2 deadman pressed\n0.5 drive_y 0.6\n0.5 drive_x 0.4\n";
    std::ofstream(dir / "circles.yaml")
        << "task: circles\nrobot: " << src << "/sim/robots/tracked_eod.yaml\nworld: " << src
        << "/sim/worlds/building.yaml\npanel: " << src << "/panels/definitions/rise_console.yaml\n"
        << "console_script: " << (dir / "circles.txt").string() << "\ntime_limit_s: 100000\nevents:\n"
        << "  - {name: area, kind: reach_region, region: neutralization_area, points: 1}\n"
        << "  - {name: bump, kind: collision, per: second, points: -1}\n";
  }
  lcm::LCM lcm(lcm_url);
  if (!lcm.good()) {
    std::fprintf(stderr, "cannot open LCM at %s\n", lcm_url.c_str());
    return 2;
  }
  Listener listener;
  rise::msgs::subscribe<&Listener::on>(lcm, "rise/bench[0-9]+/robot_state", &listener)->setQueueCapacity(5000);
  std::printf("trainees per machine: %u cores (std::thread::hardware_concurrency), LCM %s, window %.0f s\n",
              std::thread::hardware_concurrency(), lcm_url.c_str(), window_s);
  std::printf("each trainee: rise-sim (real-time paced, tracked_eod, building) + rise-trainer run-task (executor + scripted console)\n\n");
  std::printf("%9s %7s %12s %12s %10s %7s\n", "trainees", "heard", "min factor", "mean factor", "load avg", "holds");
  std::vector<Level> levels;
  // Doubling until a level fails, then halving the gap between the last
  // level that held and the first that failed (to within 2).
  int held = 0, failed = 0;
  for (int n = 1; n > 0 && n <= max_trainees;) {
    std::vector<rise::process::ChildProcess> children;
    listener.latest.clear();
    for (int i = 0; i < n; ++i) {
      const std::string id = "bench" + std::to_string(i);
      children.emplace_back(std::vector<std::string>{bin + "rise-sim", "--id", id, "--lcm", lcm_url, "--robot",
                                                     src + "/sim/robots/tracked_eod.yaml", "--world",
                                                     src + "/sim/worlds/building.yaml", "--log-level", "warn"},
                            (dir / (id + ".sim.log")).string());
      children.emplace_back(std::vector<std::string>{bin + "rise-trainer", "--log-level", "warn", "run-task",
                                                     (dir / "circles.yaml").string(), "--id", id, "--lcm", lcm_url,
                                                     "--out", dir.string(), "--scripted-console"},
                            (dir / (id + ".trainer.log")).string());
    }
    // Every sim heard, then one second to settle, then the window.
    const auto give_up = Clock::now() + std::chrono::seconds(30);
    while (Clock::now() < give_up && static_cast<int>(listener.latest.size()) < n) lcm.handleTimeout(50);
    const auto settle = Clock::now() + std::chrono::seconds(1);
    while (Clock::now() < settle) lcm.handleTimeout(50);
    const auto first = listener.latest;
    const auto end = Clock::now() + std::chrono::duration<double>(window_s);
    while (Clock::now() < end) lcm.handleTimeout(50);
    Level level{n, 0, 1e9, 0, load_average(), false};
    int measured = 0;
    for (const auto& [ch, s] : listener.latest) {
      const auto it = first.find(ch);
      if (it == first.end()) continue;
      const double wall = std::chrono::duration<double>(s.wall - it->second.wall).count();
      const double factor = wall > 0 ? (s.sim_s - it->second.sim_s) / wall : 0;
      level.min_factor = std::min(level.min_factor, factor);
      level.mean_factor += factor;
      ++measured;
    }
    level.heard = measured;
    if (measured == 0) level.min_factor = 0;
    level.mean_factor = measured ? level.mean_factor / measured : 0;
    level.holds = measured == n && level.min_factor >= 0.99;
    std::printf("%9d %7d %12.3f %12.3f %10.2f %7s\n", n, level.heard, level.min_factor, level.mean_factor, level.load,
                level.holds ? "yes" : "no");
    std::fflush(stdout);
    for (auto& c : children) c.signal(SIGTERM);
    for (auto& c : children) c.stop(2000);
    // The stopped sims' last states must not count in the next level.
    while (lcm.handleTimeout(0) > 0) {
    }
    levels.push_back(level);
    if (level.holds) held = n;
    else failed = n;
    if (!failed) n *= 2;
    else n = failed - held > 2 ? (held + failed) / 2 : 0;
  }
  std::printf("\nanswer: this machine holds %d trainee(s) at real time (every sim's real-time factor >= 0.99)%s\n", held,
              failed ? "" : " — the largest level tried");
  std::filesystem::remove_all(dir);
  return 0;
}
