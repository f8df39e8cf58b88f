#pragma once

// The four routes every builder page has for its kind of file, written once:
//   GET  /api/builder/PLURAL             the folder's files (and what each is)
//   GET  /api/builder/SINGULAR/NAME      its text, version and model (or the loader's error)
//   POST /api/builder/SINGULAR/NAME/check  {MODEL} → the YAML it would save and its errors
//   POST /api/builder/SINGULAR/NAME      {version, MODEL} → saved (new version); 409 when
//                                        the file changed on disk since `version`; 422 with
//                                        the errors when the program would not load it
// A builder says only what is its own (DesignKind): how its files are
// listed, how a file's text becomes the page's model, and how the page's
// model becomes the text to save, checked by the loader its program uses.
// The folder (instructor/design_files.hpp) makes the save atomic and refuses
// one over another's change.

#include <json/json.h>

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "instructor/design_files.hpp"

namespace httplib {
class Server;
struct Request;
struct Response;
}  // namespace httplib

namespace rise::instructor {

/// What a check of the page's model gives: the text that would be saved,
/// the loader's errors (empty: the program loads it) and anything else the
/// page draws from it (merged into the reply).
struct DesignCheck {
  std::string yaml;
  std::vector<BuilderError> errors;
  Json::Value extra;  ///< an object (its members replace the reply's: a builder's richer errors), or null
};

struct DesignKind {
  std::string plural;    ///< "worlds": GET /api/builder/worlds
  std::string singular;  ///< "world": /api/builder/world/NAME
  std::string flag;      ///< "--worlds DIR": named in the 503 when the folder is off
  /// The list's body ({dir, PLURAL: [...]} or more); never throws.
  std::function<Json::Value(const DesignFolder&)> list;
  /// The model fields of a read ({world, view}); throws std::exception when the
  /// text is not a file of this kind (the reply then carries `load_error`).
  std::function<Json::Value(const std::string& text, const std::string& path)> read;
  /// The page's body (untrusted) as the text to save at `path`, replacing
  /// `disk_text` ("" when there is none: whose comments a writer keeps);
  /// nullopt with *error set ("doors[1].hinge: expected 2 numbers") for a
  /// body of the wrong shape.
  std::function<std::optional<DesignCheck>(const Json::Value& body, const std::string& path,
                                           const std::string& disk_text, std::string* error)>
      check;
};

/// Adds the four routes of `kind` on `folder` (dir "": each answers 503).
void add_design_routes(httplib::Server& http, std::shared_ptr<DesignFolder> folder, DesignKind kind);

/// The helpers a builder's own further routes use (try-it, learn):
void reply_json(httplib::Response& res, const Json::Value& v, int status = 200);
void reply_json_error(httplib::Response& res, int status, const std::string& message);
/// The request's file name (its first path match) after checking it names a
/// .yaml of the folder, replying 503 or 400 else (then "").
std::string design_name(const DesignFolder& folder, const DesignKind& kind, const httplib::Request& req,
                        httplib::Response& res);
/// check_json's {yaml, ok, errors}, then the check's extra fields.
Json::Value design_check_json(const DesignCheck& check);

}  // namespace rise::instructor
