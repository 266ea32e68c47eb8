// Fuzz target: the camera-path text format (`render --path`, `--record`).
#include <exception>

#include "camera_path.h"
#include "fuzz_input.h"

using namespace tw;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = fuzz::writeFile("walk.path", fuzz::all(data, size));
  try {
    const CameraPath camera_path = readCameraPath(path);
    (void)camera_path;
  } catch (const std::exception&) {
    // A clear error is the right answer to a bad path file.
  }
  return 0;
}
