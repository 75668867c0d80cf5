#include "rotorid/io/crazyflie_usd.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <unordered_set>

#include "rotorid/core/error.h"
#include "rotorid/io/atomic_file.h"

namespace rotorid {
namespace {

constexpr uint8_t kUsdMagic = 0xBC;
constexpr size_t kCrcBytes = 4;

[[noreturn]] void Fail(const std::string& source, size_t offset, const std::string& what) {
  throw Error(source + ": byte " + std::to_string(offset) + ": " + what);
}

// Little-endian loads; memcpy keeps them free of alignment and aliasing problems.
uint16_t LoadU16(const uint8_t* p) { return static_cast<uint16_t>(p[0] | (p[1] << 8)); }
uint32_t LoadU32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) | (static_cast<uint32_t>(p[2]) << 16) |
         (static_cast<uint32_t>(p[3]) << 24);
}
uint64_t LoadU64(const uint8_t* p) { return LoadU32(p) | (static_cast<uint64_t>(LoadU32(p + 4)) << 32); }

// IEEE 754 half precision to double (exact).
double HalfToDouble(uint16_t h) {
  const int sign = (h >> 15) & 1;
  const int exponent = (h >> 10) & 0x1F;
  const int mantissa = h & 0x3FF;
  double value;
  if (exponent == 0) {
    value = std::ldexp(static_cast<double>(mantissa), -24);  // subnormal
  } else if (exponent == 31) {
    value = mantissa == 0 ? HUGE_VAL : std::nan("");
  } else {
    value = std::ldexp(static_cast<double>(mantissa | 0x400), exponent - 25);
  }
  return sign ? -value : value;
}

int TypeSize(char type_char) {
  switch (type_char) {
    case 'B':
    case 'b':
      return 1;
    case 'H':
    case 'h':
    case 'e':
      return 2;
    case 'I':
    case 'i':
    case 'f':
      return 4;
    default:
      return 0;
  }
}

double DecodeValue(char type_char, const uint8_t* p) {
  switch (type_char) {
    case 'B':
      return p[0];
    case 'b':
      return static_cast<int8_t>(p[0]);
    case 'H':
      return LoadU16(p);
    case 'h':
      return static_cast<int16_t>(LoadU16(p));
    case 'I':
      return LoadU32(p);
    case 'i':
      return static_cast<int32_t>(LoadU32(p));
    case 'f': {
      const uint32_t bits = LoadU32(p);
      float f;
      std::memcpy(&f, &bits, sizeof(f));
      return f;
    }
    case 'e':
      return HalfToDouble(LoadU16(p));
    default:
      return 0.0;  // unreachable: types are checked when the header is read
  }
}

std::string Hex(uint32_t v, int digits) {
  char buffer[16];
  std::snprintf(buffer, sizeof(buffer), "0x%0*X", digits, v);
  return buffer;
}

// Printable form of header text for messages (binary garbage stays readable and short).
std::string Printable(std::string_view s) {
  std::string out;
  for (const char c : s.substr(0, 64)) {
    const auto u = static_cast<unsigned char>(c);
    if (u >= 0x20 && u < 0x7F) {
      out += c;
    } else {
      out += "\\x" + Hex(u, 2).substr(2);
    }
  }
  if (s.size() > 64) out += "...";
  return out;
}

// Cursor over the header; every read is bounds-checked against the start of the CRC.
class HeaderReader {
 public:
  HeaderReader(const uint8_t* data, size_t end, size_t pos, const std::string& source)
      : data_(data), end_(end), pos_(pos), source_(source) {}

  size_t pos() const { return pos_; }
  size_t remaining() const { return end_ - pos_; }

  uint16_t U16(const char* what) {
    if (remaining() < 2) Fail(source_, pos_, "header ends inside " + std::string(what) + " (truncated file)");
    const uint16_t v = LoadU16(data_ + pos_);
    pos_ += 2;
    return v;
  }
  std::string_view CString(const std::string& what) {
    const void* nul = std::memchr(data_ + pos_, 0, remaining());
    if (!nul) Fail(source_, pos_, what + " has no terminating NUL before the end of data (truncated file)");
    const size_t length = static_cast<const uint8_t*>(nul) - (data_ + pos_);
    std::string_view s(reinterpret_cast<const char*>(data_ + pos_), length);
    pos_ += length + 1;
    return s;
  }

 private:
  const uint8_t* data_;
  size_t end_;
  size_t pos_;
  const std::string& source_;
};

struct Decoder {  // per event type, for the record loop
  int payload_bytes = 0;
  std::vector<char> types;
  std::vector<int> offsets;
};

