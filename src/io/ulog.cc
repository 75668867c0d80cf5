#include "rotorid/io/ulog.h"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <set>
#include <unordered_map>

#include "rotorid/core/error.h"
#include "rotorid/io/atomic_file.h"

namespace rotorid {
namespace {

constexpr uint8_t kULogMagic[7] = {0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35};  // "ULog" 0x01 0x12 0x35
constexpr size_t kHeaderBytes = 16;
constexpr size_t kMessageHeaderBytes = 3;  // uint16 msg_size, uint8 msg_type
// Nested types deeper than this are treated as a (recursive) corrupt definition; PX4 uses two or three.
constexpr int kMaxNestingDepth = 32;
// Bound on the work of flattening one format (guards against arrays of empty nested types).
constexpr size_t kMaxFlattenVisits = 1 << 20;

constexpr int32_t kUnsubscribed = -1;
constexpr int32_t kFiltered = -2;

template <typename T>
T Load(const uint8_t* p) {
  T value;
  std::memcpy(&value, p, sizeof(T));  // ULog is little endian, as every platform we build for
  return value;
}

std::optional<ULogBaseType> BaseTypeFromName(std::string_view name) {
  static const std::pair<std::string_view, ULogBaseType> kTypes[] = {
      {"int8_t", ULogBaseType::kInt8},     {"uint8_t", ULogBaseType::kUInt8},   {"int16_t", ULogBaseType::kInt16},
      {"uint16_t", ULogBaseType::kUInt16}, {"int32_t", ULogBaseType::kInt32},   {"uint32_t", ULogBaseType::kUInt32},
      {"int64_t", ULogBaseType::kInt64},   {"uint64_t", ULogBaseType::kUInt64}, {"float", ULogBaseType::kFloat},
      {"double", ULogBaseType::kDouble},   {"bool", ULogBaseType::kBool},       {"char", ULogBaseType::kChar}};
  for (const auto& [type_name, type] : kTypes)
    if (type_name == name) return type;
  return std::nullopt;
}

double DecodeAsDouble(const uint8_t* p, ULogBaseType type) {
  switch (type) {
    case ULogBaseType::kInt8:
      return Load<int8_t>(p);
    case ULogBaseType::kUInt8:
    case ULogBaseType::kBool:
      return Load<uint8_t>(p);
    case ULogBaseType::kChar:
      return static_cast<double>(Load<int8_t>(p));
    case ULogBaseType::kInt16:
      return Load<int16_t>(p);
    case ULogBaseType::kUInt16:
      return Load<uint16_t>(p);
    case ULogBaseType::kInt32:
      return Load<int32_t>(p);
    case ULogBaseType::kUInt32:
      return Load<uint32_t>(p);
    case ULogBaseType::kInt64:
      return static_cast<double>(Load<int64_t>(p));
    case ULogBaseType::kUInt64:
      return static_cast<double>(Load<uint64_t>(p));
    case ULogBaseType::kFloat:
      return Load<float>(p);
    case ULogBaseType::kDouble:
      return Load<double>(p);
  }
  return 0.0;
}

// Python's repr() of a float: shortest round-trip digits, exponent form outside 1e-4 <= |x| < 1e16.
std::string PythonFloat(double x) {
  if (x != x) return "nan";
  if (x == std::numeric_limits<double>::infinity()) return "inf";
  if (x == -std::numeric_limits<double>::infinity()) return "-inf";
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), x, std::chars_format::scientific);
  const std::string sci(buffer, result.ptr);
  const size_t e = sci.find('e');
  std::string mantissa = sci.substr(0, e);
  const int exponent = std::stoi(sci.substr(e + 1));
  const bool negative = mantissa[0] == '-';
  if (negative) mantissa.erase(0, 1);
  std::string digits;
  for (char c : mantissa)
    if (c != '.') digits += c;
  std::string out = negative ? "-" : "";
  if (exponent < -4 || exponent >= 16) {
    out += digits.substr(0, 1);
    if (digits.size() > 1) out += "." + digits.substr(1);
    char exp_text[16];
    std::snprintf(exp_text, sizeof(exp_text), "e%c%02d", exponent < 0 ? '-' : '+', std::abs(exponent));
    return out + exp_text;
  }
  if (exponent < 0) return out + "0." + std::string(static_cast<size_t>(-exponent - 1), '0') + digits;
  const size_t int_digits = static_cast<size_t>(exponent) + 1;
  if (digits.size() <= int_digits) return out + digits + std::string(int_digits - digits.size(), '0') + ".0";
  return out + digits.substr(0, int_digits) + "." + digits.substr(int_digits);
}

