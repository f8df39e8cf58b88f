#include "hil/io/can_log_binary.hpp"
#include "hil/io/candump_log.hpp"

#include <pcap/pcap.h>
#include <zlib.h>

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <vector>

namespace rise::hil::io {

namespace {

constexpr uint8_t kClassicMaxLen = 8;

uint16_t le16(const uint8_t* p) { return static_cast<uint16_t>(p[0] | p[1] << 8); }
uint32_t le32(const uint8_t* p) { return static_cast<uint32_t>(le16(p)) | static_cast<uint32_t>(le16(p + 2)) << 16; }
uint64_t le64(const uint8_t* p) { return static_cast<uint64_t>(le32(p)) | static_cast<uint64_t>(le32(p + 4)) << 32; }
uint16_t be16(const uint8_t* p) { return static_cast<uint16_t>(p[0] << 8 | p[1]); }
uint32_t be32(const uint8_t* p) { return static_cast<uint32_t>(be16(p)) << 16 | be16(p + 2); }

// ---------------------------------------------------------------- BLF ----

// Object types and flags as python-can's blf.py names them.
constexpr uint32_t kLogContainer = 10;
constexpr uint32_t kCanMessage = 1;
constexpr uint32_t kCanErrorExt = 73;
constexpr uint32_t kCanMessage2 = 86;
constexpr uint32_t kCanFdMessage = 100;
constexpr uint32_t kCanFdMessage64 = 101;
constexpr uint16_t kNoCompression = 0;
constexpr uint16_t kZlibDeflate = 2;
constexpr uint32_t kCanMsgExt = 0x80000000u;
constexpr uint32_t kTimeTenMics = 1;
constexpr size_t kFileHeaderMin = 72;    // "<4sLBBBBBBBBQQLL8H8H"
constexpr size_t kObjBase = 16;          // "LOBJ", header size, version, object size, type
constexpr size_t kObjHeaderV1 = 16;      // flags, client index, object version, timestamp
constexpr size_t kObjHeaderV2 = 24;      // flags, timestamp status, object version, timestamp, original
constexpr size_t kContainerHeader = 16;  // compression method, uncompressed size
constexpr size_t kCanMsgSize = 16;       // channel, flags, dlc, id, 8 data
constexpr size_t kCanFdMsgSize = 84;     // channel, flags, dlc, id, frame length, bit count, FD flags, valid bytes, 64 data
constexpr size_t kCanFd64Size = 40;      // fixed part before the data
constexpr size_t kCanErrorExtSize = 32;
constexpr uint32_t kMaxContainer = 64u << 20;  // no real writer makes containers this big

constexpr size_t kStartTimeAt = 40;     // the header's start SYSTEMTIME

// A Windows SYSTEMTIME (year, month, weekday, day, hour, minute, second,
// ms) as µs since the Unix epoch; 0 when it is no date (python-can's
// systemtime_to_timestamp gives 0 then too). BLF keeps the logger's local
// time without its zone: it is taken as UTC, as python-can on a UTC machine.
int64_t systemtime_us(const uint8_t* p) {
  std::tm t{};
  t.tm_year = le16(p) - 1900;
  t.tm_mon = le16(p + 2) - 1;
  t.tm_mday = le16(p + 6);
  t.tm_hour = le16(p + 8);
  t.tm_min = le16(p + 10);
  t.tm_sec = le16(p + 12);
  const int ms = le16(p + 14);
  if (t.tm_year < 70 || t.tm_mon < 0 || t.tm_mon > 11 || t.tm_mday < 1 || t.tm_mday > 31 || t.tm_hour > 23 ||
      t.tm_min > 59 || t.tm_sec > 59 || ms > 999)
    return 0;
  return static_cast<int64_t>(::timegm(&t)) * 1000000 + ms * 1000;
}

bool is_lobj(const uint8_t* p) { return std::memcmp(p, "LOBJ", 4) == 0; }

class BlfLog final : public BinaryCanLog {
 public:
  explicit BlfLog(const std::string& path) : path_(path), in_(path, std::ios::binary) {
    if (!in_) throw std::runtime_error(path + ": cannot open: " + std::strerror(errno));
    uint8_t header[kFileHeaderMin];
    if (!in_.read(reinterpret_cast<char*>(header), sizeof header))
      throw std::runtime_error(path + ": BLF: file header cut short");
    in_.seekg(0, std::ios::end);
    file_size_ = static_cast<uint64_t>(std::max<std::streamoff>(in_.tellg(), 0));
    header_size_ = le32(header + 4);
    start_us_ = systemtime_us(header + kStartTimeAt);
    if (header_size_ < kFileHeaderMin) throw std::runtime_error(path + ": BLF: file header size " + std::to_string(header_size_));
    rewind();
  }

