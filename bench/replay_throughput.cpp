// Replay throughput as fast as possible on the largest shared CAN log, in
// frames/s, side by side with python-can reading the same file in the same
// run (issue 4's figure; goal ≥ 50×).
//
// Ours: replay://FILE?fast=1&loop=N, i.e. the whole transport the daemon
// reads (parse, filter, deliver through CanBus::receive). python-can:
// can.LogReader over the same file N+1 times (parse and build can.Message),
// timed inside the Python process, so interpreter start-up is not counted.
//
// usage: bench_replay_throughput [LOG] [PASSES]
//   default LOG: $RISE_TEST_DATA/can/ICSim/sample-can.log (6158 frames)

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "bench/bench_data.hpp"
#include "hil/io/can_bus.hpp"

int main(int argc, char** argv) {
  const auto found = rise::bench::data_file(argc > 1 ? argv[1] : nullptr, "can/ICSim/sample-can.log");
  if (!found) return 2;
  const std::string& log = *found;
  const int passes = argc > 2 ? std::atoi(argv[2]) : 200;
  std::printf("replay throughput, %d passes over %s\n", passes, log.c_str());

  auto bus = rise::hil::io::open_can_bus("replay://" + log + "?fast=1&loop=" + std::to_string(passes - 1));
  rise::hil::io::CanFrame f;
  long long frames = 0, checksum = 0;
  const auto t0 = std::chrono::steady_clock::now();
  while (bus->receive(f, 0) == rise::hil::io::IoStatus::Ok) {
    ++frames;
    checksum += f.data[0];
  }
  const double ours_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double ours_fps = static_cast<double>(frames) / ours_s;
  std::printf("rise replay://   %10lld frames in %.3f s = %12.0f frames/s (checksum %lld)\n", frames, ours_s, ours_fps,
              checksum);

  const std::string script =
      "import can, sys, time\n"
      "path, passes = sys.argv[1], int(sys.argv[2])\n"
      "t0 = time.perf_counter(); n = 0\n"
      "for _ in range(passes):\n"
      "    for m in can.LogReader(path):\n"
      "        n += 1\n"
      "dt = time.perf_counter() - t0\n"
      "print(n, dt)\n";
  FILE* p = rise::bench::start_python("rise_bench_pycan", script, "'" + log + "' " + std::to_string(passes));
  long long py_frames = 0;
  double py_s = 0;
  if (!p || std::fscanf(p, "%lld %lf", &py_frames, &py_s) != 2 || py_s <= 0) {
    std::printf("python-can       not available (Debian python3-can for /usr/bin/python3)\n");
    if (p) ::pclose(p);
    return 0;
  }
  ::pclose(p);
  const double py_fps = static_cast<double>(py_frames) / py_s;
  std::printf("python-can 4.1   %10lld frames in %.3f s = %12.0f frames/s\n", py_frames, py_s, py_fps);
  std::printf("ratio            %.1f x   (goal >= 50 x)\n", ours_fps / py_fps);
  if (py_frames != frames) std::printf("note: frame counts differ (%lld vs %lld)\n", frames, py_frames);
  return 0;
}