// Checks the magic byte, the version and (optionally) the trailing CRC, and fills those fields
// of `log`. Returns where the records end: the CRC's offset.
size_t ReadFraming(const uint8_t* data, size_t size, const CrazyflieUsdOptions& options, CrazyflieUsdLog* log) {
  const std::string& source = log->source;
  constexpr size_t kMinBytes = 1 + 2 + 2 + kCrcBytes;
  if (size < kMinBytes) {
    Fail(source, size,
         "file too short (" + std::to_string(size) + " bytes) for a Crazyflie uSD log: the header and CRC alone take " +
             std::to_string(kMinBytes));
  }
  if (data[0] != kUsdMagic) {
    Fail(source, 0, "not a Crazyflie uSD log: first byte is " + Hex(data[0], 2) + ", expected 0xBC");
  }
  log->version = LoadU16(data + 1);
  if (log->version != 1 && log->version != 2) {
    Fail(source, 1, "unsupported uSD log version " + std::to_string(log->version) + " (versions 1 and 2 are known)");
  }
  const size_t end = size - kCrcBytes;
  log->crc32 = LoadU32(data + end);
  if (options.verify_crc) {
    const uint32_t computed = Crc32(data, end);
    if (computed != log->crc32) {
      Fail(source, end,
           "CRC32 mismatch: stored " + Hex(log->crc32, 8) + ", computed " + Hex(computed, 8) + " over bytes 0.." +
               std::to_string(end - 1) + " (corrupt file, or cut off before logging stopped)");
    }
  }
  return end;
}

// One "group.name(T)" declaration, T a type character; `names_so_far` catches repeats (views
// into the file's bytes).
UsdVariable ReadVariable(HeaderReader* header, const std::string& what, const std::string& source,
                         std::unordered_set<std::string_view>* names_so_far) {
  const size_t offset = header->pos();
  const std::string_view text = header->CString(what);
  // At least one name character, then '(', the type, ')'.
  if (text.size() < 4 || text[text.size() - 3] != '(' || text.back() != ')') {
    Fail(source, offset, what + " is '" + Printable(text) + "', expected 'name(T)' with a type character T");
  }
  UsdVariable variable;
  variable.name = std::string(text.substr(0, text.size() - 3));
  variable.type_char = text[text.size() - 2];
  variable.size_bytes = TypeSize(variable.type_char);
  if (variable.size_bytes == 0) {
    Fail(source, offset,
         what + " '" + Printable(variable.name) + "' has unknown type character '" +
             Printable(std::string_view(&variable.type_char, 1)) + "' (known: B b H h I i f e)");
  }
  if (!names_so_far->insert(text.substr(0, text.size() - 3)).second) {
    Fail(source, offset, what + " '" + Printable(variable.name) + "' is listed twice");
  }
  return variable;
}

// One event type of the header: id, name, variables (laid out in order, without padding).
UsdEventTable ReadEventType(HeaderReader* header, const std::string& label, const std::string& source,
                            std::unordered_set<std::string_view>* event_names) {
  UsdEventTable event;
  event.id = header->U16(("the id of " + label).c_str());
  const size_t name_offset = header->pos();
  const std::string_view name = header->CString("the name of " + label);
  if (name.empty()) Fail(source, name_offset, "empty name for " + label);
  event.name = std::string(name);
  if (!event_names->insert(name).second) {
    Fail(source, name_offset, "event name '" + Printable(name) + "' is defined twice");
  }
  const uint16_t num_variables = header->U16(("the variable count of event '" + Printable(name) + "'").c_str());
  // Each variable takes at least 4 bytes; never trust the count for the reservation.
  event.variables.reserve(std::min<size_t>(num_variables, header->remaining() / 4));
  std::unordered_set<std::string_view> variable_names;
  for (int v = 0; v < num_variables; ++v) {
    const std::string what = "variable " + std::to_string(v + 1) + " of event '" + Printable(name) + "'";
    UsdVariable variable = ReadVariable(header, what, source, &variable_names);
    variable.offset_bytes = event.payload_bytes;
    event.payload_bytes += variable.size_bytes;
    event.variables.push_back(std::move(variable));
  }
  return event;
}

Decoder DecoderOf(const UsdEventTable& event) {
  Decoder decoder;
  decoder.payload_bytes = event.payload_bytes;
  for (const UsdVariable& variable : event.variables) {
    decoder.types.push_back(variable.type_char);
    decoder.offsets.push_back(variable.offset_bytes);
  }
  return decoder;
}