  Result next(CanLogRecord& record) override {
    for (;;) {
      const Located at = locate_object();
      if (at == Located::Garbage) return skip_malformed(record);
      if (at == Located::NeedMore || pos_ + le32(data_.data() + pos_ + 8) > data_.size()) {
        // The object goes on in the next container (or the file is cut there).
        switch (read_container()) {
          case Fill::Added: continue;
          case Fill::Broken: return malformed(record, data_.size());
          case Fill::End: return pos_ < data_.size() ? malformed(record, data_.size()) : Result::End;
        }
      }
      const uint8_t* obj = data_.data() + pos_;
      const uint32_t size = le32(obj + 8);
      if (size < kObjBase) return skip_malformed(record);
      pos_ += size;
      record.line = ++objects_;
      switch (parse_object(obj, size, record)) {
        case Parsed::Frame: return Result::Frame;
        case Parsed::Malformed: return Result::Malformed;
        case Parsed::Other: break;
      }
    }
  }

  void rewind() override {
    in_.clear();
    in_.seekg(static_cast<std::streamoff>(header_size_));
    consumed_ = header_size_;
    data_.clear();
    pos_ = 0;
    objects_ = 0;
    eof_ = false;
  }

  // The header and padding the file claims can run past its end (a cut file).
  uint64_t bytes_consumed() const override { return std::min(consumed_, file_size_); }

 private:
  enum class Parsed { Frame, Malformed, Other };

  enum class Located { Found, NeedMore, Garbage };
  enum class Fill { Added, Broken, End };

  // Objects are followed by padding that varies with the type: the next
  // "LOBJ" is within 8 bytes (where python-can looks for it).
  Located locate_object() {
    for (size_t p = pos_; p <= pos_ + 8 && p + 4 <= data_.size(); ++p) {
      if (!is_lobj(data_.data() + p)) continue;
      pos_ = p;
      return p + kObjBase <= data_.size() ? Located::Found : Located::NeedMore;
    }
    return pos_ + 12 > data_.size() ? Located::NeedMore : Located::Garbage;
  }

  // One malformed object: counted, and parsing goes on at the next "LOBJ".
  Result skip_malformed(CanLogRecord& record) {
    size_t p = pos_ + 1;
    while (p + 4 <= data_.size() && !is_lobj(data_.data() + p)) ++p;
    return malformed(record, p + 4 <= data_.size() ? p : data_.size());
  }

  Result malformed(CanLogRecord& record, size_t resume_at) {
    pos_ = resume_at;
    record.line = ++objects_;
    return Result::Malformed;
  }

  // Appends the next LOG_CONTAINER's objects to what is left unparsed.
  // Broken: its data does not decompress (what was pending is dropped, its
  // end is lost); End: the end of the file, or where it is cut or broken.
  Fill read_container() {
    while (!eof_) {
      uint8_t base[kObjBase];
      if (!in_.read(reinterpret_cast<char*>(base), sizeof base) || !is_lobj(base)) break;
      const uint32_t size = le32(base + 8);
      const uint32_t type = le32(base + 12);
      if (size < kObjBase || size > kMaxContainer) break;
      std::vector<uint8_t> body(size - kObjBase);
      if (!in_.read(reinterpret_cast<char*>(body.data()), static_cast<std::streamsize>(body.size()))) break;
      in_.ignore(size % 4);  // padding after the object
      consumed_ += size + size % 4;
      if (type != kLogContainer || body.size() < kContainerHeader) continue;
      data_.erase(data_.begin(), data_.begin() + static_cast<std::ptrdiff_t>(std::min(pos_, data_.size())));
      pos_ = 0;
      return append_container(body) ? Fill::Added : Fill::Broken;
    }
    eof_ = true;
    return Fill::End;
  }

  bool append_container(const std::vector<uint8_t>& body) {
    const uint16_t method = le16(body.data());
    const uint32_t uncompressed = le32(body.data() + 8);
    const uint8_t* payload = body.data() + kContainerHeader;
    const size_t payload_size = body.size() - kContainerHeader;
    if (method == kNoCompression) {
      data_.insert(data_.end(), payload, payload + payload_size);
      return true;
    }
    if (method != kZlibDeflate || uncompressed > kMaxContainer) return false;
    const size_t old = data_.size();
    data_.resize(old + uncompressed);
    uLongf out = uncompressed;
    if (uncompress(data_.data() + old, &out, payload, static_cast<uLong>(payload_size)) != Z_OK) {
      data_.resize(old);
      return false;
    }
    data_.resize(old + out);
    return true;
  }

