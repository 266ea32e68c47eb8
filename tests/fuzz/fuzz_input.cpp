// Shared fuzz harness parts; see fuzz_input.h.
#include "fuzz_input.h"

#include "scene_io.h"

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <type_traits>
#include <variant>

namespace tw::fuzz {

const std::filesystem::path& scratchFolder() {
  static const std::filesystem::path folder = [] {
    std::string pattern = (std::filesystem::temp_directory_path() / "tw-fuzz-XXXXXX").string();
    if (!::mkdtemp(pattern.data())) std::abort();
    return std::filesystem::path(pattern);
  }();
  return folder;
}

std::filesystem::path writeFile(std::string_view name, std::string_view bytes) {
  const std::filesystem::path path = scratchFolder() / name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), std::streamsize(bytes.size()));
  if (!out) std::abort();
  return path;
}

SplitInput splitAtNul(const uint8_t* data, size_t size) {
  const std::string_view all(reinterpret_cast<const char*>(data), size);
  const size_t nul = all.find('\0');
  if (nul == std::string_view::npos) return {all, {}};
  return {all.substr(0, nul), all.substr(nul + 1)};
}

void ContractSink::onLayer(uint32_t index, const Layer& layer) {
  if (index != layers_) std::abort();  // layers count up without gaps
  ++layers_;
  sum_ += double(layer.name.size());
}

void ContractSink::onObject(const SceneObject& object) {
  if (object.info.layer >= std::max(layers_, 1u)) std::abort();  // declared before use
  std::visit(
      [&](const auto& g) {
        using G = std::decay_t<decltype(g)>;
        if constexpr (std::is_same_v<G, TriangleMesh>) {
          if (g.indices.size() % 3 != 0) std::abort();
          if (!g.normals.empty() && g.normals.size() != g.positions.size()) std::abort();
          if (!g.colors.empty() && g.colors.size() != g.positions.size()) std::abort();
          for (uint32_t i : g.indices)
            if (i >= g.positions.size()) std::abort();
          for (const glm::vec3& p : g.positions) sum_ += double(p.x) + double(p.y) + double(p.z);
        } else {
          sum_ += 1.0;
        }
      },
      object.geometry);
}

int readAsScene(const std::filesystem::path& path) {
  ContractSink sink;
  try {
    readScene(path, sink);
  } catch (const std::exception&) {
    // A clear error is the right answer to a bad file; only crashes, leaks and hangs are bugs.
  }
  return 0;
}

}  // namespace tw::fuzz
