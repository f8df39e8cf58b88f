#include "firmware_protocol/canopen_eds.hpp"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include "firmware_protocol/canopen.hpp"

namespace rise::firmware_protocol::canopen {
namespace {

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

std::string hex4(unsigned v) {
  static const char* digits = "0123456789ABCDEF";
  std::string s = "0x0000";
  for (int i = 0; i < 4; ++i) s[static_cast<std::size_t>(5 - i)] = digits[(v >> (4 * i)) & 0xF];
  return s;
}

// An unsigned literal as CiA 306 §4.6.3 writes them: 0x-hex, 0-octal or decimal.
std::optional<uint64_t> parse_literal(std::string_view text) {
  text = trim(text);
  if (text.empty()) return std::nullopt;
  int base = 10;
  if (text.size() > 2 && text[0] == '0' && (text[1] == 'x' || text[1] == 'X')) {
    base = 16;
    text.remove_prefix(2);
  } else if (text.size() > 1 && text[0] == '0') {
    base = 8;
    text.remove_prefix(1);
  }
  uint64_t value = 0;
  for (const char c : text) {
    const int digit = std::isdigit(static_cast<unsigned char>(c)) ? c - '0'
                      : std::isxdigit(static_cast<unsigned char>(c))
                          ? std::tolower(static_cast<unsigned char>(c)) - 'a' + 10
                          : 99;
    if (digit >= base) return std::nullopt;
    if (value > (UINT64_MAX - static_cast<uint64_t>(digit)) / static_cast<uint64_t>(base)) return std::nullopt;
    value = value * static_cast<uint64_t>(base) + static_cast<uint64_t>(digit);
  }
  return value;
}

// A value with `$NODEID` terms: "$NODEID+0x180", "0x180+$NODEID".
std::optional<uint64_t> parse_value(std::string_view text, uint8_t node_id) {
  uint64_t sum = 0;
  while (true) {
    const std::size_t plus = text.find('+');
    const std::string_view term = trim(text.substr(0, plus));
    if (lower(term) == "$nodeid") sum += node_id;
    else if (const auto v = parse_literal(term)) sum += *v;
    else return std::nullopt;
    if (plus == std::string_view::npos) return sum;
    text.remove_prefix(plus + 1);
  }
}

// A signed literal (LowLimit / HighLimit of a signed object may be negative).
std::optional<double> parse_limit(std::string_view text, uint8_t node_id) {
  text = trim(text);
  const bool negative = !text.empty() && text.front() == '-';
  if (negative) text.remove_prefix(1);
  const auto v = parse_value(text, node_id);
  if (!v) return std::nullopt;
  return negative ? -static_cast<double>(*v) : static_cast<double>(*v);
}

struct Key {
  std::string value;
  int line = 0;
};
struct Section {
  std::string name;  // as written
  int line = 0;
  std::map<std::string, Key> keys;  // by lower-case key
  const Key* get(const char* key) const {
    const auto it = keys.find(key);
    return it == keys.end() ? nullptr : &it->second;
  }
};

// "6000" / "6000sub1" → index, subindex; nullopt for a named section ([FileInfo]).
std::optional<std::pair<uint16_t, uint8_t>> object_section(std::string_view name) {
  const std::string l = lower(name);
  const std::size_t sub = l.find("sub");
  const std::string index = l.substr(0, sub);
  if (index.size() != 4 || index.find_first_not_of("0123456789abcdef") != std::string::npos) return std::nullopt;
  uint8_t subindex = 0;
  if (sub != std::string::npos) {
    const std::string digits = l.substr(sub + 3);
    if (digits.empty() || digits.size() > 2 || digits.find_first_not_of("0123456789abcdef") != std::string::npos)
      return std::nullopt;
    subindex = static_cast<uint8_t>(std::stoul(digits, nullptr, 16));
  }
  return std::make_pair(static_cast<uint16_t>(std::stoul(index, nullptr, 16)), subindex);
}

}  // namespace

// Reads the file in two passes: the INI text into sections, then the
// sections into the object dictionary and its PDOs.
class EdsReader {
 public:
  EdsReader(std::string_view text, const std::string& file, uint8_t node_id) : text_(text) {
    device_.file_ = file;
    device_.node_id_ = node_id;
  }

  EdsDevice read() {
    read_sections();
    read_entries();
    read_device_info();
    device_.tpdos_ = read_pdos(true);
    device_.rpdos_ = read_pdos(false);
    device_.tpdo_messages_ = messages(device_.tpdos_);
    device_.rpdo_messages_ = messages(device_.rpdos_);
    read_timing();
    return std::move(device_);
  }