  Parsed parse_object(const uint8_t* obj, uint32_t size, CanLogRecord& record) {
    const uint16_t version = le16(obj + 6);
    const uint32_t type = le32(obj + 12);
    const size_t header = kObjBase + (version == 1 ? kObjHeaderV1 : kObjHeaderV2);
    if ((version != 1 && version != 2) || size < header) return Parsed::Malformed;
    const uint32_t flags = le32(obj + kObjBase);
    const uint64_t stamp = le64(obj + kObjBase + 8);
    record.frame = CanFrame{};
    record.frame.timestamp_us = start_us_ + static_cast<int64_t>(flags == kTimeTenMics ? stamp * 10 : stamp / 1000);
    const uint8_t* body = obj + header;
    const size_t body_size = size - header;
    switch (type) {
      case kCanMessage:
      case kCanMessage2: return parse_can(body, body_size, record);
      case kCanFdMessage: return parse_can_fd(body, body_size, record);
      case kCanFdMessage64: return parse_can_fd64(body, body_size, record);
      case kCanErrorExt: return parse_error(body, body_size, record);
      default: return Parsed::Other;
    }
  }

  static void set_id(uint32_t raw, CanFrame& f) {
    f.extended = (raw & kCanMsgExt) != 0;
    f.id = raw & 0x1FFFFFFFu;
  }

  static bool valid_id(const CanFrame& f) { return f.extended || f.id <= 0x7FF; }

  static Parsed parse_can(const uint8_t* b, size_t n, CanLogRecord& record) {
    if (n < kCanMsgSize) return Parsed::Malformed;
    CanFrame& f = record.frame;
    record.channel = std::to_string(le16(b));
    record.tx = (b[2] & 0x01) != 0;
    f.remote = (b[2] & 0x80) != 0;
    set_id(le32(b + 4), f);
    // The DLC field can exceed 8 (python-can keeps it); a classic frame carries 8 bytes at most.
    f.len = std::min<uint8_t>(b[3], kClassicMaxLen);
    if (!f.remote) std::memcpy(f.data.data(), b + 8, f.len);
    return valid_id(f) ? Parsed::Frame : Parsed::Malformed;
  }

  static Parsed parse_can_fd(const uint8_t* b, size_t n, CanLogRecord& record) {
    if (n < kCanFdMsgSize) return Parsed::Malformed;
    CanFrame& f = record.frame;
    record.channel = std::to_string(le16(b));
    record.tx = (b[2] & 0x01) != 0;
    f.remote = (b[2] & 0x80) != 0;
    set_id(le32(b + 4), f);
    const uint8_t fd_flags = b[13];
    f.fd = (fd_flags & 0x1) != 0;
    f.brs = (fd_flags & 0x2) != 0;
    f.esi = (fd_flags & 0x4) != 0;
    const uint8_t valid = b[14];
    f.len = f.remote ? std::min<uint8_t>(b[3], kClassicMaxLen) : valid;
    if (f.len > (f.fd ? 64 : kClassicMaxLen) || (f.fd && !is_fd_length(f.len))) return Parsed::Malformed;
    if (!f.remote) std::memcpy(f.data.data(), b + 20, f.len);
    return valid_id(f) ? Parsed::Frame : Parsed::Malformed;
  }

  static Parsed parse_can_fd64(const uint8_t* b, size_t n, CanLogRecord& record) {
    if (n < kCanFd64Size) return Parsed::Malformed;
    CanFrame& f = record.frame;
    record.channel = std::to_string(b[0]);
    const uint8_t valid = b[2];
    set_id(le32(b + 4), f);
    const uint32_t flags = le32(b + 12);
    f.remote = (flags & 0x0010) != 0;
    f.fd = (flags & 0x1000) != 0;
    f.brs = (flags & 0x2000) != 0;
    f.esi = (flags & 0x4000) != 0;
    record.tx = b[34] != 0;
    f.len = f.remote ? std::min<uint8_t>(b[1], kClassicMaxLen) : valid;
    if (f.len > (f.fd ? 64 : kClassicMaxLen) || (f.fd && !is_fd_length(f.len))) return Parsed::Malformed;
    if (kCanFd64Size + (f.remote ? 0 : f.len) > n) return Parsed::Malformed;
    if (!f.remote) std::memcpy(f.data.data(), b + kCanFd64Size, f.len);
    return valid_id(f) ? Parsed::Frame : Parsed::Malformed;
  }

