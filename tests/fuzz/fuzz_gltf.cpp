// Fuzz target: the glTF reader: JSON, with the bytes after the first NUL as b.bin, the buffer the
// seeds name by `uri`.
#include "fuzz_input.h"

using namespace tw::fuzz;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const SplitInput in = splitAtNul(data, size);
  writeFile("b.bin", in.second);
  return readAsScene(writeFile("model.gltf", in.first));
}
