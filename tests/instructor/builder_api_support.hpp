#pragma once

// What the builders' API tests (*builder_api_test.cpp) share: a scratch
// folder with a page to serve, the settings of a server on it (any port,
// a token, the shipped console), the token's header for an httplib client,
// the shipped files a test edits copied into the folder, and reading a file
// and writing a JSON body as text.

#include <httplib.h>
#include <json/json.h>
#include <stdlib.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "instructor/web_server.hpp"

namespace rise::instructor_test {

inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

inline std::string text(const Json::Value& v) { return Json::writeString(Json::StreamWriterBuilder(), v); }

struct BuilderApiFixture {
  std::filesystem::path dir;
  rise::instructor::WebServerSettings settings;

  /// A folder /tmp/rise-NAME-XXXXXX with www/index.html; a server on it takes `token`.
  BuilderApiFixture(const std::string& name, const std::string& token) {
    std::string tmpl = "/tmp/rise-" + name + "-XXXXXX";
    dir = ::mkdtemp(tmpl.data());
    std::filesystem::create_directories(dir / "www");
    std::ofstream(dir / "www" / "index.html") << "<!doctype html><title>console</title>";
    settings.port = 0;
    settings.token = token;
    settings.web_dir = (dir / "www").string();
    settings.panel_file = std::string(RISE_SOURCE_DIR) + "/panels/definitions/rise_console.yaml";
  }
  ~BuilderApiFixture() { std::filesystem::remove_all(dir); }
  BuilderApiFixture(const BuilderApiFixture&) = delete;
  BuilderApiFixture& operator=(const BuilderApiFixture&) = delete;

  httplib::Headers auth() const { return {{"X-Rise-Token", settings.token}}; }

  /// The files of the source tree's folder `from` ending in `extension` (""
  /// all) copied into dir/`to`; returns that folder's path.
  std::string copy_shipped(const std::string& from, const std::filesystem::path& to, const std::string& extension) const {
    std::filesystem::create_directories(dir / to);
    for (const auto& e : std::filesystem::directory_iterator(std::string(RISE_SOURCE_DIR) + "/" + from))
      if (extension.empty() || e.path().extension() == extension)
        std::filesystem::copy_file(e.path(), dir / to / e.path().filename());
    return (dir / to).string();
  }
};

}  // namespace rise::instructor_test
