// Objects beyond the scene's documented range are refused where they are read, naming the file
// and the object: a primitive 1e20 m across once passed `info` and then aborted `preprocess`
// inside Embree (exit 134), and an origin of 1e308 failed deep inside the package writer.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "format_error.h"
#include "scene_io.h"
#include "scene_range.h"
#include "test_support.h"
#include "tws_writer.h"

namespace tw {
namespace {

namespace fs = std::filesystem;

// A scene of one ordinary box and `odd`, written as .tws.
fs::path sceneWith(const SceneObject& odd) {
  const fs::path path = test::scratchDir() / "odd.tws";
  TwsWriter writer(path);
  writer.onLayer(0, Layer{"default"});
  SceneObject box{ObjectInfo{}, Primitive{Box{glm::vec3(1.0f)}}};
  box.info.id = 0;
  box.info.name = "ordinary";
  writer.onObject(box);
  writer.onObject(odd);
  writer.finish();
  return path;
}

SceneObject named(uint32_t id, const char* name, Geometry geometry) {
  SceneObject o{ObjectInfo{}, std::move(geometry)};
  o.info.id = id;
  o.info.name = name;
  return o;
}

// The error readScene gives, or "" when it reads the file.
std::string readError(const fs::path& path) {
  test::CollectingSink sink;
  try {
    readScene(path, sink);
  } catch (const FormatError& e) {
    return e.what();
  }
  return "";
}

TEST(SceneRange, ObjectsBeyondTheRangeAreAnErrorNamingFileAndObject) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  SceneObject far = named(3, "far", Primitive{Box{glm::vec3(1.0f)}});
  far.info.transform.origin = glm::dvec3(1e308, 0.0, 0.0);
  SceneObject mesh = named(4, "bad vertex", TriangleMesh{{{0, 0, 0}, {1, 0, 0}, {0, nan, 0}}, {}, {}, {0, 1, 2}});
  const std::vector<std::pair<SceneObject, std::string>> cases = {
      {named(1, "huge box", Primitive{Box{glm::vec3(1e20f)}}),
       "object 1 'huge box': it measures 2e+20 m, beyond the 1e+07 m an object may measure"},
      {far, "object 3 'far': it reaches 1e+308 m from the origin, beyond the 1e+09 m a scene may span"},
      {named(5, "long cylinder", Primitive{Cylinder{1.0f, 3.4e38f, true}}),
       "object 5 'long cylinder': it measures 3.4e+38 m"},
  };
  for (const auto& [object, message] : cases) {
    const fs::path path = sceneWith(object);
    const std::string error = readError(path);
    EXPECT_NE(error.find(path.string()), std::string::npos) << error;
    EXPECT_NE(error.find(message), std::string::npos) << error;
  }
  // What the .tws writer already refuses to write, the sink refuses for every other reader.
  test::CollectingSink inner;
  RangeCheckedSink checked("some.obj", inner);
  const std::vector<std::pair<SceneObject, std::string>> refused = {
      {named(2, "nan cylinder", Primitive{Cylinder{nan, 1.0f, true}}),
       "some.obj: object 2 'nan cylinder': a primitive dimension is not finite"},
      {mesh, "some.obj: object 4 'bad vertex': a vertex position is not finite"},
  };
  for (const auto& [object, message] : refused) {
    try {
      checked.onObject(object);
      ADD_FAILURE() << message << ": passed";
    } catch (const FormatError& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  }
  EXPECT_TRUE(inner.objects.empty());
  // At the limits, not past them: a 10,000 km object 900,000 km out reads.
  SceneObject big = named(6, "big", Primitive{Box{glm::vec3(4.9e6f)}});
  big.info.transform.origin = glm::dvec3(9e8, 0.0, 0.0);
  EXPECT_EQ(readError(sceneWith(big)), "");
}

// What a user ran: preprocess and snapshot of the 1e20 box stop with the error, not an abort.
TEST(SceneRange, PreprocessAndSnapshotStopWithTheErrorInsteadOfAborting) {
  const fs::path path = sceneWith(named(1, "huge box", Primitive{Box{glm::vec3(1e20f)}}));
  const fs::path dir = path.parent_path();
  for (const std::string& verb : {"preprocess --quiet " + path.string() + " -o " + (dir / "p.twk").string(),
                                 "snapshot " + path.string() + " -o " + (dir / "p.png").string(),
                                 "info " + path.string()}) {
    const test::CommandResult r = test::runTerawalk(verb);
    EXPECT_EQ(r.exit_code, 1) << verb << ": " << r.output;
    EXPECT_NE(r.output.find("object 1 'huge box': it measures 2e+20 m"), std::string::npos)
        << verb << ": " << r.output;
  }
  EXPECT_FALSE(fs::exists(dir / "p.twk"));
}

}  // namespace
}  // namespace tw