// Python's repr() of a bytes object.
std::string PythonBytes(std::string_view bytes) {
  const bool use_double = bytes.find('\'') != std::string_view::npos && bytes.find('"') == std::string_view::npos;
  const char quote = use_double ? '"' : '\'';
  std::string out = "b";
  out += quote;
  for (const char ch : bytes) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '\\' || c == static_cast<unsigned char>(quote)) {
      out += '\\';
      out += ch;
    } else if (c == '\t') {
      out += "\\t";
    } else if (c == '\n') {
      out += "\\n";
    } else if (c == '\r') {
      out += "\\r";
    } else if (c < 0x20 || c >= 0x7f) {
      char hex[8];
      std::snprintf(hex, sizeof(hex), "\\x%02x", c);
      out += hex;
    } else {
      out += ch;
    }
  }
  return out + quote;
}

}  // namespace

int ULogBaseTypeSize(ULogBaseType type) {
  switch (type) {
    case ULogBaseType::kInt8:
    case ULogBaseType::kUInt8:
    case ULogBaseType::kBool:
    case ULogBaseType::kChar:
      return 1;
    case ULogBaseType::kInt16:
    case ULogBaseType::kUInt16:
      return 2;
    case ULogBaseType::kInt32:
    case ULogBaseType::kUInt32:
    case ULogBaseType::kFloat:
      return 4;
    case ULogBaseType::kInt64:
    case ULogBaseType::kUInt64:
    case ULogBaseType::kDouble:
      return 8;
  }
  return 1;
}

const char* ULogBaseTypeName(ULogBaseType type) {
  switch (type) {
    case ULogBaseType::kInt8:
      return "int8_t";
    case ULogBaseType::kUInt8:
      return "uint8_t";
    case ULogBaseType::kInt16:
      return "int16_t";
    case ULogBaseType::kUInt16:
      return "uint16_t";
    case ULogBaseType::kInt32:
      return "int32_t";
    case ULogBaseType::kUInt32:
      return "uint32_t";
    case ULogBaseType::kInt64:
      return "int64_t";
    case ULogBaseType::kUInt64:
      return "uint64_t";
    case ULogBaseType::kFloat:
      return "float";
    case ULogBaseType::kDouble:
      return "double";
    case ULogBaseType::kBool:
      return "bool";
    case ULogBaseType::kChar:
      return "char";
  }
  return "?";
}

double ULogValue::AsDouble() const {
  switch (kind) {
    case Kind::kSigned:
      return static_cast<double>(signed_value);
    case Kind::kUnsigned:
    case Kind::kBool:
      return static_cast<double>(unsigned_value);
    case Kind::kFloat:
      return float_value;
    case Kind::kString:
    case Kind::kBytes:
      break;
  }
  throw Error("ULog value of type " + type + " is not a number");
}

std::string ULogValue::ToString() const {
  switch (kind) {
    case Kind::kSigned:
      return std::to_string(signed_value);
    case Kind::kUnsigned:
      return std::to_string(unsigned_value);
    case Kind::kBool:
      return unsigned_value ? "True" : "False";
    case Kind::kFloat:
      return PythonFloat(float_value);
    case Kind::kString:
      return bytes;
    case Kind::kBytes:
      return PythonBytes(bytes);
  }
  return {};
}

