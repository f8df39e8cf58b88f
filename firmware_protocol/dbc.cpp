#include "firmware_protocol/dbc.hpp"

#include <algorithm>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>

namespace rise::firmware_protocol {
namespace {

constexpr uint32_t kExtendedFlag = 0x80000000u;  // bit 31 of a BO_ id (Vector convention)
constexpr uint32_t kExtendedIdMask = 0x1FFFFFFFu;
constexpr uint32_t kStandardIdMax = 0x7FFu;
constexpr uint32_t kMaxFrameBytes = 64;  // CAN FD
// Vector's container for signals not placed in any frame (id 0xC0000000). Its
// signal names may repeat and it is never on the bus.
constexpr std::string_view kIndependentSignals = "VECTOR__INDEPENDENT_SIG_MSG";
constexpr uint32_t kIndependentSignalsId = 0xC0000000u;

enum class TokenKind : uint8_t { Identifier, Number, String, Punct, End };

struct Token {
  TokenKind kind = TokenKind::End;
  std::string_view text;  // for String: between the quotes, escapes not yet resolved
  int line = 0;
  bool line_start = false;  // first token on its line
};

// Statement keywords of the DBC grammar. Skipping an unknown statement stops
// at ';' or at one of these at the start of a line, so a statement without a
// terminator cannot swallow the next one.
// clang-format off
constexpr std::string_view kKeywords[] = {
    "VERSION", "NS_", "NS_DESC_", "BS_", "BU_", "BO_", "SG_", "EV_", "CM_", "BA_DEF_", "BA_", "VAL_",
    "CAT_DEF_", "CAT_", "FILTER", "BA_DEF_DEF_", "EV_DATA_", "ENVVAR_DATA_", "SGTYPE_", "SGTYPE_VAL_",
    "BA_DEF_SGTYPE_", "BA_SGTYPE_", "SIG_TYPE_REF_", "VAL_TABLE_", "SIG_GROUP_", "SIG_VALTYPE_",
    "SIGTYPE_VALTYPE_", "BO_TX_BU_", "BA_DEF_REL_", "BA_REL_", "BA_DEF_DEF_REL_", "BU_SG_REL_",
    "BU_EV_REL_", "BU_BO_REL_", "SG_MUL_VAL_"};
// clang-format on

bool is_keyword(std::string_view word) {
  return std::find(std::begin(kKeywords), std::end(kKeywords), word) != std::end(kKeywords);
}

bool is_ident_start(char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_'; }
bool is_ident_char(char c) { return is_ident_start(c) || (c >= '0' && c <= '9'); }
bool is_digit(char c) { return c >= '0' && c <= '9'; }

std::string unescape(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '\\' && i + 1 < s.size()) ++i;
    out.push_back(s[i]);
  }
  return out;
}

uint32_t big_endian_msb_position(uint32_t start_bit) {
  // DBC numbers Motorola start bits in "sawtooth" order (bit 7 of byte 0 is
  // 7, bit 0 of byte 1 is 8); the signal runs from that MSB towards byte 0's
  // bit 0, then on into bit 7 of the next byte. In a big-endian linear
  // numbering (bit 0 = MSB of byte 0) it is one contiguous run.
  return (start_bit / 8) * 8 + (7 - start_bit % 8);
}

struct ParsedDbc {
  std::string version;
  std::vector<std::string> nodes;
  std::vector<DbcMessage> messages;
};

// Const or mutable, as the vector is.
template <typename Messages>
auto find_message(Messages& messages, uint32_t id, bool extended) -> decltype(&messages.front()) {
  for (auto& m : messages)
    if (m.id == id && m.extended == extended && m.name != kIndependentSignals) return &m;
  return nullptr;
}

// Turns DBC text into messages; one instance per parse.
class DbcParser {
 public:
  DbcParser(std::string_view text, const std::string& file) : text_(text), file_(file) {}

  ParsedDbc run() {
    tokenize();
    while (peek().kind != TokenKind::End) statement();
    return std::move(db_);
  }

