// Shared helpers for the test programs: scratch files, a sink that keeps everything, and the
// truncate-and-corrupt harness every reader test runs its fixtures through.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "format_error.h"
#include "scene_sink.h"

namespace tw::test {

inline std::filesystem::path dataDir() { return TW_DATA_DIR; }
inline std::filesystem::path sharedDataDir() { return TW_SHARED_DATA_DIR; }

// Where scratch files go: memory-backed /dev/shm when there is one, because the damage tests
// write thousands of small files and a busy disk made them slow; the system temp dir otherwise.
inline std::filesystem::path scratchRoot() {
  std::error_code ec;
  if (std::filesystem::is_directory("/dev/shm", ec)) return "/dev/shm";
  return std::filesystem::temp_directory_path();
}

// A fresh, empty directory for the running test, left behind for inspection after a failure.
inline std::filesystem::path scratchDir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = std::string(info->test_suite_name()) + "." + info->name();
  for (char& c : name)
    if (c == '/') c = '_';
  auto dir = scratchRoot() / "terawalk-tests" / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// What a command printed (stdout and stderr together) and its exit code (-1 if it did not exit).
struct CommandResult {
  int exit_code = -1;
  std::string output;
};

// Runs `command` through the shell and collects its output.
inline CommandResult runShell(const std::string& command) {
  CommandResult result;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return result;
  char buf[4096];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, pipe)) > 0) result.output.append(buf, n);
  const int status = pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

#ifdef TW_TERAWALK_EXE
// Runs the `terawalk` executable this build made with `args`.
inline CommandResult runTerawalk(const std::string& args) {
  return runShell(std::string(TW_TERAWALK_EXE) + " " + args);
}
#endif

// A fresh directory shared by every test of this process, for fixtures built once per test program
// (a package several tests render), removed when the process exits. Named by the process id,
// because ctest runs the tests of one program as parallel processes, and kept apart from
// scratchDir(), which each test clears.
inline std::filesystem::path processScratchDir(const std::string& name) {
  struct Dir {
    std::filesystem::path path;
    explicit Dir(std::filesystem::path p) : path(std::move(p)) {
      std::filesystem::remove_all(path);
      std::filesystem::create_directories(path);
    }
    ~Dir() {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
    }
  };
  static std::map<std::string, std::unique_ptr<Dir>> dirs;
  std::unique_ptr<Dir>& dir = dirs[name];
  if (!dir)
    dir = std::make_unique<Dir>(scratchRoot() / "terawalk-tests" /
                                (name + "-" + std::to_string(::getpid())));
  return dir->path;
}

// Appends the closed box [lo, hi] to `mesh`: 8 vertices, 12 outward counter-clockwise triangles.
inline void appendBox(TriangleMesh& mesh, const glm::vec3& lo, const glm::vec3& hi) {
  const auto base = static_cast<uint32_t>(mesh.positions.size());
  for (int i = 0; i < 8; ++i)
    mesh.positions.push_back({(i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z});
  static constexpr uint32_t kFaces[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6},
                                             {0, 1, 4}, {1, 5, 4}, {2, 6, 3}, {3, 6, 7},
                                             {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  for (const auto& f : kFaces)
    for (uint32_t v : f) mesh.indices.push_back(base + v);
}

// A closed box of half extents `half` around the origin, each face an n x n grid of quads
// (outward, counter-clockwise), vertices shared within a face only.
inline TriangleMesh subdividedBox(const glm::vec3& half, int n) {
  TriangleMesh mesh;
  for (int face = 0; face < 6; ++face) {
    const int axis = face / 2;
    const float side = (face % 2) ? 1.0f : -1.0f;
    const auto base = static_cast<uint32_t>(mesh.positions.size());
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j <= n; ++j) {
        glm::vec3 p(0.0f);
        p[axis] = side;
        p[(axis + 1) % 3] = -1.0f + 2.0f * i / n;
        p[(axis + 2) % 3] = -1.0f + 2.0f * j / n;
        mesh.positions.push_back(p * half);
      }
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const uint32_t a = base + i * (n + 1) + j, b = a + 1, c = a + (n + 1), d = c + 1;
        if (side > 0) mesh.indices.insert(mesh.indices.end(), {a, c, d, a, d, b});
        else mesh.indices.insert(mesh.indices.end(), {a, b, d, a, d, c});
      }
  }
  return mesh;
}

inline void writeFile(const std::filesystem::path& path, const std::string& bytes) {
  // Replace rather than truncate: ext4 flushes a file truncated and rewritten in place when it is
  // closed, which made the damage runs (thousands of rewrites) I/O-bound: 45x slower under load.
  std::error_code ec;
  std::filesystem::remove(path, ec);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

inline std::string readFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Keeps every layer and object part it receives.
class CollectingSink : public SceneSink {
 public:
  void onLayer(uint32_t index, const Layer& layer) override {
    if (layers.size() <= index) layers.resize(index + 1);
    layers[index] = layer;
  }
  void onObject(const SceneObject& object) override { objects.push_back(object); }

  uint64_t triangles() const {
    uint64_t n = 0;
    for (const auto& o : objects)
      if (const auto* m = std::get_if<TriangleMesh>(&o.geometry)) n += m->triangleCount();
    return n;
  }

  std::vector<Layer> layers;
  std::vector<SceneObject> objects;
};

// Discards everything: for damaged-input runs, where only "no crash, clear error" matters.
class NullSink : public SceneSink {
 public:
  void onLayer(uint32_t, const Layer&) override {}
  void onObject(const SceneObject&) override {}
};

using ReadFunction = std::function<void(const std::filesystem::path&, SceneSink&)>;

// Feeds damaged copies of `original` (file name `file_name` in a scratch directory) to `read`:
// every truncation for files up to 4 KiB and about 300 spread over the file otherwise, then
// `corruptions` copies with a few random bytes overwritten (fixed seed). Each read must either
// succeed or throw FormatError whose message names the file; any other outcome fails the test.
// Returns the number of damaged copies that were rejected with a FormatError.
inline int expectRobustToDamage(const std::string& original, const std::string& file_name,
                                const ReadFunction& read, int corruptions = 300) {
  auto path = scratchDir() / file_name;
  int rejected = 0;
  auto attempt = [&](const std::string& bytes, const std::string& what) {
    writeFile(path, bytes);
    NullSink sink;
    try {
      read(path, sink);
    } catch (const FormatError& e) {
      ++rejected;
      EXPECT_NE(std::string(e.what()).find(file_name), std::string::npos)
          << what << ": error does not name the file: " << e.what();
    } catch (const std::exception& e) {
      ADD_FAILURE() << what << ": unexpected exception type: " << e.what();
    }
  };
  size_t step = original.size() <= 4096 ? 1 : original.size() / 300;
  for (size_t cut = 0; cut < original.size(); cut += step)
    attempt(original.substr(0, cut), "truncated to " + std::to_string(cut) + " bytes");
  std::mt19937 rng(12345);
  for (int i = 0; i < corruptions && !original.empty(); ++i) {
    std::string bytes = original;
    int hits = 1 + static_cast<int>(rng() % 4);
    for (int h = 0; h < hits; ++h) {
      size_t at = rng() % bytes.size();
      bytes[at] = static_cast<char>(rng() & 0xff);
    }
    attempt(bytes, "corruption " + std::to_string(i));
  }
  return rejected;
}

}  // namespace tw::test
