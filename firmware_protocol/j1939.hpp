#pragma once

// SAE J1939 on the wire, without I/O: the 29-bit identifier (J1939-21 5.2),
// the 64-bit NAME (J1939-81 4.1), the transport protocol that carries a
// message of 9..1785 bytes in 8-byte packets (J1939-21 5.10: BAM to all,
// RTS/CTS to one address) and address claim (J1939-81 4.5). The bridge runs
// these over a raw CAN bus, so they work on any CanBus (socketcan, slcan,
// socketcand, replay) and the kernel's own J1939 stack is a peer, not a need.
//
// Identifier, worked example: 0x18FEF121 = priority 6, PGN 0xFEF1 (PDU2, a
// broadcast: PF 0xFE >= 240, PS 0xF1 is the group extension), SA 0x21.
// 0x18EA2521 = priority 6, PGN 0xEA00 (Request, PDU1: PF 0xEA < 240), DA
// 0x25, SA 0x21.
//
// Nothing here allocates or throws once constructed: safe in the cyclic path.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

namespace rise::firmware_protocol::j1939 {

inline constexpr uint8_t kNullAddress = 254;    ///< "no address" (cannot claim)
inline constexpr uint8_t kGlobalAddress = 255;  ///< destination: everyone
inline constexpr uint32_t kPgnRequest = 0xEA00;
inline constexpr uint32_t kPgnAddressClaimed = 0xEE00;
inline constexpr uint32_t kPgnTpCm = 0xEC00;  ///< transport connection management
inline constexpr uint32_t kPgnTpDt = 0xEB00;  ///< transport data transfer
inline constexpr std::size_t kMaxTpBytes = 1785;  ///< 255 packets of 7 bytes

/// An identifier taken apart. For a PDU1 PGN (PF < 240) `pgn` has its low
/// byte zero and `da` is the destination; for PDU2 `da` is kGlobalAddress.
struct Id {
  uint8_t priority = 6;  ///< 0 (highest) .. 7
  uint32_t pgn = 0;      ///< 18 bits: EDP, DP, PF, PS (PS zeroed for PDU1)
  uint8_t sa = kNullAddress;
  uint8_t da = kGlobalAddress;
};

/// PF < 240: the PS byte is a destination address.
constexpr bool is_pdu1(uint32_t pgn) { return ((pgn >> 8) & 0xFF) < 240; }
/// The PGN of a 29-bit identifier (what a J1939 DBC's BO_ id carries in
/// bits 8..25), the destination byte zeroed for PDU1.
uint32_t pgn_of(uint32_t can_id);
Id decode_id(uint32_t can_id);
/// The 29-bit identifier; for PDU1 `da` goes into PS, for PDU2 PS stays the
/// PGN's group extension and `da` is ignored.
uint32_t encode_id(const Id& id);

/// The 64-bit NAME (J1939-81 4.1.1), least significant byte first on the
/// wire. A lower value wins address contention.
struct Name {
  uint32_t identity = 0;           ///< 21 bits
  uint16_t manufacturer = 0;       ///< 11 bits
  uint8_t ecu_instance = 0;        ///< 3 bits
  uint8_t function_instance = 0;   ///< 5 bits
  uint8_t function = 0;            ///< 8 bits
  uint8_t vehicle_system = 0;      ///< 7 bits
  uint8_t vehicle_system_instance = 0;  ///< 4 bits
  uint8_t industry_group = 0;      ///< 3 bits
  bool arbitrary_address_capable = false;

  uint64_t pack() const;
  static Name unpack(uint64_t raw);
};
uint64_t name_from_bytes(std::span<const uint8_t, 8> data);
std::array<uint8_t, 8> name_to_bytes(uint64_t name);

/// One frame to go out (or that came in), in J1939 terms.
struct Frame {
  Id id;
  std::array<uint8_t, 8> data{};
  uint8_t len = 8;
};

// ---------------------------------------------------------------- transport

/// Why a transport session ended without its message (J1939-21 5.10.3.5
/// abort reasons where they apply).
enum class TpDrop : uint8_t {
  AbortReceived,  ///< the sender aborted (TP.Conn_Abort)
  Timeout,        ///< T1/T2 passed without the next packet
  OutOfOrder,     ///< a BAM packet skipped a sequence number: the gap cannot be filled
  Replaced,       ///< a new announcement from the same sender replaced an unfinished one
  BadAnnouncement,  ///< size < 9 or > 1785, or packets that do not fit the size
  NoSession,      ///< more sessions at once than the receiver holds
};
inline constexpr std::size_t kTpDropCount = 6;

struct TpCounters {
  uint64_t messages = 0;      ///< reassembled
  uint64_t duplicates = 0;    ///< a packet already taken: dropped, session goes on
  uint64_t out_of_order = 0;  ///< a packet ahead of the next expected one: dropped
  uint64_t stray = 0;         ///< a TP.DT or CTS/EOMA no session waits for
  std::array<uint64_t, kTpDropCount> dropped{};  ///< sessions lost, by TpDrop
};

/// A reassembled message. `data` points into the reassembler: valid until
/// its next call.
struct TpMessage {
  uint32_t pgn = 0;
  uint8_t sa = kNullAddress;
  uint8_t da = kGlobalAddress;
  std::span<const uint8_t> data;
};

/// What one frame did to the reassembler: a message it completed, and a
/// frame to answer with (CTS, end-of-message ack or abort; RTS/CTS only).
struct TpResult {
  std::optional<TpMessage> message;
  std::optional<Frame> reply;
};

/// The receiving side of the transport protocol for one node at `own`
/// address: BAM from anyone, RTS/CTS addressed to `own`. Holds up to
/// kSessions messages in flight (one per sender and kind, J1939-21 5.10.3).
class TpReceiver {
 public:
  static constexpr std::size_t kSessions = 8;
  static constexpr int64_t kT1Ms = 750;   ///< between data packets
  static constexpr int64_t kT2Ms = 1250;  ///< after a CTS until its first packet