 private:
  std::string_view text_;
  const std::string& file_;
  std::vector<Token> tokens_;
  std::size_t pos_ = 0;
  ParsedDbc db_;
  DbcMessage* current_ = nullptr;  // the BO_ that following SG_ lines belong to

  [[noreturn]] void fail(int line, std::string_view key, std::string_view message) const {
    std::ostringstream out;
    out << file_ << ':' << line << ": " << key << ": " << message;
    throw std::runtime_error(out.str());
  }

  // ---- tokenizer ---------------------------------------------------------
  void tokenize() {
    int line = 1;
    bool line_start = true;
    std::size_t i = 0;
    const std::size_t n = text_.size();
    auto push = [&](TokenKind kind, std::size_t begin, std::size_t end, int token_line) {
      tokens_.push_back(Token{kind, text_.substr(begin, end - begin), token_line, line_start});
      line_start = false;
    };
    while (i < n) {
      const char c = text_[i];
      if (c == '\n') {
        ++line;
        line_start = true;
        ++i;
        continue;
      }
      if (c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v') {
        ++i;
        continue;
      }
      if (c == '/' && i + 1 < n && text_[i + 1] == '/') {  // comment to end of line
        while (i < n && text_[i] != '\n') ++i;
        continue;
      }
      if (c == '"') {
        const int start_line = line;
        std::size_t j = i + 1;
        while (j < n && text_[j] != '"') {
          if (text_[j] == '\\' && j + 1 < n) ++j;
          if (text_[j] == '\n') ++line;  // comments may span lines
          ++j;
        }
        if (j >= n) fail(start_line, "string", "unterminated string");
        // A token after a multi-line string continues its statement: it is
        // on a later line but not a line start.
        push(TokenKind::String, i + 1, j, start_line);
        i = j + 1;
        continue;
      }
      if (is_ident_start(c)) {
        std::size_t j = i + 1;
        while (j < n && is_ident_char(text_[j])) ++j;
        push(TokenKind::Identifier, i, j, line);
        i = j;
        continue;
      }
      const bool sign = (c == '-' || c == '+');
      const std::size_t digits_at = sign ? i + 1 : i;
      if (digits_at < n && (is_digit(text_[digits_at]) || (text_[digits_at] == '.' && digits_at + 1 < n &&
                                                           is_digit(text_[digits_at + 1])))) {
        std::size_t j = digits_at;
        while (j < n && is_digit(text_[j])) ++j;
        if (j < n && text_[j] == '.') {
          ++j;
          while (j < n && is_digit(text_[j])) ++j;
        }
        if (j < n && (text_[j] == 'e' || text_[j] == 'E')) {
          std::size_t k = j + 1;
          if (k < n && (text_[k] == '+' || text_[k] == '-')) ++k;
          if (k < n && is_digit(text_[k])) {
            while (k < n && is_digit(text_[k])) ++k;
            j = k;
          }
        }
        push(TokenKind::Number, i, j, line);
        i = j;
        continue;
      }
      push(TokenKind::Punct, i, i + 1, line);
      ++i;
    }
    tokens_.push_back(Token{TokenKind::End, {}, line, true});
  }

  // ---- token access ------------------------------------------------------
  const Token& peek(std::size_t ahead = 0) const {
    return tokens_[std::min(pos_ + ahead, tokens_.size() - 1)];
  }
  Token take() {
    const Token t = peek();
    if (pos_ < tokens_.size() - 1) ++pos_;
    return t;
  }
  static bool is_punct(const Token& t, char c) {
    return t.kind == TokenKind::Punct && t.text.size() == 1 && t.text[0] == c;
  }
  static std::string describe(const Token& t) {
    switch (t.kind) {
      case TokenKind::End:
        return "end of file";
      case TokenKind::String:
        return "string \"" + std::string(t.text) + "\"";
      default:
        return "'" + std::string(t.text) + "'";
    }
  }
  void expect_punct(char c, std::string_view key) {
    const Token t = take();
    if (!is_punct(t, c)) fail(t.line, key, std::string("expected '") + c + "', found " + describe(t));
  }
  Token expect(TokenKind kind, std::string_view what, std::string_view key) {
    const Token t = take();
    if (t.kind != kind) fail(t.line, key, "expected " + std::string(what) + ", found " + describe(t));
    return t;
  }
  // Whether `t` belongs to the statement that started on `line` (the grammar
  // of BU_, BO_ and SG_ is line-oriented).
  static bool same_line(const Token& t, int line) {
    return t.kind != TokenKind::End && t.line == line && !t.line_start;
  }