std::string ULogLoggedMessage::LevelName() const {
  static const char* const kNames[] = {"EMERGENCY", "ALERT", "CRITICAL", "ERROR", "WARNING", "NOTICE", "INFO", "DEBUG"};
  if (level >= '0' && level <= '7') return kNames[level - '0'];
  return "UNKNOWN";
}

const ULogField* ULogTopic::FindField(std::string_view field_name) const {
  for (const ULogField& field : fields_)
    if (field.name == field_name) return &field;
  return nullptr;
}

double ULogTopic::Value(size_t message, const ULogField& field) const {
  return DecodeAsDouble(MessageData(message) + field.offset_bytes, field.type);
}

std::vector<double> ULogTopic::Column(std::string_view field_name) const {
  const ULogField* field = FindField(field_name);
  if (!field)
    throw Error("ULog topic " + name_ + " (multi id " + std::to_string(multi_id_) + ") has no field '" +
                std::string(field_name) + "'");
  std::vector<double> column(num_messages());
  const size_t stride = static_cast<size_t>(message_size_);
  const uint8_t* p = data_.data() + field->offset_bytes;
  for (size_t i = 0; i < column.size(); ++i, p += stride) column[i] = DecodeAsDouble(p, field->type);
  return column;
}

const ULogTopic* ULog::FindTopic(std::string_view name, int multi_id) const {
  for (const ULogTopic& topic : topics)
    if (topic.name() == name && topic.multi_id() == multi_id) return &topic;
  return nullptr;
}

const ULogTopic& ULog::Topic(std::string_view name, int multi_id) const {
  if (const ULogTopic* topic = FindTopic(name, multi_id)) return *topic;
  throw Error(source + ": no topic " + std::string(name) + " (multi id " + std::to_string(multi_id) + ") in this log");
}

std::vector<const ULogTopic*> ULog::TopicInstances(std::string_view name) const {
  std::vector<const ULogTopic*> instances;
  for (const ULogTopic& topic : topics)
    if (topic.name() == name) instances.push_back(&topic);
  return instances;
}

const ULogParameter* ULog::FindParameter(std::string_view name) const {
  const auto it = parameters.find(std::string(name));
  return it == parameters.end() ? nullptr : &it->second;
}

int ULog::DropoutTotalMs() const {
  int total = 0;
  for (const ULogDropout& dropout : dropouts) total += dropout.duration_ms;
  return total;
}

namespace internal {

// One pass over the message stream; see ulog.h for what is accepted and what throws.
class ULogParser {
 public:
  ULogParser(const uint8_t* data, size_t size, const std::string& source, const ULogReadOptions& options)
      : data_(data), size_(size), options_(options), topic_filter_(options.topics.begin(), options.topics.end()) {
    log_.source = source;
  }

  ULog Parse() {
    ParseHeader();
    size_t pos = kHeaderBytes;
    size_t segment = 0;  // index into the appended offsets of the segment being read
    while (true) {
      const size_t end = segment < log_.appended_offsets.size() ? log_.appended_offsets[segment] : size_;
      if (pos >= end) {
        if (segment >= log_.appended_offsets.size()) break;
        pos = log_.appended_offsets[segment++];
        continue;
      }
      const bool final_segment = segment >= log_.appended_offsets.size();
      size_t message_bytes = kMessageHeaderBytes;
      if (end - pos >= kMessageHeaderBytes) message_bytes += Load<uint16_t>(data_ + pos);
      if (message_bytes > end - pos) {
        if (!final_segment) {
          // Written up to the crash, then the appended data starts at the offset (pyulog drops it too).
          ++log_.num_cut_before_appended;
          log_.warnings.push_back("byte " + std::to_string(pos) + ": message cut by the appended data at byte " +
                                  std::to_string(end) + " dropped");
          pos = end;
          continue;
        }
        HandleTruncatedEnd(pos, message_bytes);
        break;
      }
      ParseMessage(pos, data_[pos + 2], data_ + pos + kMessageHeaderBytes, message_bytes - kMessageHeaderBytes);
      pos += message_bytes;
    }
    Finish();
    return std::move(log_);
  }

