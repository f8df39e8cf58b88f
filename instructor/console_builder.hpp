#pragma once

// The Console Builder's side of the server (/console_builder.html): a panel
// definition's controls as the page edits them (JSON), written back into the
// file's text (panels/panel_writer.hpp: only `controls:` is rewritten, with
// a comment per control) and checked by the loader rise-hild and
// `rise-panel check` use, its error with the line of that text and the key.
//
// The live view: the server opens the console's sources itself, from the
// URLs it was given (`rise-instructor serve --console-source URL`, one per
// source as rise-hild's --source), with rise-hild's own source classes and
// Bridge (hil/source_factory.hpp, hil/bridge.hpp) on a "wide" copy of the
// definition that binds every signal the source has: rise-can-v1 and
// rise-modbus-v1 every axis.N, button.N and switch.N, a dbc source every
// signal of its DBC, a hid source every input axis, button and hat of its
// device's report descriptor (read by opening the device once first); so a
// button the definition does not bind yet shows and can be learned. Why not a raw-signal message from rise-hild: that needs a
// new LCM type, a tap in the mapper's cyclic path and a daemon running with
// a definition that may not load yet (the one being built); opening the
// source again needs no new code in hil, and CAN (socketcan, socketcand),
// Modbus/TCP slaves and hidraw take several readers at once, so the view
// runs beside a rise-hild. A generic modbus source, and a hid source read
// through evdev:// or an SDL mapping, shows the signals its definition binds; j1939 and canopen sources are not opened
// (they claim an address / drive the node's NMT state, which a second
// master on the bus must not), nor is the feedback written (no LEDs).
// The preview runs the page's definition (once it loads) through a second
// Bridge: PanelState as rise-hild would publish it.

#include <json/json.h>

#include <optional>
#include <string>
#include <vector>

#include "instructor/training_builder.hpp"
#include "panels/panel_definition.hpp"
#include "panels/panel_writer.hpp"

namespace httplib {
class Server;
}

namespace rise::instructor {

/// [{comment, fields: [[key, value], ...]}], a value a string or a list of values.
Json::Value controls_json(const std::vector<panels::ControlEntry>& controls);

/// The page's JSON (untrusted) as controls; nullopt with *error set
/// ("controls[2].fields[1]: expected [key, value]") for one of the wrong shape.
std::optional<std::vector<panels::ControlEntry>> controls_from_json(const Json::Value& controls, std::string* error);

struct ConsoleCheck {
  std::string yaml;                  ///< what would be saved
  std::vector<int> lines;            ///< each control's line in `yaml`
  std::vector<BuilderError> errors;  ///< empty: rise-panel check would say ok
  std::optional<panels::PanelDefinition> definition;  ///< when it loads
};

/// `text` (the file as loaded) with `controls` written into it, loaded as
/// rise-panel check loads `path` (a DBC, EDS or SDL file beside it).
ConsoleCheck check_console(const std::string& text, const std::vector<panels::ControlEntry>& controls,
                           const std::string& path);

Json::Value check_json(const ConsoleCheck& check);

/// One signal a source has, as the live view reads it.
struct RawSignal {
  std::size_t source = 0;
  std::string signal;  ///< as a control binds it: button.7, BJM1.Horn, x
  std::string kind;    ///< axis, button, switch
  double lo = -1.0, hi = 1.0;  ///< an axis' physical range (dbc: the DBC's, else -1..1)
  bool bound = false;  ///< the definition binds it already
  std::string wire{};  ///< where it travels: "CAN 0x130", "discrete input 7", "usage 0x0009:0x0007"
};

/// Every signal of `definition`'s sources the live view reads (see above;
/// a hid source: those its definition binds, the live view adds its
/// device's). `controls`: the definition's entries (for the signals hid,
/// modbus and canopen sources bind).
std::vector<RawSignal> raw_signals(const panels::PanelDefinition& definition,
                                   const std::vector<panels::ControlEntry>& controls);

/// The routes (behind the token, as every route):
///   GET  /api/builder/consoles               the definitions of --consoles DIR, the source URLs
///   GET  /api/builder/console/NAME           its text, version, controls, sources (or the loader's error)
///   POST /api/builder/console/NAME/check     {controls} → the YAML and its errors; restarts the preview
///   POST /api/builder/console/NAME           {version, controls} → saved; 409 when changed on disk; 422 with errors
///   POST /api/builder/console/NAME/live      opens its sources: → {signals}
///   GET  /api/builder/console_live           the raw values, the preview's controls, the learn state
///   POST /api/builder/console_learn          {seconds}: the learn window starts
/// `dir` "" answers 503.
void add_console_builder_routes(httplib::Server& http, const std::string& dir, const std::vector<std::string>& urls);

}  // namespace rise::instructor
