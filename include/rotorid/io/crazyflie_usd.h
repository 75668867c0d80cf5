#pragma once

// Reader for the Crazyflie micro-SD deck's event-based binary log (firmware usddeck.c; decoded
// in Python by cfusdlog.py). Layout, all little-endian:
//
//   uint8  magic = 0xBC
//   uint16 version (1 or 2)
//   uint16 number of event types, then per event type:
//            uint16 event id, event name + '\0', uint16 number of variables,
//            per variable "group.name(T)" + '\0' with T a struct type character
//   records: uint16 event id, timestamp (v1: uint32 ms, v2: uint64 us), payload: the event's
//            variables packed in header order, no padding
//   uint32 CRC32 (zlib polynomial) of every byte before it
//
// Every event type in the header becomes one table: a timestamp per record and one column per
// variable. Values are stored as double, which holds every type the format allows exactly.

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace rotorid {

// One logged variable of an event type.
struct UsdVariable {
  std::string name;      // "group.name" as in the header, e.g. "gyro.x", "rpm.m1"
  char type_char = 0;    // B b H h I i (unsigned/signed 8, 16, 32 bit), f (float32), e (float16)
  int size_bytes = 0;    // bytes in a record's payload
  int offset_bytes = 0;  // offset in the payload
};

// All records of one event type.
struct UsdEventTable {
  uint16_t id = 0;  // 0xFFFF is the firmware's fixedFrequency event
  std::string name;
  std::vector<UsdVariable> variables;
  int payload_bytes = 0;
  std::vector<uint64_t> timestamp_us;        // per record; version-1 millisecond ticks times 1000
  std::vector<std::vector<double>> columns;  // columns[k][record] for variables[k]

  int num_records() const { return static_cast<int>(timestamp_us.size()); }
  // The column of a variable, or nullptr when the event does not log it.
  const std::vector<double>* FindColumn(std::string_view variable_name) const;
};

struct CrazyflieUsdLog {
  std::string source;  // file name, for messages
  int version = 0;
  std::vector<UsdEventTable> events;  // in header order, including events without records
  size_t header_bytes = 0;            // where the first record starts
  uint32_t crc32 = 0;                 // as stored in the file

  // The event of that name, or nullptr.
  const UsdEventTable* FindEvent(std::string_view event_name) const;
  // "fixedFrequency (4643 records), estPose (511 records)", for messages.
  std::string DescribeEvents() const;
};

struct CrazyflieUsdOptions {
  // Check the trailing CRC32 and refuse a file whose CRC disagrees (a corrupt or cut-off file).
  // Default: true. Turning it off still assumes the last 4 bytes are the CRC.
  bool verify_crc = true;
};

// Reads a uSD log. Throws rotorid::Error "<file>: byte <offset>: <what is wrong>" for a
// truncated or corrupt file (bad magic, version or CRC, malformed header, unknown event id,
// a record running past the end).
CrazyflieUsdLog ReadCrazyflieUsd(const std::string& path, const CrazyflieUsdOptions& options = {});
// The same from bytes in memory; `source_name` names them in messages.
CrazyflieUsdLog ParseCrazyflieUsd(std::string_view bytes, const std::string& source_name,
                                  const CrazyflieUsdOptions& options = {});

// zlib-compatible CRC32 (reflected polynomial 0xEDB88320) of `size` bytes, continuing from `crc`.
uint32_t Crc32(const void* data, size_t size, uint32_t crc = 0);

}  // namespace rotorid
