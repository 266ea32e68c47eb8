// Fuzz target: the PLY reader (ASCII and binary little/big endian).
#include "fuzz_input.h"

using namespace tw::fuzz;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return readAsScene(writeFile("model.ply", all(data, size)));
}