// Event index by id: a sorted (id, index) list, searched per record after a check of the
// previous record's id (real logs interleave one or two events). O(log E) whatever the header
// declares, and no table sized by the id range.
class EventIndex {
 public:
  // `id_offsets`: where each event's id is written, for the message about an id defined twice.
  EventIndex(const std::vector<UsdEventTable>& events, const std::vector<size_t>& id_offsets,
             const std::string& source) {
    for (size_t k = 0; k < events.size(); ++k) by_id_.emplace_back(events[k].id, static_cast<int32_t>(k));
    std::sort(by_id_.begin(), by_id_.end());
    for (size_t k = 1; k < by_id_.size(); ++k) {
      if (by_id_[k].first == by_id_[k - 1].first) {
        const UsdEventTable& first = events[by_id_[k - 1].second];
        const UsdEventTable& second = events[by_id_[k].second];
        Fail(source, id_offsets[by_id_[k].second],
             "event id " + std::to_string(first.id) + " is defined twice ('" + Printable(first.name) + "' and '" +
                 Printable(second.name) + "')");
      }
    }
  }

  // The event's index, or -1 when the header does not define the id.
  int32_t Find(uint16_t id) {
    if (last_index_ >= 0 && last_id_ == id) return last_index_;
    const auto it = std::lower_bound(by_id_.begin(), by_id_.end(), std::make_pair(id, int32_t{-1}));
    if (it == by_id_.end() || it->first != id) return -1;
    last_id_ = id;
    return last_index_ = it->second;
  }

 private:
  std::vector<std::pair<uint16_t, int32_t>> by_id_;
  uint16_t last_id_ = 0;
  int32_t last_index_ = -1;
};

struct EventTypes {
  std::vector<Decoder> decoders;   // per event, for the record loop
  std::vector<size_t> id_offsets;  // where each event's id is written, for messages
};

// The event table after the version; fills log->events and log->header_bytes.
EventTypes ReadEventTypes(const uint8_t* data, size_t end, CrazyflieUsdLog* log) {
  const std::string& source = log->source;
  HeaderReader header(data, end, 3, source);
  const uint16_t num_event_types = header.U16("the number of event types");
  // Each event type takes at least 5 bytes; never trust the count for the reservation.
  log->events.reserve(std::min<size_t>(num_event_types, header.remaining() / 5));
  EventTypes types;
  types.decoders.reserve(log->events.capacity());
  std::unordered_set<std::string_view> event_names;  // views into the file's bytes
  for (int e = 0; e < num_event_types; ++e) {
    const std::string label = "event type " + std::to_string(e + 1) + " of " + std::to_string(num_event_types);
    types.id_offsets.push_back(header.pos());
    log->events.push_back(ReadEventType(&header, label, source, &event_names));
    types.decoders.push_back(DecoderOf(log->events.back()));
  }
  log->header_bytes = header.pos();
  return types;
}

std::string DescribeDefinedIds(const std::vector<UsdEventTable>& events) {
  std::string defined;
  for (size_t k = 0; k < events.size() && k < 8; ++k)
    defined += (k ? ", " : "") + std::to_string(events[k].id) + " " + Printable(events[k].name);
  if (events.size() > 8) defined += ", ...";
  return defined.empty() ? std::string("none") : defined;
}

size_t RecordHeaderBytes(int version) { return version == 1 ? 2 + 4 : 2 + 8; }

// First pass over the records: checks their framing and counts them per event.
std::vector<size_t> CountRecords(const uint8_t* data, size_t end, const CrazyflieUsdLog& log,
                                 const std::vector<Decoder>& decoders, EventIndex* index) {
  const size_t record_header = RecordHeaderBytes(log.version);
  std::vector<size_t> counts(log.events.size(), 0);
  for (size_t pos = log.header_bytes; pos < end;) {
    if (end - pos < record_header) {
      Fail(log.source, pos,
           "record header needs " + std::to_string(record_header) + " bytes, only " + std::to_string(end - pos) +
               " are left before the CRC (truncated record)");
    }
    const uint16_t id = LoadU16(data + pos);
    const int32_t event = index->Find(id);
    if (event < 0) {
      Fail(log.source, pos,
           "record with event id " + std::to_string(id) +
               ", which the header does not define (defined: " + DescribeDefinedIds(log.events) + ")");
    }
    const size_t record_bytes = record_header + static_cast<size_t>(decoders[event].payload_bytes);
    if (end - pos < record_bytes) {
      Fail(log.source, pos,
           "record of event '" + Printable(log.events[event].name) + "' needs " + std::to_string(record_bytes) +
               " bytes, only " + std::to_string(end - pos) + " are left before the CRC (truncated record)");
    }
    ++counts[event];
    pos += record_bytes;
  }
  return counts;
}

