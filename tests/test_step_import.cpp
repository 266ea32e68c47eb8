// The STEP importer on the real samples in ../shared/data: one object per part instance named by
// its assembly path, colours and layers from the file (or the top-level assemblies), metres,
// watertight closed shells; damaged files give a FormatError naming the file, never a crash.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>

#include "format_error.h"
#include "patch_mesh_check.h"
#include "scene_io.h"
#include "step_importer.h"
#include "test_support.h"

namespace tw {
namespace {

namespace fs = std::filesystem;

fs::path sample(const char* name) { return test::sharedDataDir() / name; }

test::CollectingSink import(const fs::path& path) {
  test::CollectingSink sink;
  readStep(path, sink);
  return sink;
}

// World-space box of every object, from its transform and mesh.
void worldBounds(const test::CollectingSink& sink, glm::dvec3& lo, glm::dvec3& hi) {
  lo = glm::dvec3(1e300);
  hi = glm::dvec3(-1e300);
  for (const SceneObject& o : sink.objects)
    for (const glm::vec3& p : std::get<TriangleMesh>(o.geometry).positions) {
      const glm::dvec3 w = o.info.transform.apply(p);
      lo = glm::min(lo, w);
      hi = glm::max(hi, w);
    }
}

TEST(StepImport, AssemblyGivesOnePartInstancePerObjectNamedByItsPath) {
  const test::CollectingSink sink = import(sample("as1-oc-214.stp"));
  ASSERT_EQ(sink.objects.size(), 18u);  // 2 brackets, 6 bolts, 8 nuts, the rod and the plate
  std::set<std::string> names;
  std::map<std::string, int> leaf_count;
  for (const SceneObject& o : sink.objects) {
    names.insert(o.info.name);
    EXPECT_EQ(o.info.db_key, o.info.name);
    EXPECT_NE(o.info.color_rgba, 0u) << o.info.name << ": every part of this file is coloured";
    leaf_count[o.info.name.substr(o.info.name.rfind('/') + 1)]++;
  }
  EXPECT_EQ(names.size(), 18u) << "paths are unique";
  EXPECT_TRUE(names.count("as1/l-bracket-assembly_2/nut-bolt-assembly_3/bolt_1")) << *names.begin();
  EXPECT_TRUE(names.count("as1/plate_1"));
  EXPECT_EQ(leaf_count["bolt_1"], 6);
  ASSERT_EQ(sink.layers.size(), 1u);
  EXPECT_EQ(sink.layers[0].name, "256") << "the file's own layer";
  // Millimetres in the file, metres in the scene: the plate is 200 x 150 mm.
  glm::dvec3 lo, hi;
  worldBounds(sink, lo, hi);
  EXPECT_NEAR(hi.x - lo.x, 0.200, 1e-4);
  EXPECT_NEAR(hi.y - lo.y, 0.150, 1e-4);
  // Instances of one product share its mesh, placed apart.
  const SceneObject* bolts[2] = {nullptr, nullptr};
  for (const SceneObject& o : sink.objects)
    if (o.info.name.ends_with("bolt_1")) (bolts[0] ? bolts[1] : bolts[0]) = &o;
  ASSERT_TRUE(bolts[0] && bolts[1]);
  EXPECT_EQ(std::get<TriangleMesh>(bolts[0]->geometry).indices,
            std::get<TriangleMesh>(bolts[1]->geometry).indices);
  EXPECT_NE(bolts[0]->info.transform.origin, bolts[1]->info.transform.origin);
}

TEST(StepImport, FileWithoutLayersTakesTheTopLevelAssembliesAsLayers) {
  const test::CollectingSink sink = import(sample("as1_pe_203.stp"));
  EXPECT_EQ(sink.objects.size(), 18u);
  std::vector<std::string> layers;
  for (const Layer& l : sink.layers) layers.push_back(l.name);
  EXPECT_EQ(layers, (std::vector<std::string>{"PLATE", "L_BRACKET_ASSEMBLY",
                                              "L_BRACKET_ASSEMBLY:2", "ROD"}));
  for (const SceneObject& o : sink.objects) {
    const std::string& top = layers[o.info.layer];
    EXPECT_EQ(o.info.name.rfind("AS1_PE_ASM/" + top + "/", 0), 0u) << o.info.name;
    EXPECT_EQ(o.info.name.find("=>"), std::string::npos) << "unnamed instances take the product";
  }
}

// The fan housing is one closed solid of 189 B-spline and 131 analytic faces: its triangles,
// welded by position as the preprocessor does, have every edge used exactly twice.
TEST(StepImport, ClosedSolidOfBSplineFacesIsWatertight) {
  const test::CollectingSink sink = import(sample("Ventilator.stp"));
  ASSERT_EQ(sink.objects.size(), 1u);
  const TriangleMesh& mesh = std::get<TriangleMesh>(sink.objects[0].geometry);
  EXPECT_GT(mesh.triangleCount(), 5000u);
  std::map<std::pair<uint32_t, uint32_t>, int> edges;
  for (size_t t = 0; t < mesh.indices.size(); t += 3)
    for (int k = 0; k < 3; ++k) {
      uint32_t a = mesh.indices[t + k], b = mesh.indices[t + (k + 1) % 3];
      edges[{std::min(a, b), std::max(a, b)}]++;
    }
  size_t not_twice = 0;
  for (const auto& [edge, count] : edges) not_twice += count != 2;
  EXPECT_EQ(not_twice, 0u) << "of " << edges.size() << " edges";
  // Consistently wound: each edge appears once in each direction.
  std::set<std::pair<uint32_t, uint32_t>> directed;
  for (size_t t = 0; t < mesh.indices.size(); t += 3)
    for (int k = 0; k < 3; ++k)
      directed.insert({mesh.indices[t + k], mesh.indices[t + (k + 1) % 3]});
  EXPECT_EQ(directed.size(), 2 * edges.size());
}

// Its B-spline faces are tessellated by the conforming tessellator on the B-rep's edge nodes (the
// untrimmed ones zipped to them, the trimmed ones on the planned grid clipped to their wires),
// and the shell stays closed: OpenMesh's check finds no boundary edge, T-vertex, refused
// or inconsistently oriented face anywhere in it.
TEST(StepImport, ConformingBSplineFacesKeepTheShellClosedWithoutTVertices) {
  std::vector<std::string> notes;
  ReadOptions options;
  options.note = [&notes](const std::string& note) { notes.push_back(note); };
  test::CollectingSink sink;
  readStep(sample("Ventilator.stp"), sink, options);
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_EQ(notes[0], "B-spline faces 189 by the conforming tessellator: 31 untrimmed zipped to "
                      "the B-rep's edge nodes, 158 trimmed on its grid clipped to their wires "
                      "(refined by BRepMesh's deflection control); 0 by BRepMesh alone");
  ASSERT_EQ(sink.objects.size(), 1u);
  const TriangleMesh& mesh = std::get<TriangleMesh>(sink.objects[0].geometry);
  const PatchMeshReport report = checkPatchMesh(mesh, NurbsPatchSet{});
  EXPECT_EQ(report.faces, mesh.triangleCount());
  EXPECT_EQ(report.refused_faces, 0u);
  EXPECT_EQ(report.boundary_edges, 0u);
  EXPECT_EQ(report.t_vertices, 0u);
  EXPECT_EQ(report.inconsistent_orientation, 0u);
  EXPECT_TRUE(report.ok()) << report.first_problem;
}

// `--cad-bspline brepmesh`: the reference the fidelity bench compares against leaves every
// B-spline face to OpenCASCADE's own mesher.
TEST(StepImport, BSplineFacesCanBeLeftToOpenCascadesOwnMesher) {
  std::vector<std::string> notes;
  ReadOptions options;
  options.note = [&notes](const std::string& note) { notes.push_back(note); };
  options.cad.conforming_bspline = false;
  test::CollectingSink sink;
  readStep(sample("Ventilator.stp"), sink, options);
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find(": 0 untrimmed zipped to the B-rep's edge nodes, 0 trimmed on its grid"),
            std::string::npos) << notes[0];
  EXPECT_NE(notes[0].find("; 189 by BRepMesh alone"), std::string::npos) << notes[0];
  EXPECT_NE(sink.triangles(), import(sample("Ventilator.stp")).triangles());
}

TEST(StepImport, ReadSceneDispatchesByExtensionAndSplitsLargeParts) {
  EXPECT_EQ(sceneFormatOf("a/b.STEP"), SceneFormat::Step);
  EXPECT_EQ(sceneFormatOf("a/b.stp"), SceneFormat::Step);
  test::CollectingSink sink;
  ReadOptions options;
  options.max_part_triangles = 1000;
  readScene(sample("Ventilator.stp"), sink, options);
  ASSERT_GT(sink.objects.size(), 5u);
  for (const SceneObject& o : sink.objects) {
    EXPECT_EQ(o.info.id, 0u) << "parts of one object";
    EXPECT_LE(std::get<TriangleMesh>(o.geometry).triangleCount(), 1000u);
  }
  EXPECT_EQ(sink.triangles(), import(sample("Ventilator.stp")).triangles());
}

TEST(StepImport, MissingEmptyAndNonStepFilesNameTheFile) {
  const fs::path dir = test::scratchDir();
  auto rejects = [](const fs::path& p, const char* reason) {
    test::NullSink sink;
    try {
      readStep(p, sink);
      ADD_FAILURE() << p << ": accepted";
    } catch (const FormatError& e) {
      EXPECT_EQ(e.file(), p.string());
      EXPECT_NE(e.reason().find(reason), std::string::npos) << e.what();
    }
  };
  rejects(dir / "absent.stp", "no such file");
  test::writeFile(dir / "empty.stp", "");
  rejects(dir / "empty.stp", "not a readable STEP file");
  test::writeFile(dir / "text.stp", "hello\nworld\n");
  rejects(dir / "text.stp", "not a readable STEP file");
  // A valid header with no shapes.
  test::writeFile(dir / "no_shapes.stp",
                  "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\n"
                  "FILE_NAME('x','',(''),(''),'','','');\nFILE_SCHEMA(('CONFIG_CONTROL_DESIGN'));\n"
                  "ENDSEC;\nDATA;\nENDSEC;\nEND-ISO-10303-21;\n");
  rejects(dir / "no_shapes.stp", "not a valid STEP file");
  // A syntax error names OpenCASCADE's line.
  std::string garbled = test::readFile(sample("splinecage.stp"));
  const size_t at = garbled.find("#282=");
  ASSERT_NE(at, std::string::npos);
  garbled[at + 2] = 'q';
  test::writeFile(dir / "garbled.stp", garbled);
  rejects(dir / "garbled.stp", "Line ");
}

// A second reading of an unchanged file reuses the first translation (the preprocessor reads
// every input twice); a changed file or other options translate again.
TEST(StepImport, SecondReadingReusesTheTranslationUntilTheFileChanges) {
  const fs::path copy = test::scratchDir() / "part.stp";
  fs::copy_file(sample("splinecage.stp"), copy);
  ReadOptions quiet;
  std::vector<std::string> warnings;
  quiet.warn = [&](const std::string& w) { warnings.push_back(w); };
  test::CollectingSink first, second, meshed, changed;
  readStep(copy, first, quiet);
  const size_t first_warnings = warnings.size();
  readStep(copy, second, quiet);
  EXPECT_EQ(second.triangles(), first.triangles());
  EXPECT_EQ(warnings.size(), 2 * first_warnings) << "the warnings come again with the scene";
  fs::copy_file(sample("as1-oc-214.stp"), copy, fs::copy_options::overwrite_existing);
  readStep(copy, changed, quiet);
  EXPECT_EQ(changed.objects.size(), 18u) << "the new content, not the cached scene";
  ReadOptions other_tolerance = quiet;
  other_tolerance.cad.tolerance_m = 0.0005;
  readStep(copy, meshed, other_tolerance);
  EXPECT_NE(meshed.triangles(), changed.triangles()) << "another tolerance translates again";
}

// Warnings for entities that fail their checks, and the rest read.
TEST(StepImport, EntitiesFailingTheirChecksAreWarningsNamingThem) {
  std::vector<std::string> warnings;
  ReadOptions options;
  options.warn = [&](const std::string& w) { warnings.push_back(w); };
  test::CollectingSink sink;
  readStep(sample("splinecage.stp"), sink, options);  // its curve styles name no curve font
  EXPECT_EQ(sink.objects.size(), 1u);
  ASSERT_FALSE(warnings.empty());
  EXPECT_NE(warnings[0].find("splinecage.stp: entity #14: "), std::string::npos) << warnings[0];
}

// OpenCASCADE 7.6 dereferences null when a point of a B-spline curve has an unknown entity type;
// the translation runs in a child process, so that is an error naming the file, and this
// process carries on.
TEST(StepImport, CrashInsideOpenCascadeIsAnErrorNamingTheFile) {
  std::string damaged = test::readFile(sample("splinecage.stp"));
  const size_t at = damaged.find("#340=CARTESIAN_POINT");
  ASSERT_NE(at, std::string::npos);
  damaged.replace(at, 20, "#340=CARTESIANWPOINT");
  const fs::path path = test::scratchDir() / "unknown_type.stp";
  test::writeFile(path, damaged);
  ReadOptions quiet;
  quiet.warn = [](const std::string&) {};
  test::NullSink sink;
  try {
    readStep(path, sink, quiet);
    ADD_FAILURE() << "accepted";
  } catch (const FormatError& e) {
    EXPECT_EQ(e.file(), path.string());
    EXPECT_NE(e.reason().find("OpenCASCADE crashed translating the file"), std::string::npos)
        << e.what();
  }
  // And the next file reads as usual.
  EXPECT_EQ(import(sample("as1-oc-214.stp")).objects.size(), 18u);
}

TEST(StepImport, TruncatedAndCorruptedFilesGiveAFormatErrorOrAScene) {
  const std::string original = test::readFile(sample("splinecage.stp"));
  const int rejected = test::expectRobustToDamage(
      original, "damaged.stp",
      [](const fs::path& p, SceneSink& sink) {
        ReadOptions quiet;
        quiet.warn = [](const std::string&) {};
        readStep(p, sink, quiet);
      },
      100);
  EXPECT_GT(rejected, 50) << "short truncations cannot hold a shape";
}

}  // namespace
}  // namespace tw
