// Binary little-endian PLY writer for triangle soups in world coordinates, for other tools.
//
// Every object is tessellated (parametrics and NURBS at `tolerance`), transformed to world space
// and appended: positions as float x, y, z (world coordinates rounded to float), uchar red, green,
// blue per vertex, and "list uchar int vertex_indices" triangles; normals are not written. Colour:
// the object's colour if non-zero, else the mesh's own vertex colours if it has them, else its
// layer's colour (from onLayer), else grey.
//
// Memory stays bounded: vertices go straight to "<path>.tmp" behind a fixed 512-byte header
// placeholder, faces to "<path>.faces.tmp"; finish() writes the real header (exact counts, the
// slack filled by a comment line), appends the faces and renames the file to `path`. Destroying
// the writer without finish() removes both temporary files. I/O failures (disk full) throw
// std::runtime_error naming the file. At most 2^31 vertices (indices are PLY "int").
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>

#include "scene_sink.h"

namespace tw {

class PlyWriter : public SceneWriter {
 public:
  PlyWriter(const std::filesystem::path& path, float tolerance);
  ~PlyWriter() override;
  void onLayer(uint32_t index, const Layer& layer) override;
  void onObject(const SceneObject& object) override;
  void finish() override;

  uint64_t vertexCount() const;
  uint64_t triangleCount() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace tw