  // An error frame without a SocketCAN error class (BLF carries Vector's
  // own error codes): id 0 and 8 zero bytes, as the ASC reader gives.
  static Parsed parse_error(const uint8_t* b, size_t n, CanLogRecord& record) {
    if (n < kCanErrorExtSize) return Parsed::Malformed;
    record.channel = std::to_string(le16(b));
    record.frame.error = true;
    record.frame.len = kClassicMaxLen;
    return Parsed::Frame;
  }

  std::string path_;
  std::ifstream in_;
  uint32_t header_size_ = 0;
  int64_t start_us_ = 0;  // the measurement's start, 0 when the header has none
  uint64_t consumed_ = 0;
  uint64_t file_size_ = 0;
  std::vector<uint8_t> data_;  // decompressed objects not yet parsed
  size_t pos_ = 0;
  int objects_ = 0;
  bool eof_ = false;
};

// ------------------------------------------------------- pcap, pcapng ----

constexpr int kDltCanSocketcan = 227;
constexpr int kDltLinuxSll = 113;
constexpr int kDltLinuxSll2 = 276;
constexpr uint16_t kSllProtoCan = 0x000C;
constexpr uint16_t kSllProtoCanFd = 0x000D;
constexpr uint8_t kPacketOutgoing = 4;
constexpr size_t kSllHeader = 16;
constexpr size_t kSll2Header = 20;
constexpr uint32_t kEffFlag = 0x80000000u;
constexpr uint32_t kRtrFlag = 0x40000000u;
constexpr uint32_t kErrFlag = 0x20000000u;
constexpr size_t kCanMtu = 16;
constexpr size_t kCanFdMtu = 72;
constexpr uint8_t kCanFdBrs = 0x01;
constexpr uint8_t kCanFdEsi = 0x02;
constexpr uint8_t kCanFdFdf = 0x04;

// struct can_frame / canfd_frame as libpcap stores them: CAN id, length,
// FD flags, two reserved bytes, data. The id is in network byte order for
// link type 227 (libpcap turns it so) but in the capturing machine's order
// (little-endian on every machine we meet) in cooked captures, as a real
// tcpdump -i any capture of vcan shows (tests/vcan/capture_vm_test.cpp) and
// Wireshark reads it. libpcap 1.10 writes the FD flags of a 227 capture as
// zero: CAN FD is then told by the length (CANFD_MTU), BRS and ESI are lost.
bool parse_socketcan(const uint8_t* p, size_t n, bool fd, bool host_order_id, CanFrame& f) {
  if (n < 8) return false;
  const uint32_t raw = host_order_id ? le32(p) : be32(p);
  f.extended = (raw & kEffFlag) != 0;
  f.remote = (raw & kRtrFlag) != 0;
  f.error = (raw & kErrFlag) != 0;
  f.id = raw & (f.extended ? 0x1FFFFFFFu : f.error ? 0x1FFFFFFFu : 0x7FFu);
  if (!f.extended && !f.error && (raw & 0x1FFFF800u) != 0) return false;
  f.len = p[4];
  fd = fd || n == kCanFdMtu || (p[5] & kCanFdFdf) != 0;
  f.fd = fd && !f.error;
  f.brs = f.fd && (p[5] & kCanFdBrs) != 0;
  f.esi = f.fd && (p[5] & kCanFdEsi) != 0;
  if (f.len > (f.fd ? 64 : kClassicMaxLen) || (f.fd && !is_fd_length(f.len))) return false;
  if (f.remote) return true;
  if (8 + static_cast<size_t>(f.len) > n) return false;
  std::memcpy(f.data.data(), p + 8, f.len);
  return true;
}

class PcapLog final : public BinaryCanLog {
 public:
  explicit PcapLog(const std::string& path) : path_(path) { open(); }
  ~PcapLog() override { close(); }
  PcapLog(const PcapLog&) = delete;
  PcapLog& operator=(const PcapLog&) = delete;

  Result next(CanLogRecord& record) override {
    while (!done_) {
      pcap_pkthdr* header = nullptr;
      const u_char* packet = nullptr;
      const int rc = pcap_next_ex(pcap_, &header, &packet);
      if (rc == PCAP_ERROR_BREAK) {
        done_ = true;
        return Result::End;
      }
      record.line = ++packets_;
      if (rc != 1) {  // a cut or broken record: libpcap cannot go on past it
        done_ = true;
        return Result::Malformed;
      }
      record.frame = CanFrame{};
      record.channel.clear();
      record.tx = false;
      switch (decode(packet, header->caplen, record)) {
        case Decoded::Frame: break;
        case Decoded::Malformed: return Result::Malformed;
        case Decoded::NotCan: continue;
      }
      const auto time_us = capture_time_us(header->ts.tv_sec, header->ts.tv_usec);
      if (!time_us) return Result::Malformed;  // a time no candump line can carry
      record.frame.timestamp_us = *time_us;
      return Result::Frame;
    }
    return Result::End;
  }

