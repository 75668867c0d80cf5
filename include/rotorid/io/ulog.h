#pragma once

// Reader for PX4 ULog files (.ulg), the format of the PX4 logger, as specified in the PX4 guide
// ("ULog File Format", docs.px4.io/main/en/dev_log/ulog_file_format): header, flag bits (with
// appended-data offsets), format definitions (nested types, arrays, padding), information messages
// (single 'I' and multiple 'M'), parameters ('P') and their defaults ('Q'), subscriptions ('A'/'R'),
// data ('D'), logged strings ('L') and tagged logged strings ('C'), sync ('S') and dropouts ('O').
//
// The whole file is read into memory and parsed in one pass; topic data stays packed as logged and is
// decoded per column on request, so a few MB parse in milliseconds. Timestamps stay the logger's
// integer microseconds (uint64) here; conversion to seconds happens in the PX4 mapping.
//
// Errors: anything malformed throws rotorid::Error "<file>: byte <offset>: <what is wrong>". The one
// tolerated defect (as pyulog does) is a last message cut short at the end of the file, which is what
// a logger stopped by a power loss leaves behind: it is dropped and counted in ULog::truncated_tail_bytes
// (see ULogReadOptions::allow_truncated_end).

#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace rotorid {

// The scalar types a ULog field can have.
enum class ULogBaseType : uint8_t {
  kInt8,
  kUInt8,
  kInt16,
  kUInt16,
  kInt32,
  kUInt32,
  kInt64,
  kUInt64,
  kFloat,
  kDouble,
  kBool,
  kChar
};
// Size in bytes and the name used in ULog format strings ("int8_t", "float", "bool", ...).
int ULogBaseTypeSize(ULogBaseType type);
const char* ULogBaseTypeName(ULogBaseType type);

// One scalar field of a topic message after nested types and arrays are flattened the way pyulog
// names them: "timestamp", "gyro_rad[0]", "esc[2].esc_rpm" (arrays of size 1 carry no index).
struct ULogField {
  std::string name;
  ULogBaseType type = ULogBaseType::kUInt8;
  uint32_t offset_bytes = 0;  // from the start of the message payload (after msg_id)
};

// The value of an information message ('I', 'M'), typed as declared in the log.
struct ULogValue {
  enum class Kind { kSigned, kUnsigned, kFloat, kBool, kString, kBytes };
  std::string type;  // as declared: "int32_t", "char[40]", "uint8_t[16]", ...
  Kind kind = Kind::kString;
  int64_t signed_value = 0;     // kSigned (int8..int64, char)
  uint64_t unsigned_value = 0;  // kUnsigned (uint8..uint64), kBool (0/1)
  double float_value = 0.0;     // kFloat (float, double)
  std::string bytes;            // kString: the text (char[N]); kBytes: raw bytes of any other array

  bool is_number() const { return kind != Kind::kString && kind != Kind::kBytes; }
  // Numeric value; throws rotorid::Error for strings and byte arrays.
  double AsDouble() const;
  // As pyulog prints it (Python's str()): integers in decimal, floats in shortest round-trip form,
  // True/False, strings verbatim, byte arrays as a Python bytes literal.
  std::string ToString() const;
};

// A parameter value: ULog parameters are int32_t or float.
struct ULogParameter {
  bool is_float = false;
  int32_t int_value = 0;
  float float_value = 0.0f;
  double value() const { return is_float ? static_cast<double>(float_value) : static_cast<double>(int_value); }
};

// A parameter set during logging ('P' in the data section), at the latest data timestamp seen so far.
struct ULogParameterChange {
  uint64_t timestamp_us = 0;
  std::string name;
  ULogParameter value;
};

// A logged string ('L') or tagged logged string ('C').
struct ULogLoggedMessage {
  uint8_t level = 0;  // as stored: ASCII '0' (emergency) .. '7' (debug) from PX4
  uint64_t timestamp_us = 0;
  std::string text;
  std::optional<uint16_t> tag;  // set for tagged messages only
  // "EMERGENCY", "ALERT", "CRITICAL", "ERROR", "WARNING", "NOTICE", "INFO", "DEBUG" or "UNKNOWN".
  std::string LevelName() const;
};

// A dropout ('O'): the logger lost `duration_ms` of data; placed at the latest data timestamp seen.
struct ULogDropout {
  uint64_t timestamp_us = 0;
  uint16_t duration_ms = 0;
};

namespace internal {
class ULogParser;
}

