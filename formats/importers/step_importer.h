// STEP (AP203, AP214, AP242) import through OpenCASCADE's XDE reader (STEPCAFControl_Reader),
// so the product structure, names, colours and layers come along with the shapes.
//
// Why XDE and not the plain STEPControl_Reader: a reviewer needs one selectable object per part
// instance, named where it sits in the assembly, with its colour and layer; the plain reader
// gives one anonymous compound.
//
// What comes out:
// - one scene object per part instance (a leaf of the assembly tree holding faces), placed by the
//   product of the locations down its path; its name is the path of instance names from the root
//   ("as1/l-bracket-assembly_1/nut-bolt-assembly_2/bolt_1"; an unnamed instance takes its
//   product's name, and a name repeated among siblings gets ":2", ":3"), and its database key is
//   the same path;
// - its colour: the instance's surface or generic colour, else its product's;
// - its layer: the first layer the layer tool gives the instance or its product; a file with no
//   layers at all takes the top-level components of the root assembly as layers (a single part
//   is its own layer);
// - its geometry: the product's faces meshed by BRepMesh_IncrementalMesh at a linear deflection
//   of min(2 mm, 0.2 % of the part's bounding diagonal) (or CadOptions::tolerance_m) and 20
//   degrees, in metres, Z up. Faces
//   sharing an edge share its discretization, so the triangles of a closed shell are watertight
//   once welded by position (the preprocessor's weld does that). A product instanced many times
//   is meshed once.
// Robustness: OpenCASCADE dereferences the null handles a damaged file leaves, so the translation
// runs in a child process (fork) that writes the objects to a temporary .tws scene; a crash there
// becomes a FormatError here, and the parent streams the scene file to the sink. A syntax error
// is an error naming OpenCASCADE's line; an entity that fails its checks (a parameter of the
// wrong type) is a warning naming its #id (ReadOptions::warn), and the rest is read.
// Memory: the child holds the whole model and B-rep (OpenCASCADE loads the file whole) and gives
// it back when it exits; the parent holds one object part at a time (at most
// options.max_part_triangles triangles).
#pragma once

#include <filesystem>

#include "read_options.h"
#include "scene_sink.h"

namespace tw {

// Throws FormatError naming the file (and, when OpenCASCADE reports it, the entity or line) for a
// file that cannot be read or transferred, or that holds no faces.
void readStep(const std::filesystem::path& path, SceneSink& sink, const ReadOptions& options = {});

}  // namespace tw
