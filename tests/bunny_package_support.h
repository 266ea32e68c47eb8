// The Stanford bunny (../shared/data) through the real preprocessor with the default options,
// once per test program: the small real package that the rendering tests draw.
#pragma once

#include <filesystem>

#include "preprocess_driver.h"
#include "test_support.h"

namespace tw::test {

inline const std::filesystem::path& bunnyPackage() {
  static const std::filesystem::path path = [] {
    PreprocessOptions options;
    options.inputs = {sharedDataDir() / "stanford-bunny.obj"};
    options.output = processScratchDir("bunny_package") / "bunny.twk";
    runPreprocess(options);
    return options.output;
  }();
  return path;
}

}  // namespace tw::test