// All messages of one topic instance (name, multi_id), packed as logged.
class ULogTopic {
 public:
  const std::string& name() const { return name_; }
  int multi_id() const { return multi_id_; }
  // The flattened fields, trailing padding removed.
  const std::vector<ULogField>& fields() const { return fields_; }
  // Bytes per message (sum of the field sizes without trailing padding; pyulog's "message size").
  int message_size() const { return message_size_; }
  size_t num_messages() const { return timestamps_us_.size(); }
  // The 'timestamp' field of every message (us, as logged; not necessarily monotonic).
  const std::vector<uint64_t>& timestamps_us() const { return timestamps_us_; }

  const ULogField* FindField(std::string_view field_name) const;
  bool HasField(std::string_view field_name) const { return FindField(field_name) != nullptr; }
  // Every message's value of one field as double, e.g. Column("gyro_rad[0]"). Throws rotorid::Error
  // naming the topic and the field when there is no such field.
  std::vector<double> Column(std::string_view field_name) const;
  double Value(size_t message, const ULogField& field) const;
  // The raw payload of one message (message_size() bytes).
  const uint8_t* MessageData(size_t message) const {
    return data_.data() + message * static_cast<size_t>(message_size_);
  }

 private:
  friend class internal::ULogParser;
  std::string name_;
  int multi_id_ = 0;
  std::vector<ULogField> fields_;
  int message_size_ = 0;
  size_t timestamp_offset_ = 0;
  std::vector<uint8_t> data_;
  std::vector<uint64_t> timestamps_us_;
};

struct ULogReadOptions {
  // Accept a file whose last message is cut short (logger stopped mid-write): the partial message is
  // dropped and its bytes counted in ULog::truncated_tail_bytes. False: that is an error too.
  // Default: true (pyulog does the same).
  bool allow_truncated_end = true;
  // Topics to decode; data of others is skipped (their subscriptions are still checked). Empty: all.
  std::vector<std::string> topics;
};

// A parsed ULog file.
struct ULog {
  std::string source;  // file name (or the name given to ParseULog), for messages
  int file_version = 0;
  uint64_t start_timestamp_us = 0;  // from the header
  uint64_t last_timestamp_us = 0;   // largest data timestamp (or the start), as pyulog's last_timestamp
  std::array<uint8_t, 8> compat_flags{};
  std::array<uint8_t, 8> incompat_flags{};
  std::vector<uint64_t> appended_offsets;  // file offsets of appended data (trailing zeros removed)

  std::map<std::string, ULogValue> info;                                     // 'I' by key
  std::map<std::string, std::vector<std::vector<ULogValue>>> info_multiple;  // 'M': key -> lists of parts
  std::map<std::string, ULogParameter> parameters;                           // initial values ('P' before data)
  std::vector<ULogParameterChange> parameter_changes;                        // 'P' in the data section
  std::map<std::string, ULogParameter> default_parameters_system;            // 'Q' with bit 0
  std::map<std::string, ULogParameter> default_parameters_current_setup;     // 'Q' with bit 1
  std::vector<ULogTopic> topics;                   // every subscribed topic instance, sorted by (name, multi_id)
  std::vector<ULogLoggedMessage> logged_messages;  // 'L' and 'C' in file order
  std::vector<ULogDropout> dropouts;
  int num_sync_messages = 0;

  // Tolerated irregularities (never silently: each is counted here).
  size_t truncated_tail_bytes = 0;    // bytes of a cut-off last message that were ignored
  int num_unknown_messages = 0;       // messages of an unknown type, skipped (forward compatibility)
  int num_cut_before_appended = 0;    // messages crossing an appended-data offset, dropped
  std::vector<std::string> warnings;  // one line per irregularity, for the user

  const ULogTopic* FindTopic(std::string_view name, int multi_id = 0) const;
  // Throws rotorid::Error naming the file and the topic when absent.
  const ULogTopic& Topic(std::string_view name, int multi_id = 0) const;
  // All instances of a topic, by multi_id.
  std::vector<const ULogTopic*> TopicInstances(std::string_view name) const;
  const ULogParameter* FindParameter(std::string_view name) const;
  int DropoutTotalMs() const;
};

// Reads and parses a ULog file. Throws rotorid::Error "<path>: byte <offset>: <problem>".
ULog ReadULog(const std::string& path, const ULogReadOptions& options = {});
// Parses a ULog held in memory (the fuzz target's entry point); `source_name` prefixes errors.
ULog ParseULog(const void* data, size_t size, const std::string& source_name, const ULogReadOptions& options = {});

}  // namespace rotorid
