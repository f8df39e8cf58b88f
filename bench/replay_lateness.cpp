// Real-time replay: lateness of each frame against the file's timestamps
// over a long replay (issue 4's figure: p99 < 0.5 ms, no drift), side by side
// with python-can's MessageSync (the playback python-can#1372 found drifting)
// replaying the same file for the same time in the same run (its own process,
// started together with ours, so each has a core).
//
// Lateness = the time a frame is handed out minus its due time, t0 + (ts -
// ts_first) / speed. Drift = mean lateness of the last 10 % of frames minus
// that of the first 10 %: a replay that accumulates timing error grows it.
//
// usage: bench_replay_lateness [LOG] [SECONDS]
//   default LOG: $RISE_TEST_DATA/can/ICSim/sample-can.log (3.3 s, looped), 60 s

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <numeric>
#include <string>
#include <vector>

#include "bench/bench_data.hpp"
#include "hil/io/can_url.hpp"
#include "hil/io/replay_bus.hpp"

namespace {

struct Figures {
  std::size_t frames = 0;
  double p50_us = 0, p99_us = 0, max_us = 0, drift_us = 0;
};

Figures figures(std::vector<double> late_us) {
  Figures f;
  f.frames = late_us.size();
  if (late_us.empty()) return f;
  const std::size_t tenth = std::max<std::size_t>(late_us.size() / 10, 1);
  const double first = std::accumulate(late_us.begin(), late_us.begin() + static_cast<std::ptrdiff_t>(tenth), 0.0);
  const double last = std::accumulate(late_us.end() - static_cast<std::ptrdiff_t>(tenth), late_us.end(), 0.0);
  f.drift_us = (last - first) / static_cast<double>(tenth);
  std::sort(late_us.begin(), late_us.end());
  const auto at = [&](double q) { return late_us[std::min(late_us.size() - 1, static_cast<std::size_t>(q * static_cast<double>(late_us.size())))]; };
  f.p50_us = at(0.50);
  f.p99_us = at(0.99);
  f.max_us = late_us.back();
  return f;
}

void print(const char* who, const Figures& f) {
  std::printf("%-22s %8zu frames  p50 %8.1f us  p99 %8.1f us  max %9.1f us  drift %+8.1f us\n", who, f.frames,
              f.p50_us, f.p99_us, f.max_us, f.drift_us);
}

}  // namespace

int main(int argc, char** argv) {
  const auto found = rise::bench::data_file(argc > 1 ? argv[1] : nullptr, "can/ICSim/sample-can.log");
  if (!found) return 2;
  const std::string& log = *found;
  const double seconds = argc > 2 ? std::atof(argv[2]) : 60.0;
  std::printf("real-time replay lateness, %.0f s of %s (looped), speed 1\n", seconds, log.c_str());

  // python-can: MessageSync over the file looped with shifted timestamps,
  // lateness measured the same way, inside its process.
  const std::string script =
      "import can, sys, time\n"
      "path, seconds, out = sys.argv[1], float(sys.argv[2]), sys.argv[3]\n"
      "msgs = list(can.LogReader(path))\n"
      "span = msgs[-1].timestamp - msgs[0].timestamp + (msgs[-1].timestamp - msgs[0].timestamp) / max(len(msgs) - 1, 1)\n"
      "def looped():\n"
      "    k = 0\n"
      "    while True:\n"
      "        for m in msgs:\n"
      "            t = m.timestamp + k * span\n"
      "            if t - msgs[0].timestamp > seconds: return\n"
      "            yield can.Message(timestamp=t, arbitration_id=m.arbitration_id, data=m.data)\n"
      "        k += 1\n"
      "first = msgs[0].timestamp\n"
      "t0 = None\n"
      "late = []\n"
      "for m in can.MessageSync(looped(), timestamps=True, gap=0.0):\n"
      "    now = time.perf_counter()\n"
      "    if t0 is None: t0 = now\n"
      "    late.append((now - t0 - (m.timestamp - first)) * 1e6)\n"
      "open(out, 'w').write('\\n'.join('%.1f' % v for v in late))\n";
  // Its figures go to a file, not a pipe: a full pipe would stall it.
  const std::string out = "/tmp/rise_bench_pycan_sync.txt";
  std::remove(out.c_str());
  // It runs beside ours from now on.
  FILE* p = rise::bench::start_python("rise_bench_pycan_sync", script,
                                      "'" + log + "' " + std::to_string(seconds) + " " + out + " 2>/dev/null");

  const std::string url = "replay://" + log + "?loop=-1";
  rise::hil::io::ReplayBus bus(url, std::get<rise::hil::io::ReplayAddress>(rise::hil::io::parse_can_url(url)));
  std::vector<double> ours;
  ours.reserve(static_cast<std::size_t>(seconds * 3000));
  rise::hil::io::CanFrame f;
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < end) {
    if (bus.receive(f, 100) != rise::hil::io::IoStatus::Ok) continue;
    ours.push_back(static_cast<double>(bus.last_lateness_us()));
  }
  print("rise replay://", figures(ours));

  std::vector<double> theirs;
  if (p) ::pclose(p);
  if (FILE* in = std::fopen(out.c_str(), "r")) {
    double v;
    while (std::fscanf(in, "%lf", &v) == 1) theirs.push_back(v);
    std::fclose(in);
  }
  if (theirs.empty())
    std::printf("python-can MessageSync not available (Debian python3-can for /usr/bin/python3)\n");
  else
    print("python-can MessageSync", figures(theirs));
  std::printf("goal: p99 < 500 us, no drift\n");
  return 0;
}
