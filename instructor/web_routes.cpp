#include "instructor/web_routes.hpp"

#include <httplib.h>
#include <json/json.h>
#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include "hil/panel_state_message.hpp"
#include "instructor/builder_routes.hpp"
#include "instructor/world_builder_routes.hpp"
#include "instructor/robot_builder_routes.hpp"
#include "instructor/console_builder.hpp"
#include "instructor/fault_presets.hpp"
#include "instructor/scenario.hpp"
#include "instructor/task_builder_routes.hpp"
#include "instructor/trainee_directory.hpp"
#include "instructor/web_json.hpp"
#include "instructor/web_requests.hpp"
#include "msgs/channels.hpp"
#include "msgs/clock.hpp"
#include "process/child_process.hpp"
#include "rise_msgs/FaultCommand.hpp"
#include "rise_msgs/SimControl.hpp"

namespace rise::instructor {
namespace fs = std::filesystem;

namespace {

// Comparison whose time does not depend on where the strings differ.
bool same_token(const std::string& a, const std::string& b) {
  unsigned char diff = a.size() == b.size() ? 0 : 1;
  for (std::size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i % (b.empty() ? 1 : b.size())]);
  return diff == 0 && !b.empty();
}

bool authorised(const httplib::Request& req, const std::string& token) {
  if (req.has_param("token") && same_token(req.get_param_value("token"), token)) return true;
  const std::string auth = req.get_header_value("Authorization");
  if (auth.rfind("Bearer ", 0) == 0 && same_token(auth.substr(7), token)) return true;
  if (same_token(req.get_header_value("X-Rise-Token"), token)) return true;
  return same_token(cookie_token(req.get_header_value("Cookie")), token);
}

void reply_json(httplib::Response& res, const Json::Value& v, int status = 200) {
  res.status = status;
  res.set_content(json_text(v), "application/json");
}

void reply_error(httplib::Response& res, int status, const std::string& message) {
  Json::Value v;
  v["error"] = message;
  reply_json(res, v, status);
}

// The body as a JSON object; nullopt after replying 400.
std::optional<Json::Value> object_body(const httplib::Request& req, httplib::Response& res) {
  std::string error;
  auto body = parse_json_object(req.body, &error);
  if (!body) reply_error(res, 400, error);
  return body;
}

// Every trainee heard or driven from here, with every channel on which more
// than one process publishes now.
Json::Value trainees_json(const WebRouteContext& ctx) {
  std::map<std::string, Json::Value> by_id = ctx.cache.trainees();
  const std::set<std::string> virtual_ids = ctx.virtual_panels.ids();
  for (const auto& id : virtual_ids) {
    by_id[id]["id"] = id;
    by_id[id]["virtual_panel"] = true;
  }
  std::map<std::string, std::vector<rise_msgs::Publisher>> by_channel;
  for (const auto& o : ctx.publishers.others(msgs::monotonic_us())) by_channel[o.channel].push_back(o.publisher);
  for (auto& [channel, list] : by_channel) {
    const auto parts = msgs::parse_station_channel(channel);
    if (!parts) continue;
    const auto& [id, what] = *parts;
    if (what == "panel_state" && virtual_ids.count(id)) list.push_back(msgs::this_publisher());
    if (list.size() < 2) continue;
    Json::Value& d = by_id[id]["duplicate_publishers"][what];
    for (const auto& p : list) d.append(publisher_json(p));
  }
  for (const auto& l : ctx.links.links(msgs::monotonic_us())) {
    by_id[l.id]["id"] = l.id;
    by_id[l.id]["link"] = link_json(l);
  }
  Json::Value out(Json::arrayValue);
  for (auto& [id, t] : by_id) out.append(t);
  return out;
}

// Every trainee's link, by id: pushed with each SSE update so that a lost
// one shows as lost though nothing of it changes any more.
Json::Value links_json(const WebRouteContext& ctx) {
  Json::Value v(Json::objectValue);
  for (const auto& l : ctx.links.links(msgs::monotonic_us())) v[l.id] = link_json(l);
  return v;
}

Json::Value reports_json(const std::string& reports_dir) {
  Json::Value out(Json::arrayValue);
  if (reports_dir.empty() || !fs::is_directory(reports_dir)) return out;
  std::vector<std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(reports_dir)) {
    if (!e.is_regular_file()) continue;
    const auto ext = e.path().extension().string();
    if (ext == ".html" || ext == ".json") files.push_back(fs::relative(e.path(), reports_dir).string());
  }
  std::sort(files.begin(), files.end());
  for (const auto& f : files) {
    Json::Value v;
    v["path"] = f;
    v["url"] = "/reports/" + f;
    out.append(v);
  }
  return out;
}