  template <typename T>
  T integer(const Token& t, std::string_view what, std::string_view key) const {
    if (t.kind != TokenKind::Number)
      fail(t.line, key, "expected " + std::string(what) + ", found " + describe(t));
    std::string_view s = t.text;
    if (!s.empty() && s.front() == '+') s.remove_prefix(1);
    T value{};
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
    if (ec != std::errc{} || end != s.data() + s.size())
      fail(t.line, key, std::string(what) + " '" + std::string(t.text) + "' is not an integer in range");
    return value;
  }
  double real(const Token& t, std::string_view what, std::string_view key) const {
    if (t.kind != TokenKind::Number)
      fail(t.line, key, "expected " + std::string(what) + ", found " + describe(t));
    std::string_view s = t.text;
    if (!s.empty() && s.front() == '+') s.remove_prefix(1);
    double value = 0.0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
    if (ec != std::errc{} || end != s.data() + s.size() || !std::isfinite(value))
      fail(t.line, key, std::string(what) + " '" + std::string(t.text) + "' is not a finite number");
    return value;
  }

  // Skips to the end of a statement this reader does not interpret.
  void skip_statement() {
    while (peek().kind != TokenKind::End) {
      const Token& t = peek();
      if (is_punct(t, ';')) {
        take();
        return;
      }
      if (t.line_start && t.kind == TokenKind::Identifier && is_keyword(t.text)) return;
      take();
    }
  }

  // ---- statements --------------------------------------------------------
  void statement() {
    const Token t = take();
    if (is_punct(t, ';')) return;  // stray terminator
    if (t.kind != TokenKind::Identifier)
      fail(t.line, "statement", "expected a keyword, found " + describe(t));
    const std::string_view kw = t.text;
    if (kw != "SG_") current_ = nullptr;
    if (kw == "VERSION") return version(t);
    if (kw == "NS_") return new_symbols(t);
    if (kw == "BS_") return bit_timing(t);
    if (kw == "BU_") return nodes(t);
    if (kw == "BO_") return message(t);
    if (kw == "SG_") return signal(t);
    if (kw == "VAL_") return value_names(t);
    if (kw == "SIG_VALTYPE_") return value_type(t);
    if (kw == "BA_") return attribute();
    skip_statement();  // CM_, BA_DEF_, VAL_TABLE_, ... and keywords of newer tools
  }

  void version(const Token& kw) {
    const Token t = take();
    if (t.kind != TokenKind::String || t.line != kw.line)
      fail(kw.line, "VERSION", "expected a quoted version");
    db_.version = unescape(t.text);
  }

  void new_symbols(const Token& kw) {
    if (is_punct(peek(), ':')) take();
    // The list of symbols: names on the NS_ line, then one name per line.
    while (peek().kind == TokenKind::Identifier) {
      const Token& t = peek();
      const bool on_ns_line = t.line == kw.line;
      const bool alone = t.line_start && peek(1).line_start;
      if (!on_ns_line && !alone) break;
      take();
    }
  }

  void bit_timing(const Token& kw) {
    while (same_line(peek(), kw.line)) take();  // "BS_: [baudrate : BTR1 , BTR2]"
  }