  void rewind() override {
    close();
    open();
  }

  uint64_t bytes_consumed() const override {
    if (done_) return size_;
    const long at = std::ftell(pcap_file(pcap_));
    return at < 0 ? 0 : static_cast<uint64_t>(at);
  }

 private:
  enum class Decoded { Frame, Malformed, NotCan };

  void open() {
    char error[PCAP_ERRBUF_SIZE] = "";
    pcap_ = pcap_open_offline_with_tstamp_precision(path_.c_str(), PCAP_TSTAMP_PRECISION_MICRO, error);
    if (!pcap_) throw std::runtime_error(path_ + ": pcap: " + error);
    link_ = pcap_datalink(pcap_);
    if (link_ != kDltCanSocketcan && link_ != kDltLinuxSll && link_ != kDltLinuxSll2) {
      const char* name = pcap_datalink_val_to_name(link_);
      close();
      throw std::runtime_error(path_ + ": pcap: link type " + std::to_string(link_) + " (" +
                               (name ? name : "?") + ") is not SocketCAN (227, or Linux cooked SLL/SLL2)");
    }
    std::error_code ec;
    size_ = static_cast<uint64_t>(std::filesystem::file_size(path_, ec));
    packets_ = 0;
    done_ = false;
  }

  void close() {
    if (pcap_) pcap_close(pcap_);
    pcap_ = nullptr;
  }

  // A cooked capture (tcpdump -i any) holds every protocol: only CAN and
  // CAN FD packets are frames, the rest is passed over.
  Decoded decode(const u_char* p, uint32_t n, CanLogRecord& record) {
    uint16_t protocol = kSllProtoCan;
    uint8_t packet_type = 0;
    if (link_ == kDltLinuxSll) {
      if (n < kSllHeader) return Decoded::Malformed;
      packet_type = static_cast<uint8_t>(be16(p));
      protocol = be16(p + 14);
      p += kSllHeader;
      n -= static_cast<uint32_t>(kSllHeader);
    } else if (link_ == kDltLinuxSll2) {
      if (n < kSll2Header) return Decoded::Malformed;
      protocol = be16(p);
      packet_type = p[10];
      p += kSll2Header;
      n -= static_cast<uint32_t>(kSll2Header);
    }
    if (protocol != kSllProtoCan && protocol != kSllProtoCanFd) return Decoded::NotCan;
    record.tx = packet_type == kPacketOutgoing;
    const bool fd = link_ != kDltCanSocketcan && protocol == kSllProtoCanFd;
    if (n != kCanMtu && n != kCanFdMtu && !fd) return Decoded::Malformed;
    return parse_socketcan(p, n, fd, link_ != kDltCanSocketcan, record.frame) ? Decoded::Frame : Decoded::Malformed;
  }

  std::string path_;
  pcap_t* pcap_ = nullptr;
  int link_ = 0;
  int packets_ = 0;
  uint64_t size_ = 0;
  bool done_ = false;
};

}  // namespace

std::unique_ptr<BinaryCanLog> open_binary_can_log(const std::string& path, CanLogFormat& format) {
  uint8_t magic[4] = {};
  {
    std::ifstream in(path, std::ios::binary);
    if (!in.read(reinterpret_cast<char*>(magic), sizeof magic)) return nullptr;
  }
  if (std::memcmp(magic, "LOGG", 4) == 0) {
    format = CanLogFormat::VectorBlf;
    return std::make_unique<BlfLog>(path);
  }
  const uint32_t m = le32(magic);
  constexpr uint32_t kPcapMicro = 0xa1b2c3d4u, kPcapNano = 0xa1b23c4du, kPcapng = 0x0a0d0d0au;
  const uint32_t b = be32(magic);  // written on a machine of the other byte order
  if (m == kPcapMicro || m == kPcapNano || b == kPcapMicro || b == kPcapNano) {
    format = CanLogFormat::Pcap;
    return std::make_unique<PcapLog>(path);
  }
  if (m == kPcapng) {
    format = CanLogFormat::Pcapng;
    return std::make_unique<PcapLog>(path);
  }
  return nullptr;
}

}  // namespace rise::hil::io
