// Frames to a video file through Debian's ffmpeg, fed raw RGBA frames over a pipe.
//
// Why a pipe to the ffmpeg program and not libavcodec: the program is what users have and trust,
// it picks the container from the file name, and a failure (a full disk, a codec missing) stays
// in its process and comes back as its exit status and its last error line, not as a crash here.
// H.264 in MP4 (or MKV), and MJPEG in AVI, the format ENVIRON wrote, which plays anywhere.
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>

#include <sys/types.h>

namespace tw {

class VideoEncoder {
 public:
  // Starts ffmpeg writing `path` (.mp4, .mkv: H.264; .avi: MJPEG) at `fps` frames a second.
  // Throws std::runtime_error naming the file when the extension is not one of those, or ffmpeg
  // is not on PATH or does not start.
  VideoEncoder(const std::filesystem::path& path, int width, int height, double fps);
  ~VideoEncoder();  // stops ffmpeg if finish() was not called (the file is then incomplete)
  VideoEncoder(const VideoEncoder&) = delete;
  VideoEncoder& operator=(const VideoEncoder&) = delete;

  // One frame, rows top-down, width * height * 4 bytes. Throws std::runtime_error naming the
  // file and ffmpeg's own last error line when ffmpeg has stopped (a full disk).
  void write(std::span<const uint8_t> rgba);
  // Closes the pipe and waits for ffmpeg to finish the file; throws as write() does when it
  // failed. Returns the frames written.
  uint64_t finish();

  static bool ffmpegAvailable();

 private:
  std::string failure(const std::string& what) const;  // the message, with ffmpeg's last line

  std::filesystem::path path_, log_;
  int width_ = 0, height_ = 0;
  int pipe_ = -1;
  pid_t child_ = -1;
  uint64_t frames_ = 0;
};

}  // namespace tw