  void nodes(const Token& kw) {
    expect_punct(':', "BU_");
    while (same_line(peek(), kw.line)) {
      const Token t = take();
      if (t.kind != TokenKind::Identifier) fail(t.line, "BU_", "expected a node name, found " + describe(t));
      db_.nodes.emplace_back(t.text);
    }
  }

  void message(const Token& kw) {
    const Token id_token = take();
    const auto raw_id = integer<uint32_t>(id_token, "message id", "BO_");
    const std::string key = "BO_ " + std::string(id_token.text);
    DbcMessage m;
    m.line = kw.line;
    m.extended = (raw_id & kExtendedFlag) != 0;
    m.id = m.extended ? (raw_id & kExtendedIdMask) : raw_id;
    if (!m.extended && m.id > kStandardIdMax)
      fail(id_token.line, key, "standard id exceeds 11 bits (extended ids have bit 31 set)");
    m.name = expect(TokenKind::Identifier, "message name", key).text;
    expect_punct(':', key);
    const auto dlc = integer<uint32_t>(take(), "length", key);
    if (dlc > kMaxFrameBytes) fail(kw.line, key, "length " + std::to_string(dlc) + " exceeds 64 bytes");
    m.dlc = static_cast<uint8_t>(dlc);
    if (same_line(peek(), kw.line)) m.transmitter = expect(TokenKind::Identifier, "transmitter", key).text;
    if (same_line(peek(), kw.line)) fail(kw.line, key, "unexpected " + describe(peek()));
    if (m.name != kIndependentSignals && find_message(db_.messages, m.id, m.extended) != nullptr)
      fail(kw.line, key, "duplicate message id");
    db_.messages.push_back(std::move(m));
    current_ = &db_.messages.back();
  }

  void signal(const Token& kw) {
    DbcMessage* m = current_;
    const Token name_token = expect(TokenKind::Identifier, "signal name", "SG_");
    const std::string key = "SG_ " + std::string(name_token.text);
    if (m == nullptr) fail(kw.line, key, "signal outside a BO_ message");
    DbcSignal s;
    s.name = name_token.text;
    s.line = kw.line;
    if (peek().kind == TokenKind::Identifier) {
      const std::string_view mux = take().text;
      if (mux == "M") {
        s.is_multiplexer = true;
      } else if (mux.size() >= 2 && mux[0] == 'm' && is_digit(mux[1])) {
        std::string_view digits = mux.substr(1);
        if (digits.back() == 'M') {  // "mNM": extended multiplexing, itself a multiplexer
          s.is_multiplexer = true;
          digits.remove_suffix(1);
        }
        const auto [end, ec] =
            std::from_chars(digits.data(), digits.data() + digits.size(), s.multiplexer_value);
        if (ec != std::errc{} || end != digits.data() + digits.size())
          fail(kw.line, key, "bad multiplexer indicator '" + std::string(mux) + "'");
        s.is_multiplexed = true;
      } else {
        fail(kw.line, key, "bad multiplexer indicator '" + std::string(mux) + "'");
      }
    }
    expect_punct(':', key);
    s.start_bit = integer<uint32_t>(take(), "start bit", key);
    expect_punct('|', key);
    s.length_bits = integer<uint32_t>(take(), "length", key);
    expect_punct('@', key);
    const auto order = integer<uint32_t>(take(), "byte order", key);
    if (order > 1) fail(kw.line, key, "byte order must be 0 (Motorola) or 1 (Intel)");
    s.byte_order = order == 1 ? ByteOrder::LittleEndian : ByteOrder::BigEndian;
    const Token sign = take();
    if (!is_punct(sign, '+') && !is_punct(sign, '-'))
      fail(kw.line, key, "expected '+' or '-', found " + describe(sign));
    s.is_signed = is_punct(sign, '-');
    expect_punct('(', key);
    s.factor = real(take(), "factor", key);
    expect_punct(',', key);
    s.offset = real(take(), "offset", key);
    expect_punct(')', key);
    expect_punct('[', key);
    s.minimum = real(take(), "minimum", key);
    expect_punct('|', key);
    s.maximum = real(take(), "maximum", key);
    expect_punct(']', key);
    s.unit = unescape(expect(TokenKind::String, "unit", key).text);
    while (same_line(peek(), kw.line)) {
      const Token t = take();
      if (is_punct(t, ',')) continue;
      if (t.kind != TokenKind::Identifier) fail(t.line, key, "expected a receiver, found " + describe(t));
      s.receivers.emplace_back(t.text);
    }
    if (s.length_bits == 0 || s.length_bits > 64) fail(kw.line, key, "length must be 1..64 bits");
    if (s.factor == 0.0) fail(kw.line, key, "factor is 0");
    if (!signal_fits(s, kMaxFrameBytes)) fail(kw.line, key, "bits lie outside a 64-byte frame");
    if (m->name != kIndependentSignals && m->signal(s.name) != nullptr)
      fail(kw.line, key, "duplicate signal in " + m->name);
    if (s.is_multiplexer && !s.is_multiplexed &&
        std::any_of(m->signals.begin(), m->signals.end(),
                    [](const DbcSignal& o) { return o.is_multiplexer && !o.is_multiplexed; }))
      fail(kw.line, key, "second multiplexer in " + m->name);
    m->signals.push_back(std::move(s));
    current_ = m;
  }