 private:
  struct FormatField {
    std::string type_name;             // base type or nested format name
    std::optional<ULogBaseType> base;  // set for base types
    int array_size = 1;
    std::string name;
  };
  struct Format {
    std::vector<FormatField> fields;
  };
  struct Layout {
    std::vector<ULogField> fields;  // trailing padding removed
    int message_size = 0;           // without trailing padding
    int full_size = 0;              // with it
    size_t timestamp_offset = 0;
  };

  [[noreturn]] void Fail(size_t offset, const std::string& what) const {
    throw Error(log_.source + ": byte " + std::to_string(offset) + ": " + what);
  }

  void ParseHeader() {
    if (size_ < kHeaderBytes)
      Fail(0, "file is " + std::to_string(size_) + " bytes, shorter than the 16-byte ULog header");
    if (std::memcmp(data_, kULogMagic, sizeof(kULogMagic)) != 0) Fail(0, "not a ULog file (bad magic bytes)");
    log_.file_version = data_[7];
    if (log_.file_version > 1)
      log_.warnings.push_back("ULog file version " + std::to_string(log_.file_version) + " is newer than 1; read as 1");
    log_.start_timestamp_us = Load<uint64_t>(data_ + 8);
    log_.last_timestamp_us = log_.start_timestamp_us;
  }

  void HandleTruncatedEnd(size_t pos, size_t message_bytes) {
    const size_t left = size_ - pos;
    const std::string what = "message of " + std::to_string(message_bytes) + " bytes runs past the end of the file (" +
                             std::to_string(left) + " bytes left)";
    if (!options_.allow_truncated_end) Fail(pos, "truncated file: " + what);
    if (left >= kMessageHeaderBytes && !IsKnownType(data_[pos + 2]))
      Fail(pos, "corrupt message header (type 0x" + Hex(data_[pos + 2]) + ") and " + what);
    if (!in_data_section_) Fail(pos, "truncated in the definitions section: " + what);
    log_.truncated_tail_bytes = left;
    log_.warnings.push_back("byte " + std::to_string(pos) + ": last message cut short (" + std::to_string(left) +
                            " of " + std::to_string(message_bytes) + " bytes); ignored");
  }

  static bool IsKnownType(uint8_t type) { return std::strchr("BFIMPQARDLCSO", type) != nullptr && type != 0; }

  static std::string Hex(uint8_t byte) {
    char text[4];
    std::snprintf(text, sizeof(text), "%02x", byte);
    return text;
  }

