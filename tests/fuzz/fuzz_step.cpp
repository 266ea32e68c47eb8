// Fuzz target: the STEP importer (OpenCASCADE's reader and our conversion of its shapes).
#include "fuzz_input.h"

using namespace tw::fuzz;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return readAsScene(writeFile("model.stp", all(data, size)));
}
