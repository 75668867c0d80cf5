// libFuzzer target for the YAML readers: vehicle files, column maps, batch manifests and the
// loader --config goes through. Arbitrary bytes must either parse or throw rotorid::Error, never
// crash, hang (alias bombs, deep nesting) or trip the sanitizers. Found so far: yaml-cpp 0.7's
// LoadAll never returning on ",e," and a manifest key that is a map (a YAML::BadConversion, not a
// rotorid::Error).
//
//   ./fuzz/yaml_fuzzer -runs=1000000 -max_len=4096 corpus_dir

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "rotorid/core/error.h"
#include "rotorid/io/batch_manifest.h"
#include "rotorid/io/column_map.h"
#include "rotorid/io/vehicle_yaml.h"
#include "rotorid/io/yaml_document.h"

namespace {

// Walks what a reader may walk after LoadYaml accepted it (the --config options become JSON so).
size_t CountNodes(const YAML::Node& node) {
  size_t count = 1;
  if (node.IsSequence() || node.IsMap())
    for (const auto& entry : node)
      count += node.IsMap() ? CountNodes(entry.first) + CountNodes(entry.second) : CountNodes(entry);
  return count;
}

template <class Parse>
void Try(Parse parse) {
  try {
    parse();
  } catch (const rotorid::Error&) {
    // Expected for malformed input.
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  Try([&] {
    // The budget LoadYaml enforces: at most twice the text's size in nodes, plus 1000.
    if (CountNodes(rotorid::LoadYaml(text, "fuzz.yaml")) > 2 * size + 1001) std::abort();
  });
  Try([&] { rotorid::ParseVehicleYaml(text, "vehicle.yaml"); });
  Try([&] { rotorid::ParseColumnMap(text, "map.yaml"); });
  Try([&] { rotorid::ParseBatchManifest(text, "manifests/manifest.yaml"); });
  return 0;
}
