// libFuzzer target for the ULog reader: arbitrary bytes must either parse or throw rotorid::Error,
// never crash, hang or trip the sanitizers. Parsed logs are also walked (every column of every topic)
// so that the layout and offsets the parser accepted are exercised too.
//
//   ./fuzz/ulog_fuzzer -runs=1000000 corpus_dir

#include <cstddef>
#include <cstdint>

#include "rotorid/core/error.h"
#include "rotorid/io/ulog.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  {
    rotorid::ULogReadOptions options;
    options.allow_truncated_end = size % 2 == 0;  // both settings, on alternate input lengths
    try {
      const rotorid::ULog log = rotorid::ParseULog(data, size, "fuzz.ulg", options);
      double sum = 0.0;
      for (const rotorid::ULogTopic& topic : log.topics) {
        for (const rotorid::ULogField& field : topic.fields())
          for (size_t i = 0; i < topic.num_messages(); ++i) sum += topic.Value(i, field);
      }
      for (const auto& [key, value] : log.info) sum += static_cast<double>(value.ToString().size() + key.size());
      if (sum == 1.2345) return 1;  // keeps the walk from being optimised away
    } catch (const rotorid::Error&) {
      // Expected for malformed input.
    }
  }
  return 0;
}