  void ParseMessage(size_t pos, uint8_t type, const uint8_t* body, size_t n) {
    switch (type) {
      case 'D':
        ParseData(pos, body, n);
        return;
      case 'B':
        ParseFlagBits(pos, body, n);
        return;
      case 'F':
        ParseFormat(pos, body, n);
        return;
      case 'I': {
        auto [name, value] = ParseKeyValue(pos, body, n);
        log_.info[name] = std::move(value);
        return;
      }
      case 'M': {
        if (n < 1) Fail(pos, "multi information message without payload");
        auto [name, value] = ParseKeyValue(pos, body + 1, n - 1);
        auto& lists = log_.info_multiple[name];
        if (body[0] != 0 && !lists.empty())
          lists.back().push_back(std::move(value));
        else
          lists.push_back({std::move(value)});
        return;
      }
      case 'P': {
        auto [name, value] = ParseParameter(pos, body, n);
        if (in_data_section_)
          log_.parameter_changes.push_back({log_.last_timestamp_us, name, value});
        else
          log_.parameters[name] = value;
        return;
      }
      case 'Q': {
        if (n < 1) Fail(pos, "default parameter message without payload");
        auto [name, value] = ParseParameter(pos, body + 1, n - 1);
        if (body[0] & 0x1) log_.default_parameters_system[name] = value;
        if (body[0] & 0x2) log_.default_parameters_current_setup[name] = value;
        return;
      }
      case 'A':
        in_data_section_ = true;
        ParseAddLogged(pos, body, n);
        return;
      case 'R':
        if (n < 2) Fail(pos, "remove-logged message shorter than 2 bytes");
        if (const uint16_t msg_id = Load<uint16_t>(body); msg_id < msg_id_to_topic_.size())
          msg_id_to_topic_[msg_id] = kUnsubscribed;
        return;
      case 'L': {
        in_data_section_ = true;
        if (n < 9) Fail(pos, "logged string message shorter than 9 bytes");
        ULogLoggedMessage message;
        message.level = body[0];
        message.timestamp_us = Load<uint64_t>(body + 1);
        message.text.assign(reinterpret_cast<const char*>(body + 9), n - 9);
        log_.logged_messages.push_back(std::move(message));
        return;
      }
      case 'C': {
        in_data_section_ = true;
        if (n < 11) Fail(pos, "tagged logged string message shorter than 11 bytes");
        ULogLoggedMessage message;
        message.level = body[0];
        message.tag = Load<uint16_t>(body + 1);
        message.timestamp_us = Load<uint64_t>(body + 3);
        message.text.assign(reinterpret_cast<const char*>(body + 11), n - 11);
        log_.logged_messages.push_back(std::move(message));
        return;
      }
      case 'S':
        ++log_.num_sync_messages;
        return;
      case 'O':
        if (n < 2) Fail(pos, "dropout message shorter than 2 bytes");
        log_.dropouts.push_back({log_.last_timestamp_us, Load<uint16_t>(body)});
        return;
      default:
        break;
    }
    // New message types may be added to the format; those are skipped, while a non-letter type can only
    // come from corruption.
    const bool letter = (type >= 'A' && type <= 'Z') || (type >= 'a' && type <= 'z');
    if (!letter) Fail(pos, "corrupt message header: unknown message type 0x" + Hex(type));
    ++log_.num_unknown_messages;
    if (log_.num_unknown_messages <= 10)
      log_.warnings.push_back("byte " + std::to_string(pos) + ": unknown message type '" + std::string(1, char(type)) +
                              "' skipped");
  }

  void ParseFlagBits(size_t pos, const uint8_t* body, size_t n) {
    if (n < 40) Fail(pos, "flag bits message has " + std::to_string(n) + " bytes, expected at least 40");
    if (pos != kHeaderBytes) {
      log_.warnings.push_back("byte " + std::to_string(pos) + ": flag bits message is not the first message");
      if (!log_.appended_offsets.empty()) Fail(pos, "second flag bits message");
    }
    std::copy(body, body + 8, log_.compat_flags.begin());
    std::copy(body + 8, body + 16, log_.incompat_flags.begin());
    // Only "data appended" (bit 0 of byte 0) is defined; any other incompatible flag means we cannot read it.
    if ((log_.incompat_flags[0] & ~0x1) != 0 ||
        std::any_of(log_.incompat_flags.begin() + 1, log_.incompat_flags.end(), [](uint8_t f) { return f != 0; }))
      Fail(pos, "unknown incompatible flag set: this ULog variant cannot be parsed");
    std::vector<uint64_t> offsets;
    for (int i = 0; i < 3; ++i) offsets.push_back(Load<uint64_t>(body + 16 + 8 * i));
    while (!offsets.empty() && offsets.back() == 0) offsets.pop_back();
    if (!(log_.incompat_flags[0] & 0x1)) return;  // offsets only count with the flag set
    uint64_t previous = pos + kMessageHeaderBytes + n;
    for (const uint64_t offset : offsets) {
      if (offset < previous || offset > size_)
        Fail(pos, "appended data offset " + std::to_string(offset) +
                      " is out of order or beyond the end of the file (" + std::to_string(size_) + " bytes)");
      previous = offset;
    }
    log_.appended_offsets = offsets;
  }

