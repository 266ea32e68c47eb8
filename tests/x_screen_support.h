// A real X screen for window tests: an Xvfb server whose framebuffer is a file (-fbdir), read back
// as the picture a person at that screen would see, and programs started on that display in the
// background. Tests of the viewer assert on this picture, not on the renderer's own buffer.
//
// The screen file is X's XWD dump format (the one `xwd -root` writes): a big-endian header, the
// colour map, then the pixels, row by row.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace tw::test {

struct ScreenImage {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> rgba;  // top row first
  const uint8_t* at(int x, int y) const { return &rgba[(size_t(y) * width + x) * 4]; }
};

// Parses an XWD dump of a 24- or 32-bit TrueColor screen; nullopt for a file that is not one
// (or is still being written).
inline std::optional<ScreenImage> readXwd(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto field = [&](size_t i) -> uint32_t {
    const uint8_t* p = bytes.data() + 4 * i;
    return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | p[3];
  };
  if (bytes.size() < 100) return std::nullopt;
  const uint32_t header_size = field(0), version = field(1), width = field(4), height = field(5);
  const uint32_t byte_order = field(7), bits_per_pixel = field(11), bytes_per_line = field(12);
  const uint32_t red_mask = field(14), green_mask = field(15), blue_mask = field(16);
  const uint32_t ncolors = field(19);
  if (version != 7 || bits_per_pixel != 32 || width == 0 || height == 0 || width > 16384 ||
      height > 16384 || bytes_per_line < 4 * width)
    return std::nullopt;
  const uint64_t pixels_at = uint64_t(header_size) + uint64_t(ncolors) * 12;
  if (pixels_at + uint64_t(bytes_per_line) * height > bytes.size()) return std::nullopt;
  auto channel = [](uint32_t pixel, uint32_t mask) -> uint8_t {
    if (mask == 0) return 0;
    int shift = 0;
    while (!((mask >> shift) & 1u)) ++shift;
    return uint8_t(((pixel & mask) >> shift) & 0xffu);
  };
  ScreenImage image;
  image.width = int(width);
  image.height = int(height);
  image.rgba.resize(size_t(width) * height * 4);
  for (uint32_t y = 0; y < height; ++y)
    for (uint32_t x = 0; x < width; ++x) {
      const uint8_t* p = bytes.data() + pixels_at + uint64_t(y) * bytes_per_line + 4 * x;
      const uint32_t pixel = byte_order == 0
                                 ? uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 |
                                       uint32_t(p[3]) << 24
                                 : uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 |
                                       uint32_t(p[2]) << 8 | p[3];
      uint8_t* out = &image.rgba[(size_t(y) * width + x) * 4];
      out[0] = channel(pixel, red_mask);
      out[1] = channel(pixel, green_mask);
      out[2] = channel(pixel, blue_mask);
      out[3] = 255;
    }
  return image;
}

// A child process started with posix_spawnp; killed (SIGTERM) and reaped when destroyed.
class BackgroundProcess {
 public:
  BackgroundProcess(const std::vector<std::string>& argv, const std::vector<std::string>& env_add,
                    const std::filesystem::path& output) {
    std::vector<std::string> env_strings(env_add);
    for (char** e = environ; *e; ++e) env_strings.push_back(*e);
    std::vector<char*> args, env;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    for (const std::string& e : env_strings) env.push_back(const_cast<char*>(e.c_str()));
    env.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, output.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                     0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    const int rc = posix_spawnp(&pid_, args[0], &actions, nullptr, args.data(), env.data());
    posix_spawn_file_actions_destroy(&actions);
    if (rc != 0) throw std::runtime_error("cannot start " + argv[0] + ": " + std::strerror(rc));
  }
  ~BackgroundProcess() {
    if (pid_ <= 0) return;
    if (!exited_) kill(pid_, SIGTERM);
    wait();
  }
  BackgroundProcess(const BackgroundProcess&) = delete;
  BackgroundProcess& operator=(const BackgroundProcess&) = delete;

  // Whether it has exited (without waiting); its exit code is then exitCode().
  bool running() {
    if (exited_) return false;
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) == pid_) {
      exited_ = true;
      exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    }
    return !exited_;
  }
  int wait() {
    if (!exited_) {
      int status = 0;
      waitpid(pid_, &status, 0);
      exited_ = true;
      exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    }
    return exit_code_;
  }
  int exitCode() const { return exit_code_; }

 private:
  pid_t pid_ = -1;
  bool exited_ = false;
  int exit_code_ = -1;
};

// An Xvfb server on a free display, its screen 0 in `dir`/Xvfb_screen0.
class XvfbScreen {
 public:
  XvfbScreen(const std::filesystem::path& dir, int width, int height) : dir_(dir) {
    std::filesystem::create_directories(dir);
    for (int display = 90; display < 140 && !server_; ++display) {
      if (std::filesystem::exists("/tmp/.X11-unix/X" + std::to_string(display)) ||
          std::filesystem::exists("/tmp/.X" + std::to_string(display) + "-lock"))
        continue;
      display_ = ":" + std::to_string(display);
      server_.emplace(std::vector<std::string>{"Xvfb", display_, "-screen", "0",
                                               std::to_string(width) + "x" +
                                                   std::to_string(height) + "x24",
                                               "-fbdir", dir.string(), "-nolisten", "tcp",
                                               // The pointer is drawn into the framebuffer, and
                                               // not always the same: two captures of one still
                                               // frame differed by its 72 pixels.
                                               "-nocursor"},
                      std::vector<std::string>{}, dir / "xvfb.log");
      // Ready once the screen file holds a whole picture; a taken display makes Xvfb exit.
      for (int i = 0; i < 100 && server_->running() && !capture(); ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      if (!server_->running() || !capture()) server_.reset();
    }
    if (!server_) throw std::runtime_error("cannot start Xvfb (see " + (dir / "xvfb.log").string() + ")");
  }

  const std::string& display() const { return display_; }
  std::optional<ScreenImage> capture() const { return readXwd(dir_ / "Xvfb_screen0"); }

 private:
  std::filesystem::path dir_;
  std::string display_;
  std::optional<BackgroundProcess> server_;
};

}  // namespace tw::test
