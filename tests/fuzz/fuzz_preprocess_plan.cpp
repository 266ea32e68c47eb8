// Fuzz target: the manifest of a split preprocessing run (`preprocess brick|merge --work DIR`
// read it from a shared folder other machines write).
#include <exception>

#include "fuzz_input.h"
#include "preprocess_plan.h"

using namespace tw;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = fuzz::writeFile("manifest.json", fuzz::all(data, size));
  try {
    const PreprocessPlan plan = readPreprocessPlan(path.parent_path());
    (void)plan;
  } catch (const std::exception&) {
    // A clear error is the right answer to a damaged manifest.
  }
  return 0;
}