// Reports: only the .html / .json files /api/reports lists, never
// whatever else the folder holds (a key file, a journal).
void handle_report(const WebRouteContext& ctx, const httplib::Request& req, httplib::Response& res) {
  const std::string& reports_dir = ctx.settings.reports_dir;
  const std::string rel = req.matches[1];
  const fs::path path = fs::path(reports_dir) / rel;
  const auto ext = path.extension().string();
  const bool inside = !reports_dir.empty() && rel.find("..") == std::string::npos && rel[0] != '/';
  if (!inside || (ext != ".html" && ext != ".json") || !fs::is_regular_file(path))
    return reply_error(res, 404, "no report '" + rel + "'");
  std::ifstream in(path, std::ios::binary);
  std::string body((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  res.set_content(body, ext == ".html" ? "text/html" : "application/json");
}

// One SSE stream: the channels that changed since the client's last push,
// and the new events, at most push_hz times a second, at least every second.
void handle_stream(std::shared_ptr<const WebRouteContext> ctx, httplib::Response& res) {
  res.set_header("Cache-Control", "no-cache");
  auto last = std::make_shared<uint64_t>(0);
  const auto period = std::chrono::microseconds(static_cast<int64_t>(1e6 / ctx->settings.push_hz));
  auto next = std::make_shared<std::chrono::steady_clock::time_point>(std::chrono::steady_clock::now());
  res.set_chunked_content_provider("text/event-stream", [ctx, last, period, next](size_t, httplib::DataSink& sink) {
    if (!ctx->running) return false;
    std::this_thread::sleep_until(*next);
    *next = std::max(*next + period, std::chrono::steady_clock::now());
    auto update = ctx->cache.changes_since(last.get(), std::chrono::seconds(1));
    if (!update || !ctx->running) return false;
    (*update)["server_utime"] = Json::Int64(msgs::wall_us());
    (*update)["links"] = links_json(*ctx);
    const std::string text = "data: " + json_text(*update) + "\n\n";
    return sink.write(text.data(), text.size());
  });
}

void handle_virtual(const WebRouteContext& ctx, const httplib::Request& req, httplib::Response& res) {
  const std::string id = req.matches[1];
  if (!valid_trainee_id(id)) return reply_error(res, 400, "trainee id '" + id + "': letters, digits, _ . - only");
  const auto body = object_body(req, res);
  if (!body) return;
  std::string error;
  const auto controls = virtual_controls_from_json(*body, &error);
  if (!controls) return reply_error(res, 400, error);
  const std::string page = req.get_param_value("page");
  if (!valid_trainee_id(page) && !page.empty()) return reply_error(res, 400, "page '" + page + "': letters, digits, _ . - only");
  if (const auto refused = ctx.virtual_panels.update(id, *controls, req.remote_addr, page))
    return reply_error(res, refused->channel_taken ? 409 : refused->page_closed ? 410 : 400, refused->message);
  res.status = 204;
}

void handle_virtual_close(const WebRouteContext& ctx, const httplib::Request& req, httplib::Response& res) {
  if (!ctx.virtual_panels.disconnect(req.matches[1], req.get_param_value("page")))
    return reply_error(res, 404, "no virtual panel '" + std::string(req.matches[1]) + "'");
  res.status = 204;
}

void handle_sim_control(const WebRouteContext& ctx, const httplib::Request& req, httplib::Response& res) {
  const std::string id = req.matches[1], command = req.matches[2];
  if (!valid_trainee_id(id)) return reply_error(res, 400, "trainee id '" + id + "': letters, digits, _ . - only");
  rise_msgs::SimControl c;
  c.utime = msgs::wall_us();
  c.issuer = "rise-instructor";
  c.seq = ++ctx.sim_control_seq;
  c.command = command;
  c.steps = command == "step" ? 100 : 0;
  ctx.lcm.publish(msgs::sim_control_channel(id), &c);
  Json::Value v;
  v["published"] = msgs::sim_control_channel(id);
  v["command"] = command;
  v["seq"] = Json::Int64(c.seq);
  reply_json(res, v);
}

// Inject or clear one fault: a FaultCommand signed with the instructor key
// on rise/<trainee>/fault_command. The body names a preset ("fault") or
// gives the fields (kind, target, value, rate, duration_s, seed).
void handle_fault(const WebRouteContext& ctx, const httplib::Request& req, httplib::Response& res,
                  const std::string& action) {
  if (!ctx.key) return reply_error(res, 503, "no instructor key (rise-instructor serve --instructor-key FILE)");
  const auto body = object_body(req, res);
  if (!body) return;
  std::string error;
  auto command = fault_command_from_json(*body, action, &error);
  if (!command) return reply_error(res, 400, error);
  rise_msgs::FaultCommand& c = *command;
  const std::string& id = c.trainee_id;
  // Stamped in the receiver's clock, as measured: a station whose clock is
  // off by more than its --command-window still takes it (msgs/clock_offset.hpp).
  const auto offset = ctx.links.offset_us(id);
  c.utime = msgs::wall_us() + offset.value_or(0);
  c.nonce = 0;
  c.issuer = ctx.settings.issuer;
  msgs::sign(c, *ctx.key);
  ctx.lcm.publish(msgs::fault_command_channel(id), &c);
  Json::Value v;
  v["published"] = msgs::fault_command_channel(id);
  v["action"] = action;
  v["fault_id"] = c.fault_id;
  v["kind"] = c.kind;
  v["target"] = c.target;
  v["nonce"] = Json::Int64(c.nonce);
  v["utime"] = Json::Int64(c.utime);
  if (offset) v["clock_offset_ms"] = static_cast<double>(*offset) / 1000.0;
  reply_json(res, v);
}

// The scenario files offered: name (the file's `scenario:`), file, faults,
// and which trainees run one now.
Json::Value scenarios_json(const WebRouteContext& ctx) {
  Json::Value v;
  v["enabled"] = !ctx.settings.scenario_program.empty() && ctx.key.has_value();
  Json::Value files(Json::arrayValue);
  const std::string& dir = ctx.settings.scenarios_dir;
  if (!dir.empty() && fs::is_directory(dir)) {
    std::vector<fs::path> paths;
    for (const auto& e : fs::directory_iterator(dir))
      if (e.is_regular_file() && e.path().extension() == ".yaml") paths.push_back(e.path());
    std::sort(paths.begin(), paths.end());
    for (const auto& p : paths) {
      Json::Value f;
      f["file"] = p.filename().string();
      try {
        const Scenario s = load_scenario(p.string());
        f["name"] = s.name;
        f["faults"] = static_cast<Json::UInt64>(s.faults.size());
        f["seed"] = static_cast<Json::UInt64>(s.seed);
      } catch (const std::exception& e) {
        f["error"] = e.what();
      }
      files.append(f);
    }
  }
  v["files"] = files;
  Json::Value running(Json::objectValue);
  for (const auto& run : ctx.scenarios.running()) {
    Json::Value r;
    r["file"] = run.file;
    r["seed"] = static_cast<Json::UInt64>(run.seed);
    r["pid"] = run.pid;
    running[run.trainee] = r;
  }
  v["running"] = running;
  return v;
}

// Starts the request's scenario file for its trainee (seed: the request's, else the file's).
void start_scenario(const WebRouteContext& ctx, const ScenarioRequest& request, ScenarioRun run,
                    httplib::Response& res) {
  const std::string& dir = ctx.settings.scenarios_dir;
  run.file = request.file;
  const fs::path path = fs::path(dir) / run.file;
  if (!fs::is_regular_file(path))
    return reply_error(res, 400, "scenario file '" + run.file + "': not a .yaml file in " + dir);
  run.path = path.string();
  try {
    const Scenario s = load_scenario(run.path);
    run.name = s.name;
    run.seed = request.seed.value_or(s.seed);
  } catch (const std::exception& e) {
    return reply_error(res, 400, e.what());
  }
  try {
    run = ctx.scenarios.start(run);
  } catch (const std::exception& e) {
    return reply_error(res, 500, e.what());
  }
  Json::Value v;
  v["trainee"] = run.trainee;
  v["file"] = run.file;
  v["name"] = run.name;
  v["seed"] = static_cast<Json::UInt64>(run.seed);
  v["pid"] = run.pid;
  reply_json(res, v);
}

void handle_scenario(const WebRouteContext& ctx, const httplib::Request& req, httplib::Response& res, bool start) {
  if (ctx.settings.scenario_program.empty() || ctx.settings.scenarios_dir.empty())
    return reply_error(res, 503, "scenario control is off (rise-instructor serve --scenarios-dir DIR)");
  if (!ctx.key) return reply_error(res, 503, "no instructor key (rise-instructor serve --instructor-key FILE)");
  const auto body = object_body(req, res);
  if (!body) return;
  std::string error;
  const auto request = scenario_request_from_json(*body, start, &error);
  if (!request) return reply_error(res, 400, error);
  ScenarioRun run;
  run.trainee = request->trainee;
  // Stopping (or replacing) a run.
  ctx.scenarios.stop(run.trainee);
  if (start) return start_scenario(ctx, *request, run, res);
  Json::Value v;
  v["trainee"] = run.trainee;
  v["stopped"] = true;
  reply_json(res, v);
}

// The token on every request; a request that carries it as ?token= gets
// the cookie too.
void check_tokens(httplib::Server& http, const std::string& token) {
  http.set_pre_routing_handler([&token](const httplib::Request& req, httplib::Response& res) {
    if (authorised(req, token)) {
      // The pages load their scripts by plain URLs: a cookie carries the token on.
      if (req.has_param("token"))
        res.set_header("Set-Cookie", "rise_token=" + token + "; Path=/; HttpOnly; SameSite=Strict");
      return httplib::Server::HandlerResponse::Unhandled;
    }
    reply_error(res, 401, "token required (?token=, Authorization: Bearer, or X-Rise-Token)");
    return httplib::Server::HandlerResponse::Handled;
  });
}

}  // namespace

void add_routes(httplib::Server& http, const WebRouteContext& context) {
  using Req = httplib::Request;
  using Res = httplib::Response;
  const std::size_t threads = std::max<std::size_t>(context.settings.http_threads, 4);
  http.new_task_queue = [threads] { return new httplib::ThreadPool(threads); };
  check_tokens(http, context.settings.token);
  if (!http.set_mount_point("/", context.settings.web_dir))
    throw std::runtime_error(context.settings.web_dir + ": cannot serve this folder");
  // The handlers outlive this call: they share one copy of the context.
  const auto ctx = std::make_shared<const WebRouteContext>(context);
  http.Get(R"(/reports/(.+))", [ctx](const Req& req, Res& res) { handle_report(*ctx, req, res); });
  http.Get("/api/world", [ctx](const Req&, Res& res) { res.set_content(ctx->world_text, "application/json"); });
  http.Get("/api/trainees", [ctx](const Req&, Res& res) { reply_json(res, trainees_json(*ctx)); });
  http.Get("/api/reports", [ctx](const Req&, Res& res) { reply_json(res, reports_json(ctx->settings.reports_dir)); });
  http.Get("/api/panel", [ctx](const Req&, Res& res) {
    reply_json(res, panel_definition_json(ctx->console, ctx->settings.virtual_timeout_ms));
  });
  http.Get("/api/stream", [ctx](const Req&, Res& res) { handle_stream(ctx, res); });
  http.Post(R"(/api/virtual/([^/]+))", [ctx](const Req& req, Res& res) { handle_virtual(*ctx, req, res); });
  http.Post(R"(/api/virtual/([^/]+)/close)", [ctx](const Req& req, Res& res) { handle_virtual_close(*ctx, req, res); });
  http.Get("/api/faults", [ctx](const Req&, Res& res) {
    reply_json(res, fault_buttons_json(default_fault_presets(), ctx->key.has_value()));
  });
  http.Post("/api/fault/inject", [ctx](const Req& req, Res& res) { handle_fault(*ctx, req, res, "inject"); });
  http.Post("/api/fault/clear", [ctx](const Req& req, Res& res) { handle_fault(*ctx, req, res, "clear"); });
  http.Get("/api/scenarios", [ctx](const Req&, Res& res) { reply_json(res, scenarios_json(*ctx)); });
  http.Post("/api/scenario/start", [ctx](const Req& req, Res& res) { handle_scenario(*ctx, req, res, true); });
  http.Post("/api/scenario/stop", [ctx](const Req& req, Res& res) { handle_scenario(*ctx, req, res, false); });
  http.Post(R"(/api/sim/([^/]+)/(pause|resume|step|reset))",
            [ctx](const Req& req, Res& res) { handle_sim_control(*ctx, req, res); });
  add_builder_routes(http, ctx->settings.designs_dir);
  add_world_builder_routes(http, ctx->settings.worlds_dir);
  add_robot_builder_routes(http, {ctx->settings.robots_dir, ctx->settings.world_file, ctx->settings.lcm_url});
  add_task_builder_routes(http, ctx->settings.designs_dir, process::executable_dir(), ctx->settings.lcm_url);
  add_console_builder_routes(http, ctx->settings.consoles_dir, ctx->settings.console_sources);
}

}  // namespace rise::instructor
