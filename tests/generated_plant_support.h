// A one-module generated plant (about 200K equivalent triangles, seed 1) with its project
// database, made once per test program through the `terawalk` executable, for the tests that
// pick, select and review objects of a real-looking plant; and the vector argument they pass to
// the executable.
#pragma once

#include <cstdio>
#include <filesystem>
#include <string>

#include <glm/glm.hpp>

#include "test_support.h"

namespace tw::test {

struct GeneratedPlant {
  std::filesystem::path package, db, scene;  // the package names the database (preprocess --db)
};

inline const GeneratedPlant& generatedPlant() {
  static const GeneratedPlant plant = [] {
    const auto dir = processScratchDir("generated_plant");
    GeneratedPlant out{dir / "plant.twk", dir / "plant.db", dir / "plant.tws"};
    const auto& tws = out.scene;
    CommandResult gen = runTerawalk("gen plant --quiet --triangles 200K --seed 1 -o " +
                                    tws.string() + " --db " + out.db.string());
    EXPECT_EQ(gen.exit_code, 0) << gen.output;
    CommandResult pre =
        runTerawalk("preprocess --quiet " + tws.string() + " -o " + out.package.string() +
                    " --db " + out.db.string());
    EXPECT_EQ(pre.exit_code, 0) << pre.output;
    return out;
  }();
  return plant;
}

// "x,y,z" with every digit a double holds.
inline std::string vec3Arg(const glm::dvec3& v) {
  char text[128];
  std::snprintf(text, sizeof text, "%.17g,%.17g,%.17g", v.x, v.y, v.z);
  return text;
}

}  // namespace tw::test