  void ParseFormat(size_t pos, const uint8_t* body, size_t n) {
    const std::string_view text(reinterpret_cast<const char*>(body), n);
    const size_t colon = text.find(':');
    if (colon == std::string_view::npos || colon == 0) Fail(pos, "format definition without 'name:'");
    Format format;
    std::string_view rest = text.substr(colon + 1);
    while (!rest.empty()) {
      const size_t semicolon = rest.find(';');
      const std::string_view item = rest.substr(0, semicolon);
      rest = semicolon == std::string_view::npos ? std::string_view() : rest.substr(semicolon + 1);
      if (item.empty()) continue;
      const size_t space = item.find(' ');
      if (space == std::string_view::npos || space == 0 || space + 1 >= item.size())
        Fail(pos, "format field '" + std::string(item) + "' is not 'type name'");
      FormatField field;
      std::string_view type = item.substr(0, space);
      field.name = std::string(item.substr(space + 1));
      const size_t bracket = type.find('[');
      if (bracket != std::string_view::npos) {
        if (type.back() != ']' || bracket == 0) Fail(pos, "bad array type '" + std::string(type) + "'");
        const std::string_view count = type.substr(bracket + 1, type.size() - bracket - 2);
        int array_size = 0;
        const auto result = std::from_chars(count.data(), count.data() + count.size(), array_size);
        if (result.ec != std::errc() || result.ptr != count.data() + count.size() || array_size < 0 ||
            array_size > 0xFFFF)
          Fail(pos, "bad array size in '" + std::string(type) + "'");
        field.array_size = array_size;
        type = type.substr(0, bracket);
      }
      field.type_name = std::string(type);
      field.base = BaseTypeFromName(type);
      format.fields.push_back(std::move(field));
    }
    formats_[std::string(text.substr(0, colon))] = std::move(format);
    layouts_.clear();  // a redefinition may change nested layouts
  }

  std::pair<std::string, ULogValue> ParseKeyValue(size_t pos, const uint8_t* body, size_t n) const {
    if (n < 1) Fail(pos, "information message without payload");
    const size_t key_len = body[0];
    if (1 + key_len > n) Fail(pos, "information key of " + std::to_string(key_len) + " bytes overruns its message");
    const std::string_view key(reinterpret_cast<const char*>(body + 1), key_len);
    const size_t space = key.find(' ');
    if (space == std::string_view::npos || space == 0 || space + 1 >= key.size())
      Fail(pos, "information key '" + std::string(key) + "' is not 'type name'");
    ULogValue value;
    value.type = std::string(key.substr(0, space));
    const uint8_t* v = body + 1 + key_len;
    const size_t v_size = n - 1 - key_len;
    const auto base = BaseTypeFromName(value.type);
    if (value.type.compare(0, 5, "char[") == 0) {
      value.kind = ULogValue::Kind::kString;
      value.bytes.assign(reinterpret_cast<const char*>(v), v_size);
    } else if (base) {
      if (static_cast<int>(v_size) != ULogBaseTypeSize(*base))
        Fail(pos, "information value '" + std::string(key) + "' has " + std::to_string(v_size) + " bytes, expected " +
                      std::to_string(ULogBaseTypeSize(*base)));
      switch (*base) {
        case ULogBaseType::kFloat:
          value.kind = ULogValue::Kind::kFloat;
          value.float_value = Load<float>(v);
          break;
        case ULogBaseType::kDouble:
          value.kind = ULogValue::Kind::kFloat;
          value.float_value = Load<double>(v);
          break;
        case ULogBaseType::kUInt8:
        case ULogBaseType::kUInt16:
        case ULogBaseType::kUInt32:
        case ULogBaseType::kUInt64: {
          value.kind = ULogValue::Kind::kUnsigned;
          uint64_t u = 0;
          std::memcpy(&u, v, v_size);
          value.unsigned_value = u;
          break;
        }
        case ULogBaseType::kBool:
          value.kind = ULogValue::Kind::kBool;
          value.unsigned_value = v[0] != 0;
          break;
        case ULogBaseType::kInt8:
        case ULogBaseType::kChar:
          value.kind = ULogValue::Kind::kSigned;
          value.signed_value = Load<int8_t>(v);
          break;
        case ULogBaseType::kInt16:
          value.kind = ULogValue::Kind::kSigned;
          value.signed_value = Load<int16_t>(v);
          break;
        case ULogBaseType::kInt32:
          value.kind = ULogValue::Kind::kSigned;
          value.signed_value = Load<int32_t>(v);
          break;
        case ULogBaseType::kInt64:
          value.kind = ULogValue::Kind::kSigned;
          value.signed_value = Load<int64_t>(v);
          break;
      }
    } else {
      value.kind = ULogValue::Kind::kBytes;  // other arrays (e.g. uint8_t[N]) and unknown types: raw bytes
      value.bytes.assign(reinterpret_cast<const char*>(v), v_size);
    }
    return {std::string(key.substr(space + 1)), std::move(value)};
  }