  // The message a VAL_ / SIG_VALTYPE_ / BA_ refers to by its file id.
  DbcMessage* message_of(const Token& id_token, std::string_view key) {
    const auto raw_id = integer<uint32_t>(id_token, "message id", key);
    const bool extended = (raw_id & kExtendedFlag) != 0;
    DbcMessage* m = find_message(db_.messages, extended ? (raw_id & kExtendedIdMask) : raw_id, extended);
    if (m == nullptr && raw_id == kIndependentSignalsId) {
      const auto it = std::find_if(db_.messages.begin(), db_.messages.end(),
                                   [](const DbcMessage& x) { return x.name == kIndependentSignals; });
      if (it != db_.messages.end()) m = &*it;
    }
    if (m == nullptr) fail(id_token.line, key, "unknown message");
    return m;
  }

  DbcSignal& signal_of(const Token& id_token, const Token& name_token, std::string_view key) {
    DbcMessage* it = message_of(id_token, key);
    auto s = std::find_if(it->signals.begin(), it->signals.end(),
                          [&](const DbcSignal& x) { return x.name == name_token.text; });
    if (s == it->signals.end()) fail(name_token.line, key, "unknown signal in " + it->name);
    return *s;
  }

  void value_names(const Token& kw) {
    if (peek().kind != TokenKind::Number) return skip_statement();  // VAL_ of an environment variable
    const Token id_token = take();
    const Token name_token = expect(TokenKind::Identifier, "signal name", "VAL_");
    const std::string key = "VAL_ " + std::string(id_token.text) + " " + std::string(name_token.text);
    DbcSignal& s = signal_of(id_token, name_token, key);
    while (!is_punct(peek(), ';')) {
      const Token v = take();
      if (v.kind == TokenKind::End) fail(kw.line, key, "missing ';'");
      const auto raw = integer<int64_t>(v, "value", key);
      s.value_names[raw] = unescape(expect(TokenKind::String, "quoted text", key).text);
    }
    take();
  }

  void value_type(const Token&) {
    const Token id_token = take();
    const Token name_token = expect(TokenKind::Identifier, "signal name", "SIG_VALTYPE_");
    const std::string key = "SIG_VALTYPE_ " + std::string(id_token.text) + " " + std::string(name_token.text);
    DbcSignal& s = signal_of(id_token, name_token, key);
    if (is_punct(peek(), ':')) take();
    const auto type = integer<uint32_t>(take(), "value type", key);
    if (type == 1 && s.length_bits == 32) {
      s.value_type = SignalValueType::Float32;
    } else if (type == 2 && s.length_bits == 64) {
      s.value_type = SignalValueType::Float64;
    } else if (type != 0) {
      fail(id_token.line, key,
           "value type " + std::to_string(type) + " does not fit a " + std::to_string(s.length_bits) +
               "-bit signal");
    }
    if (is_punct(peek(), ';')) take();
  }

