// What every fuzz target shares: the fuzzer's bytes as the files a reader opens, and a sink that
// holds a reader to its contract.
//
// Why files: the readers open paths (and glTF and OBJ follow relative paths to their buffers and
// materials), so the bytes are written to a private folder first. An input may carry a second
// file after its first NUL byte (the OBJ's material library, the glTF's buffer); the seeds refer
// to it by the name the target gives it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string_view>

#include "scene_sink.h"

namespace tw::fuzz {

// A folder of this process's own, made once and reused by every run.
const std::filesystem::path& scratchFolder();

// Writes `bytes` to scratchFolder() / name and returns the path.
std::filesystem::path writeFile(std::string_view name, std::string_view bytes);

// The input up to its first NUL byte, and what follows it (empty when there is none).
struct SplitInput {
  std::string_view first, second;
};
SplitInput splitAtNul(const uint8_t* data, size_t size);
inline std::string_view all(const uint8_t* data, size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

// Checks what a reader hands on: every index within its mesh, one normal and colour per position
// when present, positions read (so a sanitizer sees any uninitialised or freed memory). A broken
// contract aborts the run, which the fuzzer reports as a crash.
class ContractSink : public SceneSink {
 public:
  void onLayer(uint32_t index, const Layer& layer) override;
  void onObject(const SceneObject& object) override;
  double checksum() const { return sum_; }

 private:
  uint32_t layers_ = 0;
  double sum_ = 0.0;
};

// Reads `path` with the reader its extension selects (as `terawalk` does) into a ContractSink;
// errors thrown as exceptions are the expected answer to bad input. Returns 0.
int readAsScene(const std::filesystem::path& path);

}  // namespace tw::fuzz