 private:
  [[noreturn]] void fail(int line, const std::string& section, const std::string& key, const std::string& what) const {
    std::string where = device_.file_ + ":" + std::to_string(line) + ": ";
    if (!section.empty()) where += "[" + section + "] ";
    if (!key.empty()) where += key + ": ";
    throw std::runtime_error(where + what);
  }

  void read_sections() {
    std::size_t start = 0;
    int line = 0;
    Section* current = nullptr;
    while (start <= text_.size()) {
      const std::size_t end = std::min(text_.find('\n', start), text_.size());
      ++line;
      read_line(trim(text_.substr(start, end - start)), line, current);
      start = end + 1;
    }
  }

  void read_line(std::string_view text, int line, Section*& current) {
    if (text.empty() || text.front() == ';' || text.front() == '#') return;
    if (text.front() == '[') {
      if (text.back() != ']') fail(line, "", "", "section header without ']'");
      const std::string name(trim(text.substr(1, text.size() - 2)));
      if (name.empty()) fail(line, "", "", "empty section name");
      if (section_index_.count(lower(name)))
        fail(line, name, "", "section given twice (first at line " +
                                 std::to_string(sections_[section_index_[lower(name)]].line) + ")");
      section_index_[lower(name)] = sections_.size();
      sections_.push_back({name, line, {}});
      current = &sections_.back();
      return;
    }
    const std::size_t eq = text.find('=');
    if (eq == std::string_view::npos) fail(line, current ? current->name : "", "", "expected key=value or [section]");
    if (!current) fail(line, "", std::string(trim(text.substr(0, eq))), "key before the first [section]");
    const std::string key(trim(text.substr(0, eq)));
    if (key.empty()) fail(line, current->name, "", "empty key");
    if (!current->keys.emplace(lower(key), Key{std::string(trim(text.substr(eq + 1))), line}).second)
      fail(line, current->name, key, "given twice in this section");
  }

  const Section* section(const std::string& name) const {
    const auto it = section_index_.find(lower(name));
    return it == section_index_.end() ? nullptr : &sections_[it->second];
  }

  uint64_t number(const Section& s, const Key& k, const char* key) const {
    const auto v = parse_value(k.value, device_.node_id_);
    if (!v) fail(k.line, s.name, key, "'" + k.value + "' is not a number (decimal, 0x-hex, 0-octal, $NODEID+N)");
    return *v;
  }

  void read_entries() {
    for (const Section& s : sections_) {
      const auto address = object_section(s.name);
      if (!address) continue;
      for (const char* refused : {"compactsubobj", "compactpdo"})
        if (const Key* k = s.get(refused); k && k->value != "0")
          fail(k->line, s.name, refused, "compact storage is not supported: write each sub-object's section");
      const Key* object_type = s.get("objecttype");
      const uint64_t type = object_type ? number(s, *object_type, "ObjectType") : 0x7;
      // ARRAY (0x8) and RECORD (0x9) hold their sub-objects in [IIIIsubN].
      if (type == 0x8 || type == 0x9) continue;
      device_.entries_.push_back(entry(s, address->first, address->second));
    }
  }

  OdEntry entry(const Section& s, uint16_t index, uint8_t subindex) const {
    OdEntry e;
    e.index = index;
    e.subindex = subindex;
    e.line = s.line;
    e.section = s.name;
    const Key* name = s.get("parametername");
    if (!name) fail(s.line, s.name, "ParameterName", "missing");
    e.name = name->value;
    const Key* type = s.get("datatype");
    if (!type) fail(s.line, s.name, "DataType", "missing");
    e.data_type = static_cast<uint16_t>(number(s, *type, "DataType"));
    if (const Key* access = s.get("accesstype")) e.access_type = lower(access->value);
    const Key* dcf_value = s.get("parametervalue");
    const Key* value = dcf_value && !dcf_value->value.empty() ? dcf_value : s.get("defaultvalue");
    if (value) e.default_value = value->value;
    if (const Key* mapping = s.get("pdomapping")) e.pdo_mapping = number(s, *mapping, "PDOMapping") != 0;
    for (const auto& [key, slot] : {std::pair{"lowlimit", &e.low_limit}, std::pair{"highlimit", &e.high_limit}}) {
      const Key* limit = s.get(key);
      if (!limit || limit->value.empty()) continue;
      *slot = parse_limit(limit->value, device_.node_id_);
      if (!*slot) fail(limit->line, s.name, key == std::string("lowlimit") ? "LowLimit" : "HighLimit",
                       "'" + limit->value + "' is not a number");
    }
    return e;
  }

