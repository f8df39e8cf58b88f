#include "firmware_protocol/j1939.hpp"

#include <algorithm>

namespace rise::firmware_protocol::j1939 {
namespace {

// TP.CM control bytes (J1939-21 5.10.3).
constexpr uint8_t kRts = 16;
constexpr uint8_t kCts = 17;
constexpr uint8_t kEndOfMsgAck = 19;
constexpr uint8_t kBam = 32;
constexpr uint8_t kAbort = 255;
// Abort reasons (J1939-21 Table 7).
constexpr uint8_t kAbortBusy = 1;
constexpr uint8_t kAbortResources = 2;
constexpr uint8_t kAbortTimeout = 3;

constexpr uint8_t kFirstDynamicAddress = 128;  // J1939-81 4.5: the self-configurable range
constexpr uint8_t kLastDynamicAddress = 247;

uint8_t packets_for(std::size_t size) { return static_cast<uint8_t>((size + 6) / 7); }

void put_pgn(std::array<uint8_t, 8>& d, uint32_t pgn) {
  d[5] = static_cast<uint8_t>(pgn);
  d[6] = static_cast<uint8_t>(pgn >> 8);
  d[7] = static_cast<uint8_t>(pgn >> 16);
}

uint32_t get_pgn(const std::array<uint8_t, 8>& d) {
  return static_cast<uint32_t>(d[5]) | static_cast<uint32_t>(d[6]) << 8 | (static_cast<uint32_t>(d[7]) & 0x03) << 16;
}

uint16_t get_size(const std::array<uint8_t, 8>& d) { return static_cast<uint16_t>(d[1] | d[2] << 8); }

Frame cm_frame(uint8_t sa, uint8_t da, std::array<uint8_t, 8> data) {
  Frame f;
  f.id = {7, kPgnTpCm, sa, da};
  f.data = data;
  return f;
}

}  // namespace

uint32_t pgn_of(uint32_t can_id) { return decode_id(can_id).pgn; }

Id decode_id(uint32_t can_id) {
  Id id;
  id.priority = static_cast<uint8_t>((can_id >> 26) & 0x7);
  id.sa = static_cast<uint8_t>(can_id & 0xFF);
  const uint32_t field = (can_id >> 8) & 0x3FFFF;
  if (is_pdu1(field)) {
    id.pgn = field & 0x3FF00;
    id.da = static_cast<uint8_t>(field & 0xFF);
  } else {
    id.pgn = field;
    id.da = kGlobalAddress;
  }
  return id;
}

uint32_t encode_id(const Id& id) {
  const uint32_t field = is_pdu1(id.pgn) ? (id.pgn & 0x3FF00) | id.da : id.pgn & 0x3FFFF;
  return static_cast<uint32_t>(id.priority & 0x7) << 26 | field << 8 | id.sa;
}

// J1939-81 4.1.1: identity 0..20, manufacturer 21..31, ECU instance 32..34,
// function instance 35..39, function 40..47, reserved 48, vehicle system
// 49..55, its instance 56..59, industry group 60..62, arbitrary address 63.
uint64_t Name::pack() const {
  return (identity & 0x1FFFFFull) | (manufacturer & 0x7FFull) << 21 | (ecu_instance & 0x7ull) << 32 |
         (function_instance & 0x1Full) << 35 | static_cast<uint64_t>(function) << 40 |
         (vehicle_system & 0x7Full) << 49 | (vehicle_system_instance & 0xFull) << 56 |
         (industry_group & 0x7ull) << 60 | static_cast<uint64_t>(arbitrary_address_capable) << 63;
}

Name Name::unpack(uint64_t raw) {
  Name n;
  n.identity = static_cast<uint32_t>(raw & 0x1FFFFF);
  n.manufacturer = static_cast<uint16_t>((raw >> 21) & 0x7FF);
  n.ecu_instance = static_cast<uint8_t>((raw >> 32) & 0x7);
  n.function_instance = static_cast<uint8_t>((raw >> 35) & 0x1F);
  n.function = static_cast<uint8_t>(raw >> 40);
  n.vehicle_system = static_cast<uint8_t>((raw >> 49) & 0x7F);
  n.vehicle_system_instance = static_cast<uint8_t>((raw >> 56) & 0xF);
  n.industry_group = static_cast<uint8_t>((raw >> 60) & 0x7);
  n.arbitrary_address_capable = (raw >> 63) != 0;
  return n;
}

uint64_t name_from_bytes(std::span<const uint8_t, 8> data) {
  uint64_t v = 0;
  for (std::size_t i = 0; i < 8; ++i) v |= static_cast<uint64_t>(data[i]) << (8 * i);
  return v;
}

std::array<uint8_t, 8> name_to_bytes(uint64_t name) {
  std::array<uint8_t, 8> d{};
  for (std::size_t i = 0; i < 8; ++i) d[i] = static_cast<uint8_t>(name >> (8 * i));
  return d;
}

// ---------------------------------------------------------------- TpReceiver

void TpReceiver::set_own_address(uint8_t own) {
  if (own == own_) return;
  for (Session& s : sessions_)
    if (s.active && !s.bam) s.active = false;
  own_ = own;
}

TpResult TpReceiver::on_frame(const Frame& frame, int64_t now_ms) {
  if (frame.len != 8) return {};  // J1939-21: TP frames are always 8 bytes
  if (frame.id.pgn == kPgnTpCm) return on_cm(frame, now_ms);
  if (frame.id.pgn == kPgnTpDt) return on_dt(frame, now_ms);
  return {};
}

TpReceiver::Session* TpReceiver::find(uint8_t sa, uint8_t da, bool bam) {
  for (Session& s : sessions_)
    if (s.active && s.bam == bam && s.sa == sa && s.da == da) return &s;
  return nullptr;
}

void TpReceiver::drop(Session& s, TpDrop why) {
  s.active = false;
  counters_.dropped[static_cast<std::size_t>(why)]++;
}

Frame TpReceiver::cts(const Session& s) const {
  Frame f = cm_frame(s.da, s.sa, {kCts, static_cast<uint8_t>(s.window_end - s.next + 1), s.next, 0xFF, 0xFF, 0, 0, 0});
  put_pgn(f.data, s.pgn);
  return f;
}

Frame TpReceiver::abort_frame(const Session& s, uint8_t reason) const {
  Frame f = cm_frame(s.da, s.sa, {kAbort, reason, 0xFF, 0xFF, 0xFF, 0, 0, 0});
  put_pgn(f.data, s.pgn);
  return f;
}

TpResult TpReceiver::on_cm(const Frame& frame, int64_t now_ms) {
  const uint8_t control = frame.data[0];
  if (control == kBam && frame.id.da == kGlobalAddress) return on_announce(frame, true, now_ms);
  if (frame.id.da != own_ || own_ == kNullAddress) return {};  // another pair's session
  if (control == kRts) return on_announce(frame, false, now_ms);
  if (control == kAbort) {
    if (Session* s = find(frame.id.sa, own_, false)) drop(*s, TpDrop::AbortReceived);
    else counters_.stray++;
    return {};
  }
  if (control == kCts || control == kEndOfMsgAck) counters_.stray++;  // we never send with RTS
  return {};
}

TpResult TpReceiver::on_announce(const Frame& frame, bool bam, int64_t now_ms) {
  const uint8_t da = bam ? kGlobalAddress : own_;
  if (Session* old = find(frame.id.sa, da, bam)) drop(*old, TpDrop::Replaced);
  const uint16_t size = get_size(frame.data);
  const uint8_t packets = frame.data[3];
  Session proto;
  proto.sa = frame.id.sa;
  proto.da = da;
  proto.pgn = get_pgn(frame.data);
  TpResult result;
  if (size < 9 || size > kMaxTpBytes || packets != packets_for(size)) {
    counters_.dropped[static_cast<std::size_t>(TpDrop::BadAnnouncement)]++;
    if (!bam) result.reply = abort_frame(proto, kAbortResources);
    return result;
  }
  Session* s = nullptr;
  for (Session& candidate : sessions_)
    if (!candidate.active) s = &candidate;
  if (!s) {
    counters_.dropped[static_cast<std::size_t>(TpDrop::NoSession)]++;
    if (!bam) result.reply = abort_frame(proto, kAbortBusy);
    return result;
  }
  s->active = true;
  s->bam = bam;
  s->sa = proto.sa;
  s->da = da;
  s->pgn = proto.pgn;
  s->size = size;
  s->packets = packets;
  s->next = 1;
  s->max_per_cts = bam || frame.data[4] == 0 ? 255 : frame.data[4];
  if (bam) {
    s->deadline_ms = now_ms + kT1Ms;
    return result;
  }
  s->window_end = static_cast<uint8_t>(std::min<int>(packets, s->max_per_cts));
  s->deadline_ms = now_ms + kT2Ms;
  result.reply = cts(*s);
  return result;
}

TpResult TpReceiver::on_dt(const Frame& frame, int64_t now_ms) {
  const bool bam = frame.id.da == kGlobalAddress;
  if (!bam && (frame.id.da != own_ || own_ == kNullAddress)) return {};  // another pair's session
  Session* s = find(frame.id.sa, frame.id.da, bam);
  if (!s) {
    counters_.stray++;
    return {};
  }
  const uint8_t seq = frame.data[0];
  TpResult result;
  if (seq != 0 && seq < s->next) {
    counters_.duplicates++;
    return result;
  }
  if (seq != s->next) {
    counters_.out_of_order++;
    if (bam) {
      drop(*s, TpDrop::OutOfOrder);
    } else if (seq >= s->window_end) {
      // The sender finished its window with a gap: ask again from the gap
      // (J1939-21 5.10.3.2, retransmission by CTS).
      s->window_end = static_cast<uint8_t>(std::min<int>(s->packets, s->next + s->max_per_cts - 1));
      s->deadline_ms = now_ms + kT2Ms;
      result.reply = cts(*s);
    }
    return result;
  }
  const std::size_t offset = static_cast<std::size_t>(seq - 1) * 7;
  const std::size_t n = std::min<std::size_t>(7, s->size - offset);
  std::copy_n(frame.data.begin() + 1, n, s->data.begin() + static_cast<std::ptrdiff_t>(offset));
  s->deadline_ms = now_ms + kT1Ms;
  if (seq == s->packets) {
    s->active = false;
    counters_.messages++;
    result.message = TpMessage{s->pgn, s->sa, s->da, std::span<const uint8_t>(s->data.data(), s->size)};
    if (!bam) {
      Frame ack = cm_frame(s->da, s->sa, {kEndOfMsgAck, static_cast<uint8_t>(s->size), static_cast<uint8_t>(s->size >> 8),
                                          s->packets, 0xFF, 0, 0, 0});
      put_pgn(ack.data, s->pgn);
      result.reply = ack;
    }
    return result;
  }
  s->next = static_cast<uint8_t>(seq + 1);
  if (!bam && seq == s->window_end) {
    s->window_end = static_cast<uint8_t>(std::min<int>(s->packets, seq + s->max_per_cts));
    s->deadline_ms = now_ms + kT2Ms;
    result.reply = cts(*s);
  }
  return result;
}

std::size_t TpReceiver::expire(int64_t now_ms, std::span<Frame> aborts) {
  std::size_t n = 0;
  for (Session& s : sessions_) {
    if (!s.active || now_ms <= s.deadline_ms) continue;
    drop(s, TpDrop::Timeout);
    if (!s.bam && n < aborts.size()) aborts[n++] = abort_frame(s, kAbortTimeout);
  }
  return n;
}

// ---------------------------------------------------------------- BamSender

bool BamSender::start(uint32_t pgn, uint8_t sa, std::span<const uint8_t> data, uint8_t priority) {
  if (data.size() < 9 || data.size() > kMaxTpBytes) return false;
  std::copy(data.begin(), data.end(), data_.begin());
  size_ = static_cast<uint16_t>(data.size());
  packets_ = packets_for(data.size());
  sent_ = 0;
  pgn_ = pgn;
  sa_ = sa;
  priority_ = priority;
  return true;
}

std::optional<Frame> BamSender::next() {
  if (!busy()) return std::nullopt;
  Frame f;
  if (sent_ == 0) {
    f = cm_frame(sa_, kGlobalAddress,
                 {kBam, static_cast<uint8_t>(size_), static_cast<uint8_t>(size_ >> 8), packets_, 0xFF, 0, 0, 0});
    put_pgn(f.data, pgn_);
  } else {
    f.id = {priority_, kPgnTpDt, sa_, kGlobalAddress};
    f.data.fill(0xFF);  // J1939-21: the last packet's unused bytes are 0xFF
    f.data[0] = static_cast<uint8_t>(sent_);
    const std::size_t offset = (sent_ - 1u) * 7u;
    const std::size_t n = std::min<std::size_t>(7, size_ - offset);
    std::copy_n(data_.begin() + static_cast<std::ptrdiff_t>(offset), n, f.data.begin() + 1);
  }
  f.id.priority = priority_;
  sent_++;
  return f;
}

// ---------------------------------------------------------- AddressClaimer

AddressClaimer::AddressClaimer(uint64_t name, uint8_t preferred)
    : name_(name), preferred_(preferred), address_(preferred) {}

Frame AddressClaimer::claim_frame() const {
  Frame f;
  f.id = {6, kPgnAddressClaimed, state_ == State::CannotClaim ? kNullAddress : address_, kGlobalAddress};
  f.data = name_to_bytes(name_);
  return f;
}

Frame AddressClaimer::start(int64_t now_ms) {
  address_ = preferred_;
  state_ = State::Claiming;
  claimed_at_ms_ = now_ms;
  return claim_frame();
}

bool AddressClaimer::on_frame(const Frame& frame, int64_t now_ms, Frame& reply) {
  if (frame.id.pgn == kPgnRequest && frame.len >= 3) {
    const uint32_t wanted = static_cast<uint32_t>(frame.data[0]) | static_cast<uint32_t>(frame.data[1]) << 8 |
                            static_cast<uint32_t>(frame.data[2]) << 16;
    const bool to_us = frame.id.da == kGlobalAddress || (state_ != State::CannotClaim && frame.id.da == address_);
    if (wanted != kPgnAddressClaimed || !to_us || state_ == State::Idle) return false;
    reply = claim_frame();
    return true;
  }
  if (frame.id.pgn != kPgnAddressClaimed || frame.len != 8) return false;
  const uint64_t name = name_from_bytes(std::span<const uint8_t, 8>(frame.data.data(), 8));
  if (name == name_) return false;  // our own claim, looped back
  for (std::size_t a = 0; a < taken_.size(); ++a)
    if (taken_[a] && names_[a] == name) taken_[a] = false;  // it moved (or gave up)
  const uint8_t sa = frame.id.sa;
  if (sa >= kNullAddress) return false;
  names_[sa] = name;
  taken_[sa] = true;
  if (sa != address_ || (state_ != State::Claiming && state_ != State::Claimed)) return false;
  if (name_ < name) {
    reply = claim_frame();  // ours is the lower NAME: we keep the address
    return true;
  }
  return lose(now_ms, reply);
}

bool AddressClaimer::lose(int64_t now_ms, Frame& reply) {
  lost_++;
  uint8_t free_address = kNullAddress;
  const bool arbitrary = (name_ >> 63) != 0;
  if (arbitrary && next_free_address(free_address)) {
    address_ = free_address;
    state_ = State::Claiming;
    claimed_at_ms_ = now_ms;
  } else {
    state_ = State::CannotClaim;
  }
  reply = claim_frame();
  return true;
}

bool AddressClaimer::next_free_address(uint8_t& address) const {
  // Walk the dynamic range from just above where we lost, wrapping once.
  const int span = kLastDynamicAddress - kFirstDynamicAddress + 1;
  const int start = address_ >= kFirstDynamicAddress && address_ <= kLastDynamicAddress
                        ? address_ - kFirstDynamicAddress + 1
                        : 0;
  for (int i = 0; i < span; ++i) {
    const int a = kFirstDynamicAddress + (start + i) % span;
    if (a != address_ && !taken_[static_cast<std::size_t>(a)]) {
      address = static_cast<uint8_t>(a);
      return true;
    }
  }
  return false;
}

void AddressClaimer::tick(int64_t now_ms) {
  if (state_ == State::Claiming && now_ms - claimed_at_ms_ >= kClaimWaitMs) state_ = State::Claimed;
}

uint8_t AddressClaimer::address_of(uint64_t name) const {
  for (std::size_t a = 0; a < taken_.size(); ++a)
    if (taken_[a] && names_[a] == name) return static_cast<uint8_t>(a);
  return kNullAddress;
}

std::optional<uint64_t> AddressClaimer::name_at(uint8_t address) const {
  if (address >= kNullAddress || !taken_[address]) return std::nullopt;
  return names_[address];
}

}  // namespace rise::firmware_protocol::j1939
