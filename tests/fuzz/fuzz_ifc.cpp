// Fuzz target: the IFC importer (the STEP clear-text parser and the geometry built from it).
#include "fuzz_input.h"

using namespace tw::fuzz;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  return readAsScene(writeFile("model.ifc", all(data, size)));
}