  void attribute() {
    // Only BA_ "GenMsgCycleTime" BO_ <id> <ms>; is read, the rest skipped.
    const bool cycle_time = peek(0).kind == TokenKind::String && peek(0).text == "GenMsgCycleTime" &&
                            peek(1).kind == TokenKind::Identifier && peek(1).text == "BO_" &&
                            peek(2).kind == TokenKind::Number && peek(3).kind == TokenKind::Number;
    if (!cycle_time) return skip_statement();
    take();
    take();
    const Token id_token = take();
    const std::string key = "BA_ GenMsgCycleTime BO_ " + std::string(id_token.text);
    DbcMessage* m = message_of(id_token, key);
    m->cycle_time_ms = integer<uint32_t>(take(), "cycle time", key);
    skip_statement();
  }
};

}  // namespace

const DbcSignal* DbcMessage::signal(std::string_view signal_name) const {
  for (const DbcSignal& s : signals)
    if (s.name == signal_name) return &s;
  return nullptr;
}

std::string_view DecodedSignal::label() const {
  if (signal == nullptr) return {};
  const auto it = signal->value_names.find(raw);
  return it == signal->value_names.end() ? std::string_view{} : std::string_view{it->second};
}

DbcDatabase DbcDatabase::load(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open: " + std::strerror(errno));
  std::ostringstream text;
  text << in.rdbuf();
  return parse(text.str(), path);
}

DbcDatabase DbcDatabase::parse(std::string_view text, const std::string& name_for_errors) {
  ParsedDbc parsed = DbcParser(text, name_for_errors).run();
  DbcDatabase db;
  db.version_ = std::move(parsed.version);
  db.nodes_ = std::move(parsed.nodes);
  db.messages_ = std::move(parsed.messages);
  return db;
}

const DbcMessage* DbcDatabase::find(uint32_t id, bool extended) const {
  return find_message(messages_, id, extended);
}

const DbcMessage* DbcDatabase::find(std::string_view name) const {
  for (const DbcMessage& m : messages_)
    if (m.name == name) return &m;
  return nullptr;
}

bool signal_fits(const DbcSignal& signal, std::size_t size_bytes) {
  if (signal.length_bits == 0 || signal.length_bits > 64) return false;
  const uint64_t first = signal.byte_order == ByteOrder::LittleEndian
                             ? signal.start_bit
                             : big_endian_msb_position(signal.start_bit);
  return first + signal.length_bits <= static_cast<uint64_t>(size_bytes) * 8;
}

int64_t extract_raw(const DbcSignal& signal, std::span<const uint8_t> data) {
  uint64_t raw = 0;
  const uint32_t n = signal.length_bits;
  if (signal.byte_order == ByteOrder::LittleEndian) {
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t p = signal.start_bit + i;  // bit p%8 of byte p/8, LSB first
      raw |= static_cast<uint64_t>((data[p / 8] >> (p % 8)) & 1u) << i;
    }
  } else {
    const uint32_t msb = big_endian_msb_position(signal.start_bit);
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t p = msb + i;  // big-endian linear position, MSB first
      raw = (raw << 1) | ((data[p / 8] >> (7 - p % 8)) & 1u);
    }
  }
  if (signal.is_signed && signal.value_type == SignalValueType::Integer && n < 64 &&
      ((raw >> (n - 1)) & 1u) != 0)
    raw |= ~uint64_t{0} << n;
  return static_cast<int64_t>(raw);
}

