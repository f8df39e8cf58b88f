#pragma once

// What a virtual panel's page posts (POST /api/virtual/ID), apart from the
// panel so that the request's parser (instructor/web_requests.hpp) needs
// nothing of hil.

#include <map>
#include <string>

namespace rise::instructor {

/// What a page sends, by the panel definition's control names. Controls it
/// leaves out keep their safe value.
struct VirtualControls {
  std::map<std::string, float> axes;          ///< -1..1
  std::map<std::string, bool> buttons;        ///< pressed
  std::map<std::string, std::string> switches;  ///< position label
};

}  // namespace rise::instructor