  void read_device_info() {
    if (const Section* info = section("DeviceInfo"))
      if (const Key* name = info->get("productname")) device_.product_name_ = name->value;
    // A DCF is one node's configuration (CiA 306 §5.3, spelt as the standard spells it).
    if (const Section* dcf = section("DeviceComissioning"))
      if (const Key* node = dcf->get("nodeid"); node && !node->value.empty()) {
        const uint64_t id = number(*dcf, *node, "NodeID");
        if (id != device_.node_id_)
          fail(node->line, dcf->name, "NodeID",
               "the DCF configures node " + std::to_string(id) + ", not node " + std::to_string(device_.node_id_));
      }
  }

  // The entry's value, or a message naming where it is.
  uint64_t entry_value(const OdEntry& e) const {
    const auto v = parse_value(e.default_value, device_.node_id_);
    if (!v)
      fail(e.line, section_name(e), "DefaultValue",
           "'" + e.default_value + "' is not a number (decimal, 0x-hex, 0-octal, $NODEID+N)");
    return *v;
  }

  // The entry's value, which must fit `max` (the object's data type).
  uint64_t entry_value(const OdEntry& e, uint64_t max) const {
    const uint64_t v = entry_value(e);
    if (v > max) fail(e.line, section_name(e), "DefaultValue", std::to_string(v) + " is out of range 0.." + std::to_string(max));
    return v;
  }

  static const std::string& section_name(const OdEntry& e) { return e.section; }

  std::vector<Pdo> read_pdos(bool transmit) const {
    std::vector<Pdo> pdos;
    const uint16_t comm_base = transmit ? 0x1800 : 0x1400;
    const uint16_t map_base = transmit ? 0x1A00 : 0x1600;
    for (uint16_t n = 0; n < 512; ++n) {
      const OdEntry* cob = device_.find(static_cast<uint16_t>(comm_base + n), 1);
      const OdEntry* count = device_.find(static_cast<uint16_t>(map_base + n), 0);
      if (!cob && !count) continue;
      const std::string label = std::string(transmit ? "TPDO" : "RPDO") + std::to_string(n + 1);
      if (!cob) fail(count->line, section_name(*count), "", label + " has a mapping but no COB-ID (" +
                                                               hex4(comm_base + n) + "sub1)");
      if (!count) fail(cob->line, section_name(*cob), "", label + " has no mapping (" + hex4(map_base + n) + "sub0)");
      Pdo pdo;
      pdo.transmit = transmit;
      pdo.number = n + 1u;
      const uint64_t cob_id = entry_value(*cob, 0xFFFFFFFF);
      if (cob_id & 0x80000000u) continue;  // bit 31: PDO not valid (not used)
      pdo.extended = (cob_id & 0x20000000u) != 0;
      pdo.cob_id = static_cast<uint32_t>(cob_id & (pdo.extended ? 0x1FFFFFFFu : 0x7FFu));
      if (const OdEntry* type = device_.find(static_cast<uint16_t>(comm_base + n), 2))
        pdo.transmission_type = static_cast<uint8_t>(entry_value(*type, 0xFF));
      if (const OdEntry* inhibit = device_.find(static_cast<uint16_t>(comm_base + n), 3))
        pdo.inhibit_100us = static_cast<uint16_t>(entry_value(*inhibit, 0xFFFF));
      if (const OdEntry* timer = device_.find(static_cast<uint16_t>(comm_base + n), 5))
        pdo.event_timer_ms = static_cast<uint16_t>(entry_value(*timer, 0xFFFF));
      pdo.line = count->line;
      read_mapping(pdo, *count, static_cast<uint16_t>(map_base + n));
      pdos.push_back(std::move(pdo));
    }
    return pdos;
  }

  void read_mapping(Pdo& pdo, const OdEntry& count, uint16_t map_index) const {
    const uint64_t n = entry_value(count);
    if (n > 64) fail(count.line, section_name(count), "DefaultValue", "a PDO maps at most 64 objects");
    for (uint8_t i = 1; i <= n; ++i) {
      const OdEntry* m = device_.find(map_index, i);
      if (!m)
        fail(count.line, section_name(count), "DefaultValue",
             pdo.label() + " maps " + std::to_string(n) + " objects but " + hex4(map_index) + "sub" +
                 std::to_string(i) + " is missing");
      pdo.entries.push_back(mapped(pdo, *m, entry_value(*m)));
    }
  }

