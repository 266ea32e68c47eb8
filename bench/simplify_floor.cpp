// simplify_floor: how few triangles meshoptimizer itself needs to draw a model within a given
// object-space error, as a floor for what a cluster DAG's cut can draw at that error.
//
// The runtime's cut at tau 1 may use any cluster whose error projects below one pixel, so the
// triangles it draws are bounded below by the best simplification of the model at about one
// pixel's size in metres. Two anchors, both from meshoptimizer (Debian's 0.18):
//  - per part, meshopt_simplify with no triangle target: the topology-keeping path that
//    clusterlod and our DAG take first; no part is merged with another, so a closed part keeps a
//    minimum and open borders stay;
//  - the whole model, meshopt_simplifySloppy: vertex clustering over every part at once, which may
//    merge neighbouring parts (the fallback clusterlod takes for groups that do not simplify).
// Every part is welded by position and stripped of exact repeated triangles first, as the
// preprocessor does.
//
//   build/rel/bench/simplify_floor ../shared/data/duplex-mep.obj 0.023 0.037
//
// Prints one line per error: input, welded and deduplicated, per-part and whole-model counts.
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <map>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <glm/glm.hpp>
#include <meshoptimizer.h>

#include "scene_io.h"
#include "scene_sink.h"

namespace {

struct Part {
  std::vector<glm::vec3> positions;  // relative to the model's first origin
  std::vector<uint32_t> indices;
};

// Gathers each object's mesh triangles into one part per object id.
class PartSink : public tw::SceneSink {
 public:
  void onLayer(uint32_t, const tw::Layer&) override {}
  void onObject(const tw::SceneObject& object) override {
    const auto* mesh = std::get_if<tw::TriangleMesh>(&object.geometry);
    if (!mesh) return;
    if (!has_origin_) origin_ = object.info.transform.origin, has_origin_ = true;
    Part& part = parts[object.info.id];
    const auto base = static_cast<uint32_t>(part.positions.size());
    for (const glm::vec3& p : mesh->positions)
      part.positions.push_back(glm::vec3(object.info.transform.apply(p) - origin_));
    for (uint32_t i : mesh->indices) part.indices.push_back(base + i);
  }
  std::map<uint32_t, Part> parts;

 private:
  glm::dvec3 origin_{0.0};
  bool has_origin_ = false;
};

// Welds equal positions and drops degenerate and exactly repeated triangles.
Part weldAndDeduplicate(const Part& part) {
  std::vector<unsigned> remap(part.positions.size());
  const size_t unique = meshopt_generateVertexRemap(remap.data(), part.indices.data(),
                                                    part.indices.size(), part.positions.data(),
                                                    part.positions.size(), sizeof(glm::vec3));
  Part welded;
  welded.positions.resize(unique);
  meshopt_remapVertexBuffer(welded.positions.data(), part.positions.data(), part.positions.size(),
                            sizeof(glm::vec3), remap.data());
  std::vector<std::array<uint32_t, 3>> seen;
  std::vector<std::array<uint32_t, 3>> triangles;
  for (size_t i = 0; i + 2 < part.indices.size(); i += 3) {
    const std::array<uint32_t, 3> t{remap[part.indices[i]], remap[part.indices[i + 1]],
                                    remap[part.indices[i + 2]]};
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
    triangles.push_back(t);
  }
  std::vector<size_t> order(triangles.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  auto sortedKey = [&](size_t i) {
    std::array<uint32_t, 3> k = triangles[i];
    std::sort(k.begin(), k.end());
    return k;
  };
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return sortedKey(a) < sortedKey(b); });
  for (size_t n = 0; n < order.size(); ++n) {
    if (n > 0 && sortedKey(order[n]) == sortedKey(order[n - 1])) continue;
    for (uint32_t v : triangles[order[n]]) welded.indices.push_back(v);
  }
  return welded;
}

// Triangles meshopt_simplify keeps for `part` at an absolute error of `error_m`.
size_t simplifiedTriangles(const Part& part, double error_m) {
  if (part.indices.empty()) return 0;
  const float scale = meshopt_simplifyScale(&part.positions[0].x, part.positions.size(), sizeof(glm::vec3));
  const float relative = scale > 0.0f ? float(error_m / scale) : 0.0f;
  std::vector<uint32_t> out(part.indices.size());
  float reached = 0.0f;
  return meshopt_simplify(out.data(), part.indices.data(), part.indices.size(), &part.positions[0].x,
                          part.positions.size(), sizeof(glm::vec3), 0, relative, 0, &reached) / 3;
}

// Triangles meshopt_simplifySloppy keeps for the whole model at an absolute error of `error_m`.
size_t sloppyTriangles(const Part& model, double error_m) {
  if (model.indices.empty()) return 0;
  const float scale = meshopt_simplifyScale(&model.positions[0].x, model.positions.size(), sizeof(glm::vec3));
  std::vector<uint32_t> out(model.indices.size());
  float reached = 0.0f;
  return meshopt_simplifySloppy(out.data(), model.indices.data(), model.indices.size(),
                                &model.positions[0].x, model.positions.size(), sizeof(glm::vec3), 0,
                                scale > 0.0f ? float(error_m / scale) : 0.0f, &reached) / 3;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"meshoptimizer's floor: triangles needed at a given object-space error"};
  std::string input;
  std::vector<double> errors_m;
  std::string up = "auto";
  app.add_option("input", input, "Mesh file (OBJ, PLY, STL, glTF)")->required();
  app.add_option("errors", errors_m, "Object-space errors in metres")->required();
  app.add_option("--up", up, "Up axis: auto (the format's), y or z")
      ->check(CLI::IsMember({"auto", "y", "z"}));
  CLI11_PARSE(app, argc, argv);
  try {
    tw::ReadOptions options;
    options.up = up == "y" ? tw::UpAxis::Y : up == "z" ? tw::UpAxis::Z : tw::UpAxis::Auto;
    PartSink sink;
    tw::readScene(input, sink, options);

    std::vector<Part> parts;
    Part model;
    size_t input_triangles = 0;
    for (const auto& [id, raw] : sink.parts) {
      input_triangles += raw.indices.size() / 3;
      parts.push_back(weldAndDeduplicate(raw));
      const auto base = static_cast<uint32_t>(model.positions.size());
      model.positions.insert(model.positions.end(), parts.back().positions.begin(), parts.back().positions.end());
      for (uint32_t i : parts.back().indices) model.indices.push_back(base + i);
    }
    model = weldAndDeduplicate(model);  // parts that touch share their vertices for the sloppy pass
    size_t kept = 0;
    for (const Part& p : parts) kept += p.indices.size() / 3;
    std::printf("%s: %zu parts, %zu input triangles, %zu after weld and repeats\n", input.c_str(),
                parts.size(), input_triangles, kept);
    for (double e : errors_m) {
      size_t per_part = 0;
      for (const Part& p : parts) per_part += simplifiedTriangles(p, e);
      std::printf("error %.4f m: simplify per part %zu triangles, sloppy whole model %zu triangles\n",
                  e, per_part, sloppyTriangles(model, e));
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "simplify_floor: %s\n", e.what());
    return 1;
  }
  return 0;
}
