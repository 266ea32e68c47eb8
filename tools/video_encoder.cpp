// The ffmpeg pipe (video_encoder.h).
#include "video_encoder.h"

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <vector>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

namespace tw {
namespace {

std::string formatFps(double fps) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", fps);
  return text;
}

// The codec arguments for the container the name asks for.
std::vector<std::string> codecArguments(const std::filesystem::path& path, int width, int height) {
  const std::string ext = path.extension().string();
  if (ext == ".mp4" || ext == ".mkv") {
    if (width % 2 != 0 || height % 2 != 0)
      throw std::runtime_error(path.string() + ": H.264 video needs an even width and height, not " +
                               std::to_string(width) + "x" + std::to_string(height));
    std::vector<std::string> args{"-c:v", "libx264", "-preset", "veryfast", "-crf", "18", "-pix_fmt", "yuv420p"};
    if (ext == ".mp4") args.insert(args.end(), {"-movflags", "+faststart"});
    return args;
  }
  if (ext == ".avi") return {"-c:v", "mjpeg", "-q:v", "3", "-pix_fmt", "yuvj420p"};
  throw std::runtime_error(path.string() + ": a video is written as .mp4 or .mkv (H.264) or .avi (MJPEG)");
}

// SIGPIPE ignored while a pipe to ffmpeg is open, so a write after ffmpeg stopped fails with EPIPE
// (and is reported) instead of killing this process.
struct SigpipeIgnored {
  SigpipeIgnored() { previous = std::signal(SIGPIPE, SIG_IGN); }
  ~SigpipeIgnored() { std::signal(SIGPIPE, previous); }
  void (*previous)(int) = SIG_DFL;
};

bool executableOnPath(const std::string& name) {
  const char* path = std::getenv("PATH");
  if (!path) return false;
  std::string dirs = path;
  for (size_t start = 0; start <= dirs.size();) {
    const size_t end = std::min(dirs.find(':', start), dirs.size());
    const std::filesystem::path candidate = std::filesystem::path(dirs.substr(start, end - start)) / name;
    if (::access(candidate.c_str(), X_OK) == 0) return true;
    start = end + 1;
  }
  return false;
}

}  // namespace

bool VideoEncoder::ffmpegAvailable() { return executableOnPath("ffmpeg"); }

VideoEncoder::VideoEncoder(const std::filesystem::path& path, int width, int height, double fps)
    : path_(path), width_(width), height_(height) {
  const std::vector<std::string> codec = codecArguments(path, width, height);
  if (!ffmpegAvailable())
    throw std::runtime_error(path.string() +
                             ": ffmpeg was not found on PATH; install Debian's ffmpeg package, or "
                             "write the frames as pictures with --png");
  std::vector<std::string> argv{"ffmpeg", "-hide_banner", "-nostats", "-loglevel", "error", "-xerror", "-y",
                                "-f", "rawvideo", "-pix_fmt", "rgba",
                                "-s", std::to_string(width) + "x" + std::to_string(height),
                                "-framerate", formatFps(fps), "-i", "pipe:0", "-an"};
  argv.insert(argv.end(), codec.begin(), codec.end());
  argv.push_back(path.string());

  char log_name[] = "/tmp/terawalk-ffmpeg-XXXXXX";
  const int log_fd = ::mkstemp(log_name);
  if (log_fd < 0) throw std::runtime_error(path.string() + ": cannot create ffmpeg's log: " + std::strerror(errno));
  log_ = log_name;
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) {
    ::close(log_fd);
    throw std::runtime_error(path.string() + ": cannot open a pipe to ffmpeg: " + std::strerror(errno));
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[0], STDIN_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, log_fd, STDERR_FILENO);
  std::vector<char*> raw;
  for (std::string& a : argv) raw.push_back(a.data());
  raw.push_back(nullptr);
  const int status = ::posix_spawnp(&child_, "ffmpeg", &actions, nullptr, raw.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(fds[0]);
  ::close(log_fd);
  if (status != 0) {
    ::close(fds[1]);
    child_ = -1;
    throw std::runtime_error(path.string() + ": cannot start ffmpeg: " + std::strerror(status));
  }
  pipe_ = fds[1];
}

VideoEncoder::~VideoEncoder() {
  if (pipe_ >= 0) ::close(pipe_);
  if (child_ > 0) {
    int status = 0;
    ::waitpid(child_, &status, 0);
  }
  if (!log_.empty()) {
    std::error_code ignored;
    std::filesystem::remove(log_, ignored);
  }
}

std::string VideoEncoder::failure(const std::string& what) const {
  std::ifstream log(log_);
  std::string line, last;
  while (std::getline(log, line))
    if (!line.empty()) last = line;
  return path_.string() + ": " + what + (last.empty() ? "" : " (ffmpeg: " + last + ")");
}

void VideoEncoder::write(std::span<const uint8_t> rgba) {
  if (rgba.size() != size_t(width_) * size_t(height_) * 4)
    throw std::invalid_argument(path_.string() + ": a frame of the wrong size");
  if (pipe_ < 0) throw std::runtime_error(path_.string() + ": the video is already finished");
  const SigpipeIgnored sigpipe;
  size_t done = 0;
  while (done < rgba.size()) {
    const ssize_t n = ::write(pipe_, rgba.data() + done, rgba.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int error = errno;
      ::close(pipe_);
      pipe_ = -1;
      int status = 0;
      ::waitpid(child_, &status, 0);
      child_ = -1;
      throw std::runtime_error(failure("ffmpeg stopped after " + std::to_string(frames_) + " frames (" +
                                       std::strerror(error) + ")"));
    }
    done += size_t(n);
  }
  ++frames_;
}

uint64_t VideoEncoder::finish() {
  if (pipe_ >= 0) {
    ::close(pipe_);
    pipe_ = -1;
  }
  if (child_ <= 0) throw std::runtime_error(failure("ffmpeg is not running"));
  int status = 0;
  while (::waitpid(child_, &status, 0) < 0 && errno == EINTR) {
  }
  child_ = -1;
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
    throw std::runtime_error(failure(WIFEXITED(status) ? "ffmpeg failed with status " + std::to_string(WEXITSTATUS(status))
                                                       : "ffmpeg was killed"));
  // ffmpeg 5.1 exits with 0 when only writing the file's end failed (a disk that filled then);
  // at -loglevel error, any line it wrote is an error.
  std::error_code ignored;
  if (std::filesystem::file_size(log_, ignored) > 0)
    throw std::runtime_error(failure("ffmpeg could not finish the file"));
  return frames_;
}

}  // namespace tw
