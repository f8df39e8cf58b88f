#pragma once

// Decoding LCM messages from the network without trusting them.
//
// lcm-gen's C++ decode() (LCM 1.4, Debian 12) checks a string's length
// against the bytes left but not for being <= 0, and then calls
// std::string::assign(data, length - 1): a packet whose string length is 0
// or negative throws std::length_error out of decode(). LCM's own typed
// subscriptions call decode() inside lcm_handle() with no try, so one such
// UDP packet from anyone on the multicast group aborts the receiving
// process (found by tests/fuzz/command_auth_fuzz.cpp; a 126-byte
// TrainingControl killed rise-sim; a length of INT32_MIN overflowed the int
// before that). msgs/lcm_gen.sh adds the missing checks to the generated
// code (string lengths >= 1, array counts within the bytes left); as a
// second line, every receiver in this project decodes through
// decode_message(), and subscribes typed handlers through
// subscribe<&Class::method>(), which counts and drops what does not decode.

#include <lcm/lcm-cpp.hpp>

#include <atomic>
#include <cstdint>
#include <exception>
#include <string>

namespace rise::msgs {

/// Messages that did not decode in this process (a wrong type hash, a
/// truncated packet, a length decode() throws on), over all channels.
inline std::atomic<uint64_t>& malformed_messages() {
  static std::atomic<uint64_t> count{0};
  return count;
}

/// Decodes `size` bytes into `out`; false (counted in malformed_messages())
/// when they are not a whole message of that type. Never throws.
template <class Message>
bool decode_message(const void* data, int64_t size, Message& out) noexcept {
  try {
    if (size >= 0 && size <= INT32_MAX && out.decode(data, 0, static_cast<int>(size)) >= 0) return true;
  } catch (const std::exception&) {
  }
  malformed_messages().fetch_add(1, std::memory_order_relaxed);
  return false;
}

namespace detail {

template <class Method>
struct TypedHandler;
template <class Class, class Message>
struct TypedHandler<void (Class::*)(const lcm::ReceiveBuffer*, const std::string&, const Message*)> {
  using Handler = Class;
  using Type = Message;
};

template <auto Method>
void deliver(const lcm::ReceiveBuffer* rbuf, const std::string& channel,
             typename TypedHandler<decltype(Method)>::Handler* handler) {
  typename TypedHandler<decltype(Method)>::Type message;
  if (decode_message(rbuf->data, rbuf->data_size, message)) (handler->*Method)(rbuf, channel, &message);
}

}  // namespace detail

/// lcm.subscribe(channel, Method, handler) for a typed handler method
/// `void Class::on(const lcm::ReceiveBuffer*, const std::string&, const Msg*)`,
/// except that a message that does not decode is counted and dropped
/// (decode_message()) instead of throwing through LCM:
///   msgs::subscribe<&Listener::on>(lcm, channel, &listener)->setQueueCapacity(16);
template <auto Method>
lcm::Subscription* subscribe(lcm::LCM& lcm, const std::string& channel,
                             typename detail::TypedHandler<decltype(Method)>::Handler* handler) {
  return lcm.subscribeFunction(channel, &detail::deliver<Method>, handler);
}

}  // namespace rise::msgs
