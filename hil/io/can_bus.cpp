#include "hil/io/can_bus.hpp"

#include <stdexcept>
#include <type_traits>

#include "hil/io/can_url.hpp"
#include "hil/io/mem_bus.hpp"
#include "hil/io/replay_bus.hpp"
#include "hil/io/slcan_bus.hpp"
#include "hil/io/socketcan_bus.hpp"
#include "hil/io/socketcand_client.hpp"
#include "hil/io/socketcand_server.hpp"

namespace rise::hil::io {

const char* to_string(IoStatus s) {
  switch (s) {
    case IoStatus::Ok: return "ok";
    case IoStatus::Timeout: return "timeout";
    case IoStatus::Disconnected: return "disconnected";
    case IoStatus::Invalid: return "invalid";
    case IoStatus::Error: return "error";
  }
  return "unknown";
}

std::unique_ptr<CanBus> open_can_bus(std::string_view url) {
  const CanAddress address = parse_can_url(url);
  std::string text(url);
  return std::visit(
      [&text](const auto& a) -> std::unique_ptr<CanBus> {
        using A = std::decay_t<decltype(a)>;
        if constexpr (std::is_same_v<A, MemAddress>) {
          return std::make_unique<MemBus>(std::move(text), a.name);
        } else if constexpr (std::is_same_v<A, SocketCanAddress>) {
          auto bus = std::make_unique<SocketCanBus>(std::move(text), a);
          if (bus->reopen() != IoStatus::Ok) throw std::runtime_error(bus->last_error());
          return bus;
        } else if constexpr (std::is_same_v<A, ReplayAddress>) {
          return std::make_unique<ReplayBus>(std::move(text), a);
        } else if constexpr (std::is_same_v<A, SlcanAddress>) {
          // An unplugged adapter may come later: the caller retries with reopen().
          auto bus = std::make_unique<SlcanBus>(std::move(text), a);
          bus->reopen();
          return bus;
        } else if (a.listen) {
          auto bus = std::make_unique<SocketcandServer>(std::move(text), a);
          if (bus->reopen() != IoStatus::Ok) throw std::runtime_error(bus->last_error());
          return bus;
        } else {
          // The server may come later: the caller retries with reopen().
          auto bus = std::make_unique<SocketcandClient>(std::move(text), a);
          bus->reopen();
          return bus;
        }
      },
      address);
}

uint16_t listening_port(const CanBus& bus) {
  const auto* server = dynamic_cast<const SocketcandServer*>(&bus);
  return server != nullptr ? server->port() : 0;
}

}  // namespace rise::hil::io