  // One mapping value 0xIIIISSLL (index, subindex, length in bits; CiA 301 §7.5.2.36).
  PdoEntry mapped(Pdo& pdo, const OdEntry& m, uint64_t value) const {
    PdoEntry e;
    e.index = static_cast<uint16_t>(value >> 16);
    e.subindex = static_cast<uint8_t>(value >> 8);
    e.bits = static_cast<uint8_t>(value);
    e.bit_offset = pdo.bits;
    const auto bad = [&](const std::string& what) {
      fail(m.line, section_name(m), "DefaultValue", pdo.label() + " maps " + od_address(e.index, e.subindex) + ": " + what);
    };
    if (value > 0xFFFFFFFFu || e.bits == 0) bad("not a mapping value 0xIIIISSLL with a length");
    if (e.index >= 0x0001 && e.index <= 0x0007) {
      // A dummy entry (CiA 301 §7.4.8.3): a gap of the data type's size.
      if (data_type_bits(e.index) != e.bits) bad("a dummy entry's length is its data type's");
    } else {
      e.entry = device_.find(e.index, e.subindex);
      if (!e.entry) bad("the EDS has no such object");
      if (!e.entry->pdo_mapping) bad("'" + e.entry->name + "' is not PDO-mappable (PDOMapping=0)");
      const uint8_t type_bits = data_type_bits(e.entry->data_type);
      if (type_bits == 0) bad("its data type " + hex4(e.entry->data_type) + " cannot be mapped");
      const bool boolean = e.entry->data_type == 0x0001 && e.bits <= 8;
      if (e.bits != type_bits && !boolean)
        bad("length " + std::to_string(e.bits) + " bits, but its data type has " + std::to_string(type_bits));
    }
    pdo.bits += e.bits;
    if (pdo.bits > 64) bad("the PDO's mapping exceeds 64 bits (8 bytes)");
    return e;
  }

  static std::vector<DbcMessage> messages(const std::vector<Pdo>& pdos) {
    std::vector<DbcMessage> out;
    for (const Pdo& pdo : pdos) {
      DbcMessage m;
      m.id = pdo.cob_id;
      m.extended = pdo.extended;
      m.name = pdo.label();
      m.dlc = static_cast<uint8_t>((pdo.bits + 7) / 8);
      m.line = pdo.line;
      for (const PdoEntry& e : pdo.entries) {
        if (!e.entry) continue;
        DbcSignal s;
        s.name = e.entry->name;
        s.start_bit = e.bit_offset;
        s.length_bits = e.bits;
        s.byte_order = ByteOrder::LittleEndian;
        s.is_signed = data_type_signed(e.entry->data_type);
        s.value_type = !data_type_real(e.entry->data_type) ? SignalValueType::Integer
                       : e.bits == 32                      ? SignalValueType::Float32
                                                           : SignalValueType::Float64;
        s.minimum = e.entry->low_limit.value_or(0.0);
        s.maximum = e.entry->high_limit.value_or(0.0);
        s.line = e.entry->line;
        m.signals.push_back(std::move(s));
      }
      out.push_back(std::move(m));
    }
    return out;
  }

  void read_timing() {
    const OdEntry* heartbeat = device_.find(0x1017, 0);
    if (!heartbeat)
      fail(1, "", "", "no object 0x1017 (Producer heartbeat time): the bridge watches the node by its heartbeat "
                      "(node guarding is not supported)");
    device_.heartbeat_ms_ = static_cast<uint16_t>(entry_value(*heartbeat, 0xFFFF));
    if (device_.heartbeat_ms_ == 0)
      fail(heartbeat->line, section_name(*heartbeat), "DefaultValue",
           "producer heartbeat time 0: the bridge watches the node by its heartbeat (node guarding is not supported)");
    if (const OdEntry* cycle = device_.find(0x1006, 0))
      device_.sync_period_us_ = static_cast<uint32_t>(entry_value(*cycle, 0xFFFFFFFF));
  }

  std::string_view text_;
  std::vector<Section> sections_;
  std::map<std::string, std::size_t> section_index_;
  EdsDevice device_;
};

std::string Pdo::label() const { return std::string(transmit ? "TPDO" : "RPDO") + std::to_string(number); }

EdsDevice EdsDevice::load(const std::string& path, uint8_t node_id) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open");
  std::ostringstream text;
  text << in.rdbuf();
  return parse(text.str(), path, node_id);
}

EdsDevice EdsDevice::parse(std::string_view text, const std::string& file, uint8_t node_id) {
  if (!is_node_id(node_id)) throw std::runtime_error(file + ": node id " + std::to_string(node_id) + " is not 1..127");
  return EdsReader(text, file, node_id).read();
}