  std::pair<std::string, ULogParameter> ParseParameter(size_t pos, const uint8_t* body, size_t n) const {
    auto [name, value] = ParseKeyValue(pos, body, n);
    ULogParameter parameter;
    if (value.type == "float") {
      parameter.is_float = true;
      parameter.float_value = static_cast<float>(value.float_value);
    } else if (value.type == "int32_t") {
      parameter.int_value = static_cast<int32_t>(value.signed_value);
    } else {
      Fail(pos, "parameter " + name + " has type " + value.type + "; ULog parameters are int32_t or float");
    }
    return {std::move(name), parameter};
  }

  // Flattens a format into scalar fields (pyulog's naming), checking nesting and size.
  const Layout& LayoutOf(size_t pos, const std::string& name) {
    if (const auto it = layouts_.find(name); it != layouts_.end()) return it->second;
    Layout layout;
    size_t offset = 0, visits = 0;
    Flatten(pos, name, "", 0, &offset, &visits, &layout.fields);
    layout.full_size = static_cast<int>(offset);
    while (!layout.fields.empty() && layout.fields.back().name.compare(0, 8, "_padding") == 0) layout.fields.pop_back();
    layout.message_size = 0;
    if (!layout.fields.empty())
      layout.message_size =
          static_cast<int>(layout.fields.back().offset_bytes) + ULogBaseTypeSize(layout.fields.back().type);
    bool has_timestamp = false;
    for (const ULogField& field : layout.fields) {
      if (field.name == "timestamp") {
        if (field.type != ULogBaseType::kUInt64) Fail(pos, "topic " + name + ": 'timestamp' is not uint64_t");
        layout.timestamp_offset = field.offset_bytes;
        has_timestamp = true;
        break;
      }
    }
    if (!has_timestamp) Fail(pos, "topic " + name + " has no 'timestamp' field");
    return layouts_.emplace(name, std::move(layout)).first->second;
  }

  void Flatten(size_t pos, const std::string& type_name, const std::string& prefix, int depth, size_t* offset,
               size_t* visits, std::vector<ULogField>* fields) {
    if (depth > kMaxNestingDepth) Fail(pos, "format " + type_name + " nests deeper than 32 levels (recursive?)");
    const auto it = formats_.find(type_name);
    if (it == formats_.end()) Fail(pos, "no format definition for type '" + type_name + "'");
    for (const FormatField& f : it->second.fields) {
      const int count = f.array_size;
      for (int i = 0; i < count; ++i) {
        if (++*visits > kMaxFlattenVisits) Fail(pos, "format " + type_name + " is too large to flatten");
        const std::string name = count > 1 ? prefix + f.name + "[" + std::to_string(i) + "]" : prefix + f.name;
        if (f.base) {
          fields->push_back({name, *f.base, static_cast<uint32_t>(*offset)});
          *offset += static_cast<size_t>(ULogBaseTypeSize(*f.base));
        } else {
          Flatten(pos, f.type_name, name + ".", depth + 1, offset, visits, fields);
        }
        if (*offset > 0xFFFF) Fail(pos, "format " + type_name + " is larger than 65535 bytes");
      }
    }
  }

