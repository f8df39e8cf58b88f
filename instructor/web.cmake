# rise::instructor_web — the web console's server and the virtual panel
# (cpp-httplib from Debian's libcpp-httplib-dev; the pages are built from npm
# packages at set-up into instructor/web/dist, see run.sh).
find_package(PkgConfig REQUIRED)
pkg_check_modules(RISE_HTTPLIB REQUIRED IMPORTED_TARGET GLOBAL cpp-httplib)
add_library(rise_instructor_web
  web_server.cpp
  web_routes.cpp
  web_json.cpp
  web_requests.cpp
  channel_cache.cpp
  fault_presets.cpp
  virtual_panel.cpp
  virtual_panels.cpp
  scenario_processes.cpp
  launcher_thread.cpp
  design_files.cpp
  builder_errors.cpp
  training_builder.cpp
  builder_routes.cpp
  design_routes.cpp
  world_builder.cpp
  world_builder_routes.cpp
  sandbox.cpp
  robot_builder.cpp
  robot_builder_routes.cpp
  task_builder.cpp
  task_builder_routes.cpp
  console_builder.cpp
  console_builder_model.cpp)
add_library(rise::instructor_web ALIAS rise_instructor_web)
rise_target_options(rise_instructor_web)
target_link_libraries(rise_instructor_web PUBLIC rise::hil rise::msgs
  PRIVATE rise::sim rise::training rise::instructor rise::process rise::hil_io PkgConfig::RISE_HTTPLIB JsonCpp::JsonCpp lcm Threads::Threads)

# rise-instructor serve
add_library(rise_instructor_serve STATIC app/serve_command.cpp)
rise_target_options(rise_instructor_serve)
target_compile_definitions(rise_instructor_serve PRIVATE RISE_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
target_link_libraries(rise_instructor_serve PUBLIC rise::instructor_web rise::panels rise::hil_io rise::process CLI11::CLI11
  spdlog::spdlog)