// Second pass, over records CountRecords has checked: into columns allocated once.
void DecodeRecords(const uint8_t* data, size_t end, const std::vector<Decoder>& decoders,
                   const std::vector<size_t>& counts, EventIndex* index, CrazyflieUsdLog* log) {
  for (size_t k = 0; k < log->events.size(); ++k) {
    UsdEventTable& event = log->events[k];
    event.timestamp_us.resize(counts[k]);
    event.columns.assign(event.variables.size(), std::vector<double>(counts[k]));
  }
  const size_t record_header = RecordHeaderBytes(log->version);
  std::vector<size_t> rows(log->events.size(), 0);
  for (size_t pos = log->header_bytes; pos < end;) {
    const int32_t k = index->Find(LoadU16(data + pos));
    UsdEventTable& event = log->events[k];
    const Decoder& decoder = decoders[k];
    const size_t row = rows[k]++;
    // Version 1 stamps FreeRTOS ticks (1 kHz on the Crazyflie), version 2 microseconds.
    event.timestamp_us[row] =
        log->version == 1 ? static_cast<uint64_t>(LoadU32(data + pos + 2)) * 1000u : LoadU64(data + pos + 2);
    const uint8_t* payload = data + pos + record_header;
    for (size_t v = 0; v < decoder.types.size(); ++v) {
      event.columns[v][row] = DecodeValue(decoder.types[v], payload + decoder.offsets[v]);
    }
    pos += record_header + static_cast<size_t>(decoder.payload_bytes);
  }
}

}  // namespace

uint32_t Crc32(const void* data, size_t size, uint32_t crc) {
  // Slice-by-8 tables: 8 bytes per step, several times faster than the byte-wise loop on a
  // multi-megabyte log.
  static const auto tables = [] {
    std::array<std::array<uint32_t, 256>, 8> t{};
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[0][i] = c;
    }
    for (uint32_t i = 0; i < 256; ++i) {
      for (int s = 1; s < 8; ++s) t[s][i] = (t[s - 1][i] >> 8) ^ t[0][t[s - 1][i] & 0xFF];
    }
    return t;
  }();
  const auto* p = static_cast<const uint8_t*>(data);
  crc = ~crc;
  while (size >= 8) {
    const uint32_t lo = LoadU32(p) ^ crc;
    const uint32_t hi = LoadU32(p + 4);
    crc = tables[7][lo & 0xFF] ^ tables[6][(lo >> 8) & 0xFF] ^ tables[5][(lo >> 16) & 0xFF] ^ tables[4][lo >> 24] ^
          tables[3][hi & 0xFF] ^ tables[2][(hi >> 8) & 0xFF] ^ tables[1][(hi >> 16) & 0xFF] ^ tables[0][hi >> 24];
    p += 8;
    size -= 8;
  }
  while (size-- > 0) crc = tables[0][(crc ^ *p++) & 0xFF] ^ (crc >> 8);
  return ~crc;
}

const std::vector<double>* UsdEventTable::FindColumn(std::string_view variable_name) const {
  for (size_t k = 0; k < variables.size(); ++k) {
    if (variables[k].name == variable_name) return &columns[k];
  }
  return nullptr;
}

const UsdEventTable* CrazyflieUsdLog::FindEvent(std::string_view event_name) const {
  for (const UsdEventTable& event : events) {
    if (event.name == event_name) return &event;
  }
  return nullptr;
}

std::string CrazyflieUsdLog::DescribeEvents() const {
  if (events.empty()) return "no events";
  std::string out;
  for (const UsdEventTable& event : events) {
    if (!out.empty()) out += ", ";
    out += event.name + " (" + std::to_string(event.num_records()) + " records)";
  }
  return out;
}

CrazyflieUsdLog ParseCrazyflieUsd(std::string_view bytes, const std::string& source,
                                  const CrazyflieUsdOptions& options) {
  const auto* data = reinterpret_cast<const uint8_t*>(bytes.data());
  CrazyflieUsdLog log;
  log.source = source;
  const size_t end = ReadFraming(data, bytes.size(), options, &log);
  const EventTypes types = ReadEventTypes(data, end, &log);
  EventIndex index(log.events, types.id_offsets, source);
  // Records in two passes: the first checks framing and counts records per event, so that the
  // second decodes into columns allocated once (no allocation per record).
  const std::vector<size_t> counts = CountRecords(data, end, log, types.decoders, &index);
  DecodeRecords(data, end, types.decoders, counts, &index, &log);
  return log;
}

CrazyflieUsdLog ReadCrazyflieUsd(const std::string& path, const CrazyflieUsdOptions& options) {
  const std::string bytes = ReadFile(path);
  return ParseCrazyflieUsd(bytes, path, options);
}

}  // namespace rotorid
