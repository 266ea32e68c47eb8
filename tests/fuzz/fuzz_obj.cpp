// Fuzz target: the OBJ reader with its material library: the bytes after the first NUL are m.mtl,
// which the seeds name in `mtllib`.
#include "fuzz_input.h"

using namespace tw::fuzz;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const SplitInput in = splitAtNul(data, size);
  writeFile("m.mtl", in.second);
  return readAsScene(writeFile("model.obj", in.first));
}