  void ParseAddLogged(size_t pos, const uint8_t* body, size_t n) {
    if (n < 4) Fail(pos, "add-logged message shorter than 4 bytes");
    const int multi_id = body[0];
    const uint16_t msg_id = Load<uint16_t>(body + 1);
    const std::string name(reinterpret_cast<const char*>(body + 3), n - 3);
    const Layout& layout = LayoutOf(pos, name);
    // msg_ids are small in practice (one per subscription), so a table indexed by them grows as needed.
    if (msg_id >= msg_id_to_topic_.size()) msg_id_to_topic_.resize(static_cast<size_t>(msg_id) + 1, kUnsubscribed);
    if (!topic_filter_.empty() && topic_filter_.count(name) == 0) {
      msg_id_to_topic_[msg_id] = kFiltered;
      return;
    }
    const auto key = std::make_pair(name, multi_id);
    auto it = topic_index_.find(key);
    if (it == topic_index_.end()) {
      ULogTopic topic;
      topic.name_ = name;
      topic.multi_id_ = multi_id;
      topic.fields_ = layout.fields;
      topic.message_size_ = layout.message_size;
      topic.timestamp_offset_ = layout.timestamp_offset;
      log_.topics.push_back(std::move(topic));
      full_sizes_.push_back(layout.full_size);
      it = topic_index_.emplace(key, static_cast<int32_t>(log_.topics.size() - 1)).first;
    }
    msg_id_to_topic_[msg_id] = it->second;
  }

  void ParseData(size_t pos, const uint8_t* body, size_t n) {
    if (n < 2) Fail(pos, "data message shorter than 2 bytes");
    const uint16_t msg_id = Load<uint16_t>(body);
    const int32_t index = msg_id < msg_id_to_topic_.size() ? msg_id_to_topic_[msg_id] : kUnsubscribed;
    if (index == kFiltered) return;
    if (index < 0) Fail(pos, "data message for msg_id " + std::to_string(msg_id) + ", which no subscription announced");
    ULogTopic& topic = log_.topics[static_cast<size_t>(index)];
    const size_t payload = n - 2;
    const auto message_size = static_cast<size_t>(topic.message_size_);
    // The logger leaves out the trailing padding; accept it if present.
    if (payload < message_size || payload > static_cast<size_t>(full_sizes_[static_cast<size_t>(index)]))
      Fail(pos, "data message of " + std::to_string(payload) + " bytes for topic " + topic.name_ + ", expected " +
                    std::to_string(message_size));
    const uint8_t* p = body + 2;
    topic.data_.insert(topic.data_.end(), p, p + message_size);
    const uint64_t timestamp = Load<uint64_t>(p + topic.timestamp_offset_);
    topic.timestamps_us_.push_back(timestamp);
    if (timestamp > log_.last_timestamp_us) log_.last_timestamp_us = timestamp;
  }

  void Finish() {
    std::sort(log_.topics.begin(), log_.topics.end(), [](const ULogTopic& a, const ULogTopic& b) {
      return a.name() != b.name() ? a.name() < b.name() : a.multi_id() < b.multi_id();
    });
  }

  const uint8_t* data_;
  size_t size_;
  const ULogReadOptions& options_;
  std::set<std::string> topic_filter_;
  ULog log_;
  bool in_data_section_ = false;
  std::unordered_map<std::string, Format> formats_;
  std::unordered_map<std::string, Layout> layouts_;
  std::map<std::pair<std::string, int>, int32_t> topic_index_;
  std::vector<int> full_sizes_;           // per topic index: message size with trailing padding
  std::vector<int32_t> msg_id_to_topic_;  // msg_id -> topic index, kUnsubscribed or kFiltered
};

}  // namespace internal

ULog ParseULog(const void* data, size_t size, const std::string& source_name, const ULogReadOptions& options) {
  return internal::ULogParser(static_cast<const uint8_t*>(data), size, source_name, options).Parse();
}

ULog ReadULog(const std::string& path, const ULogReadOptions& options) {
  const std::string bytes = ReadFile(path);
  return ParseULog(bytes.data(), bytes.size(), path, options);
}

}  // namespace rotorid
