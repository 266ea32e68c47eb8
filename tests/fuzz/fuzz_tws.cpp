// Fuzz target: the .tws scene reader.
#include "fuzz_input.h"

using namespace tw::fuzz;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return readAsScene(writeFile("model.tws", all(data, size)));
}