bool EdsDevice::has_sync_tpdo() const {
  return std::any_of(tpdos_.begin(), tpdos_.end(), [](const Pdo& p) { return is_synchronous(p.transmission_type); });
}

const OdEntry* EdsDevice::find(uint16_t index, uint8_t subindex) const {
  for (const OdEntry& e : entries_)
    if (e.index == index && e.subindex == subindex) return &e;
  return nullptr;
}

OdLookup EdsDevice::lookup(std::string_view text) const {
  OdLookup r;
  if (const auto address = parse_od_address(text)) {
    r.entry = find(address->first, address->second);
    if (!r.entry) r.error = "no object " + od_address(address->first, address->second) + " in " + file_;
    return r;
  }
  std::string matches;
  int count = 0;
  for (const OdEntry& e : entries_)
    if (e.name == text) {
      r.entry = &e;
      matches += (count++ ? ", " : "") + od_address(e.index, e.subindex);
    }
  if (count > 1) {
    r.entry = nullptr;
    r.error = "'" + std::string(text) + "' names " + std::to_string(count) + " objects (" + matches +
              "): bind one by index:subindex";
  } else if (count == 0) {
    r.error = "no object '" + std::string(text) + "' (a ParameterName or index:subindex) in " + file_;
  }
  return r;
}

PdoSignal EdsDevice::pdo_signal(const OdEntry& entry, bool transmit) const {
  const auto& pdos = transmit ? tpdos_ : rpdos_;
  const auto& messages = transmit ? tpdo_messages_ : rpdo_messages_;
  for (std::size_t p = 0; p < pdos.size(); ++p) {
    std::size_t signal = 0;
    for (const PdoEntry& e : pdos[p].entries) {
      if (!e.entry) continue;
      if (e.entry == &entry) return {&pdos[p], &messages[p], &messages[p].signals[signal], e.entry};
      ++signal;
    }
  }
  return {};
}

std::optional<uint64_t> EdsDevice::value(uint16_t index, uint8_t subindex) const {
  const OdEntry* e = find(index, subindex);
  return e ? parse_value(e->default_value, node_id_) : std::nullopt;
}

std::optional<std::pair<uint16_t, uint8_t>> parse_od_address(std::string_view text) {
  text = trim(text);
  if (text.size() > 2 && text[0] == '0' && (text[1] == 'x' || text[1] == 'X')) text.remove_prefix(2);
  const std::string l = lower(text);
  std::size_t split = l.find(':');
  std::size_t sub_start = split == std::string::npos ? std::string::npos : split + 1;
  if (split == std::string::npos && (split = l.find("sub")) != std::string::npos) sub_start = split + 3;
  const std::string index = l.substr(0, split);
  if (index.size() != 4 || index.find_first_not_of("0123456789abcdef") != std::string::npos) return std::nullopt;
  uint64_t sub = 0;
  if (sub_start != std::string::npos) {
    std::string digits = l.substr(sub_start);
    if (digits.size() > 2 && digits[0] == '0' && digits[1] == 'x') digits = digits.substr(2);
    if (digits.empty() || digits.size() > 2 || digits.find_first_not_of("0123456789abcdef") != std::string::npos)
      return std::nullopt;
    sub = std::stoul(digits, nullptr, 16);
  }
  return std::make_pair(static_cast<uint16_t>(std::stoul(index, nullptr, 16)), static_cast<uint8_t>(sub));
}

std::string od_address(uint16_t index, uint8_t subindex) {
  static const char* digits = "0123456789ABCDEF";
  return hex4(index) + ":" + digits[subindex >> 4] + digits[subindex & 0xF];
}

uint8_t data_type_bits(uint16_t t) {
  switch (t) {
    case 0x01: return 1;
    case 0x02: case 0x05: return 8;
    case 0x03: case 0x06: return 16;
    case 0x10: case 0x16: return 24;
    case 0x04: case 0x07: case 0x08: return 32;
    case 0x12: case 0x18: return 40;
    case 0x13: case 0x19: return 48;
    case 0x14: case 0x1A: return 56;
    case 0x15: case 0x1B: case 0x11: return 64;
    default: return 0;
  }
}

bool data_type_signed(uint16_t t) {
  return t == 0x02 || t == 0x03 || t == 0x04 || t == 0x10 || t == 0x12 || t == 0x13 || t == 0x14 || t == 0x15;
}

bool data_type_real(uint16_t t) { return t == 0x08 || t == 0x11; }

}  // namespace rise::firmware_protocol::canopen
