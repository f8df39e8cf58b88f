// libFuzzer target: the LCM messages anyone on the classroom's multicast
// group can send, as the instructor receives them: the first byte picks the
// channel (rise/t1/panel_state, robot_state, task_status, panel_feedback,
// sim_event, task_event, sound; or the bytes are a channel name), the rest
// is the packet. TraineeDirectory takes it or counts it malformed; what
// decodes (msgs::decode_message, lcm-gen's code with msgs/lcm_gen.sh's
// checks) encodes to bytes that decode and encode to the same again, and
// becomes the JSON the web console pushes (instructor/web_json.hpp), which
// must parse back as a JSON object. Seeds (each type encoded by lcm-gen's
// code) are written into the corpus folder at start.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "instructor/trainee_directory.hpp"
#include "instructor/web_json.hpp"
#include "msgs/channels.hpp"
#include "msgs/lcm_decode.hpp"
#include "tests/fuzz/fuzz_check.hpp"

namespace ins = rise::instructor;
namespace m = rise::msgs;

namespace {

template <typename Message>
std::vector<uint8_t> encoded(const Message& msg) {
  std::vector<uint8_t> bytes(static_cast<std::size_t>(msg.getEncodedSize()));
  fuzz_check(msg.encode(bytes.data(), 0, static_cast<int>(bytes.size())) == static_cast<int>(bytes.size()));
  return bytes;
}

// The JSON the page parses.
void check_json(const Json::Value& v) {
  const std::string text = ins::json_text(v);
  Json::CharReaderBuilder b;
  const std::unique_ptr<Json::CharReader> reader(b.newCharReader());
  Json::Value back;
  std::string errors;
  fuzz_check(reader->parse(text.data(), text.data() + text.size(), &back, &errors) && back.isObject());
}

template <typename Message, typename ToJson>
void decode(const uint8_t* data, std::size_t size, ToJson to_json) {
  Message msg;
  if (!m::decode_message(data, static_cast<int64_t>(size), msg)) return;
  const std::vector<uint8_t> once = encoded(msg);
  Message again;
  fuzz_check(m::decode_message(once.data(), static_cast<int64_t>(once.size()), again));
  fuzz_check(encoded(again) == once);
  check_json(to_json(msg));
}

constexpr const char* kKinds[] = {"panel_state", "robot_state", "task_status", "panel_feedback",
                                  "sim_event",   "task_event",  "sound"};

template <typename Message>
void write_seed(const std::string& path, uint8_t kind, const Message& msg) {
  std::vector<uint8_t> bytes = encoded(msg);
  bytes.insert(bytes.begin(), kind);
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()),
                                              static_cast<std::streamsize>(bytes.size()));
}

void write_seeds(const std::string& dir) {
  rise_msgs::PanelState panel{};
  panel.panel_id = "rise_console", panel.num_axes = 1, panel.axes.resize(1), panel.axes[0].name = "drive_y";
  panel.axes[0].value = 0.5f, panel.num_buttons = 1, panel.buttons.resize(1), panel.buttons[0].name = "deadman";
  panel.num_switches = 1, panel.switches.resize(1), panel.switches[0].name = "mode", panel.switches[0].label = "drive";
  panel.num_faults = 1, panel.active_faults = {"stick-stuck: stuck_at drive_y"};
  panel.publisher.program = "rise-hild", panel.publisher.host = "station1";
  write_seed(dir + "/panel_state", 0, panel);
  rise_msgs::RobotState robot{};
  robot.robot_id = "tracked_eod", robot.orientation_wxyz[0] = 1, robot.num_objects = 1, robot.object_names = {"box"};
  robot.object_positions_m = {{1, 2, 0.1}}, robot.num_contacts = 1, robot.contacts = {"wall"};
  write_seed(dir + "/robot_state", 1, robot);
  rise_msgs::TaskStatus task{};
  task.training = "fig10_metro", task.node = "mission1", task.task = "approach", task.state = "running";
  write_seed(dir + "/task_status", 2, task);
  rise_msgs::PanelFeedback feedback{};
  feedback.panel_id = "rise_console", feedback.num_leds = 1, feedback.led_names = {"armed"}, feedback.led_on = {1};
  feedback.num_displays = 1, feedback.display_names = {"speed"}, feedback.display_values = {1.25f};
  write_seed(dir + "/panel_feedback", 3, feedback);
  rise_msgs::SimEvent event{};
  event.kind = "collision_started", event.a = "robot", event.b = "wall";
  write_seed(dir + "/sim_event", 4, event);
  rise_msgs::TaskEvent task_event{};
  task_event.task = "approach", task_event.name = "reached", task_event.kind = "reach_region", task_event.points = 10;
  write_seed(dir + "/task_event", 5, task_event);
  rise_msgs::SoundCue sound{};
  sound.name = "motor", sound.sample = "motor_loop", sound.continuous = true, sound.gain = 0.5f, sound.pitch = 1.0f;
  write_seed(dir + "/sound", 6, sound);
  std::ofstream(dir + "/channel", std::ios::binary) << '\x07' << "rise/t1/robot_state";
}

}  // namespace

// The seeds go into every folder named on the command line (the corpus).
extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  rise::fuzz::for_each_corpus_folder(*argc, *argv, write_seeds);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const uint8_t kind = data[0] % 8;
  ++data, --size;
  if (kind == 7) {
    // A channel name: taken apart, or not a station's.
    const std::string channel(reinterpret_cast<const char*>(data), size);
    if (const auto parts = m::parse_station_channel(channel)) {
      fuzz_check(!parts->trainee_id.empty() && !parts->what.empty());
      fuzz_check("rise/" + parts->trainee_id + "/" + parts->what == channel);
    }
    return 0;
  }
  ins::TraineeDirectory directory;
  const std::string channel = std::string("rise/t1/") + kKinds[kind];
  const bool taken = directory.on_message(channel, data, static_cast<int>(size), 1'000'000);
  fuzz_check(taken == (directory.rows().size() == 1));
  if (taken) fuzz_check(directory.rows()[0].id == "t1");
  switch (kind) {
    case 0: decode<rise_msgs::PanelState>(data, size, [](const auto& msg) { return ins::panel_json(msg); }); break;
    case 1: decode<rise_msgs::RobotState>(data, size, [](const auto& msg) { return ins::robot_json(msg); }); break;
    case 2: decode<rise_msgs::TaskStatus>(data, size, [](const auto& msg) { return ins::task_status_json(msg); }); break;
    case 3: decode<rise_msgs::PanelFeedback>(data, size, [](const auto& msg) { return ins::panel_feedback_json(msg); }); break;
    case 4: decode<rise_msgs::SimEvent>(data, size, [](const auto& msg) { return ins::sim_event_json(msg); }); break;
    case 5: decode<rise_msgs::TaskEvent>(data, size, [](const auto& msg) { return ins::task_event_json(msg); }); break;
    default: decode<rise_msgs::SoundCue>(data, size, [](const auto& msg) { return ins::sound_cue_json(msg); }); break;
  }
  return 0;
}