  /// Our address, whose RTS/CTS sessions we answer; kNullAddress = none
  /// (only BAM is taken). Changing it drops the RTS/CTS sessions to the old one.
  void set_own_address(uint8_t own);
  /// One received frame whose PGN is TP.CM or TP.DT (others: empty result).
  TpResult on_frame(const Frame& frame, int64_t now_ms);
  /// Ends sessions whose timer ran out; writes an abort for each RTS/CTS
  /// one into `aborts`, returns how many.
  std::size_t expire(int64_t now_ms, std::span<Frame> aborts);
  const TpCounters& counters() const { return counters_; }

 private:
  struct Session {
    bool active = false;
    bool bam = false;
    uint8_t sa = 0, da = 0;
    uint32_t pgn = 0;
    uint16_t size = 0;
    uint8_t packets = 0;
    uint8_t next = 1;        ///< sequence number expected next
    uint8_t window_end = 0;  ///< RTS/CTS: last packet of the current CTS
    uint8_t max_per_cts = 255;
    int64_t deadline_ms = 0;
    std::array<uint8_t, kMaxTpBytes> data{};
  };
  TpResult on_cm(const Frame& frame, int64_t now_ms);
  TpResult on_dt(const Frame& frame, int64_t now_ms);
  TpResult on_announce(const Frame& frame, bool bam, int64_t now_ms);
  Session* find(uint8_t sa, uint8_t da, bool bam);
  void drop(Session& s, TpDrop why);
  Frame cts(const Session& s) const;
  Frame abort_frame(const Session& s, uint8_t reason) const;

  uint8_t own_ = kNullAddress;
  std::array<Session, kSessions> sessions_{};
  TpCounters counters_;
};

/// The sending side of BAM (a broadcast of 9..1785 bytes): TP.CM_BAM, then
/// one TP.DT per call of next() (J1939-21 wants 50..200 ms between them).
class BamSender {
 public:
  /// Starts a broadcast of `data` with PGN `pgn` from `sa`; false when the
  /// size is outside 9..1785.
  bool start(uint32_t pgn, uint8_t sa, std::span<const uint8_t> data, uint8_t priority = 7);
  bool busy() const { return sent_ <= packets_ && packets_ > 0; }
  /// The next frame of the broadcast (the announcement first), or nothing
  /// when it is done.
  std::optional<Frame> next();

 private:
  std::array<uint8_t, kMaxTpBytes> data_{};
  uint16_t size_ = 0;
  uint8_t packets_ = 0;
  uint16_t sent_ = 0;  ///< 0 = announcement not yet sent
  uint32_t pgn_ = 0;
  uint8_t sa_ = kNullAddress;
  uint8_t priority_ = 7;
};

// ------------------------------------------------------------ address claim

/// One node's address claim (J1939-81 4.5): claims `preferred` with its
/// NAME, answers requests for the claim, defends its address against a
/// higher NAME and, beaten by a lower one, moves to a free address in
/// 128..247 when arbitrary-address capable (else gives up: Cannot Claim).
/// Also keeps the address of every NAME it hears claim, so that a peer is
/// followed by NAME when it changes address.
class AddressClaimer {
 public:
  static constexpr int64_t kClaimWaitMs = 250;  ///< J1939-81 4.5.2: before the address is used
  enum class State : uint8_t { Idle, Claiming, Claimed, CannotClaim };

  AddressClaimer(uint64_t name, uint8_t preferred);

  /// Starts (or restarts) the claim: the frame to send.
  Frame start(int64_t now_ms);
  /// A received frame (any PGN; only requests for the claim and claims are
  /// looked at). Writes a reply into `reply` and returns true when one is due.
  bool on_frame(const Frame& frame, int64_t now_ms, Frame& reply);
  /// Advances Claiming to Claimed once kClaimWaitMs passed without contention.
  void tick(int64_t now_ms);

  State state() const { return state_; }
  /// The address while Claimed, else kNullAddress.
  uint8_t address() const { return state_ == State::Claimed ? address_ : kNullAddress; }
  uint64_t name() const { return name_; }
  /// Where `name` last claimed, or kNullAddress when it never did or gave
  /// its address up (Cannot Claim).
  uint8_t address_of(uint64_t name) const;
  /// The NAME that last claimed `address`, if any.
  std::optional<uint64_t> name_at(uint8_t address) const;
  /// Claims lost to a lower NAME so far (each moved us or made us give up).
  uint64_t contentions_lost() const { return lost_; }

 private:
  Frame claim_frame() const;
  bool lose(int64_t now_ms, Frame& reply);
  bool next_free_address(uint8_t& address) const;

  uint64_t name_;
  uint8_t preferred_;
  uint8_t address_;
  State state_ = State::Idle;
  int64_t claimed_at_ms_ = 0;
  uint64_t lost_ = 0;
  std::array<uint64_t, 254> names_{};  ///< NAME heard at each address
  std::array<bool, 254> taken_{};
};

}  // namespace rise::firmware_protocol::j1939