void insert_raw(const DbcSignal& signal, uint64_t raw, std::span<uint8_t> data) {
  const uint32_t n = signal.length_bits;
  auto put = [&](uint32_t byte, uint32_t bit, bool on) {
    const auto mask = static_cast<uint8_t>(1u << bit);
    data[byte] = static_cast<uint8_t>(on ? (data[byte] | mask) : (data[byte] & ~mask));
  };
  if (signal.byte_order == ByteOrder::LittleEndian) {
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t p = signal.start_bit + i;
      put(p / 8, p % 8, ((raw >> i) & 1u) != 0);
    }
  } else {
    const uint32_t msb = big_endian_msb_position(signal.start_bit);
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t p = msb + i;
      put(p / 8, 7 - p % 8, ((raw >> (n - 1 - i)) & 1u) != 0);
    }
  }
}

double physical_value(const DbcSignal& signal, int64_t raw) {
  double scaled = 0.0;
  switch (signal.value_type) {
    case SignalValueType::Float32:
      scaled = std::bit_cast<float>(static_cast<uint32_t>(static_cast<uint64_t>(raw) & 0xFFFFFFFFu));
      break;
    case SignalValueType::Float64:
      scaled = std::bit_cast<double>(raw);
      break;
    case SignalValueType::Integer:
      scaled = signal.is_signed || signal.length_bits < 64 ? static_cast<double>(raw)
                                                           : static_cast<double>(static_cast<uint64_t>(raw));
      break;
  }
  return scaled * signal.factor + signal.offset;
}

std::vector<DecodedSignal> DbcDatabase::decode(const DbcMessage& message,
                                               std::span<const uint8_t> data) const {
  std::vector<DecodedSignal> out;
  out.reserve(message.signals.size());
  bool have_mux = false;
  int64_t mux = 0;
  for (const DbcSignal& s : message.signals) {
    if (s.is_multiplexer && !s.is_multiplexed && signal_fits(s, data.size())) {
      have_mux = true;
      mux = extract_raw(s, data);
    }
  }
  for (const DbcSignal& s : message.signals) {
    if (!signal_fits(s, data.size())) continue;
    if (s.is_multiplexed && (!have_mux || mux != static_cast<int64_t>(s.multiplexer_value))) continue;
    const int64_t raw = extract_raw(s, data);
    out.push_back(DecodedSignal{&s, raw, physical_value(s, raw)});
  }
  return out;
}

std::vector<uint8_t> DbcDatabase::encode(const DbcMessage& message,
                                         std::span<const SignalValue> values) const {
  std::vector<uint8_t> data(message.dlc, 0);
  for (const SignalValue& v : values) {
    const DbcSignal* s = message.signal(v.name);
    if (s == nullptr)
      throw std::invalid_argument(message.name + ": unknown signal '" + std::string(v.name) + "'");
    if (!signal_fits(*s, data.size()))
      throw std::out_of_range(message.name + "." + s->name + ": signal lies outside the message's " +
                              std::to_string(message.dlc) + " bytes");
    const double scaled = (v.value - s->offset) / s->factor;
    uint64_t raw = 0;
    if (s->value_type == SignalValueType::Float32) {
      raw = std::bit_cast<uint32_t>(static_cast<float>(scaled));
    } else if (s->value_type == SignalValueType::Float64) {
      raw = std::bit_cast<uint64_t>(scaled);
    } else {
      const double rounded = std::round(scaled);
      const int n = static_cast<int>(s->length_bits);
      const double lo = s->is_signed ? -std::ldexp(1.0, n - 1) : 0.0;
      const double hi_exclusive = s->is_signed ? std::ldexp(1.0, n - 1) : std::ldexp(1.0, n);
      if (!(rounded >= lo && rounded < hi_exclusive))
        throw std::out_of_range(message.name + "." + s->name + ": value " + std::to_string(v.value) +
                                " does not fit " + std::to_string(n) + " bits");
      raw = s->is_signed ? static_cast<uint64_t>(static_cast<int64_t>(rounded))
                         : static_cast<uint64_t>(rounded);
    }
    insert_raw(*s, raw, data);
  }
  return data;
}

}  // namespace rise::firmware_protocol
