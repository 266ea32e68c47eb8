// Objects by layer name and database key; see object_queries.h.
#include "object_queries.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace tw {

uint32_t layerIndex(const PackageView& view, std::string_view name) {
  std::string known;
  for (uint32_t l = 0; l < view.layers().size(); ++l) {
    if (view.layerName(l) == name) return l;
    known += (known.empty() ? "" : ", ") + std::string(view.layerName(l));
  }
  throw std::invalid_argument(view.fileName() + ": no layer named '" + std::string(name) +
                              "' (layers: " + known + ")");
}

std::vector<uint32_t> objectsOfLayer(const PackageView& view, uint32_t layer) {
  std::vector<uint32_t> out;
  const auto objects = view.objects();
  for (uint32_t o = 0; o < objects.size(); ++o)
    if (objects[o].layer == layer) out.push_back(o);
  return out;
}

std::vector<uint32_t> objectsWithKeys(const PackageView& view,
                                      const std::unordered_set<std::string>& keys) {
  std::vector<uint32_t> out;
  std::string key;
  for (uint32_t o = 0; o < view.objects().size(); ++o) {
    key.assign(view.objectDbKey(o));
    if (!key.empty() && keys.count(key)) out.push_back(o);
  }
  return out;
}

std::vector<uint32_t> objectsNamed(const PackageView& view, std::string_view text) {
  std::vector<uint32_t> out;
  for (uint32_t o = 0; o < view.objects().size(); ++o)
    if (view.objectName(o).find(text) != std::string_view::npos ||
        view.objectDbKey(o).find(text) != std::string_view::npos)
      out.push_back(o);
  return out;
}

std::unordered_set<std::string> parseKeyList(const std::string& text) {
  std::unordered_set<std::string> keys;
  std::error_code ec;
  if (std::filesystem::is_regular_file(text, ec)) {
    std::ifstream in(text);
    for (std::string line; std::getline(in, line);) {
      while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
      if (!line.empty() && line[0] != '#') keys.insert(line);
    }
    if (keys.empty()) throw std::runtime_error(text + ": no database keys in the file");
    return keys;
  }
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = std::min(text.find(',', start), text.size());
    if (comma > start) keys.insert(text.substr(start, comma - start));
    start = comma + 1;
  }
  if (keys.empty()) throw std::runtime_error("no database keys in '" + text + "'");
  return keys;
}

bool objectsBounds(const PackageView& view, std::span<const uint32_t> objects, glm::dvec3& lo,
                   glm::dvec3& hi) {
  if (objects.empty()) return false;
  lo = glm::dvec3(INFINITY);
  hi = glm::dvec3(-INFINITY);
  for (uint32_t o : objects) {
    const pkg::ObjectRecord& r = view.objects()[o];
    lo = glm::min(lo, view.origin() + glm::dvec3(r.aabb_min[0], r.aabb_min[1], r.aabb_min[2]));
    hi = glm::max(hi, view.origin() + glm::dvec3(r.aabb_max[0], r.aabb_max[1], r.aabb_max[2]));
  }
  return true;
}

}  // namespace tw
