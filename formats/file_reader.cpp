// FileReader: one large buffer over stdio, with every overrun turned into a FormatError.
#include "file_reader.h"

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace tw {

FileReader::FileReader(const std::filesystem::path& path, size_t buffer_bytes)
    : name_(path.string()) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw FormatError(name_, "is a directory");
  file_ = std::fopen(name_.c_str(), "rb");
  if (!file_) throw FormatError(name_, std::string("cannot open: ") + std::strerror(errno));
  if (std::fseek(file_, 0, SEEK_END) != 0) {
    std::fclose(file_);
    throw FormatError(name_, "cannot seek");
  }
  long end = std::ftell(file_);
  std::fseek(file_, 0, SEEK_SET);
  size_ = end < 0 ? 0 : static_cast<uint64_t>(end);
  std::setvbuf(file_, nullptr, _IONBF, 0);  // we buffer ourselves
  // Never more buffer than the file needs: damage tests and small inputs open thousands of files.
  buffer_.resize(std::max<uint64_t>(4096, std::min<uint64_t>(buffer_bytes, size_ + 1)));
}

FileReader::~FileReader() {
  if (file_) std::fclose(file_);
}

void FileReader::refill() {
  // Move the unconsumed tail to the front, then fill the rest.
  size_t tail = end_ - begin_;
  if (tail && begin_) std::memmove(buffer_.data(), buffer_.data() + begin_, tail);
  begin_ = 0;
  end_ = tail;
  size_t got = std::fread(buffer_.data() + end_, 1, buffer_.size() - end_, file_);
  if (got == 0 && std::ferror(file_)) fail("read error");
  end_ += got;
}

void FileReader::read(void* out, size_t bytes) {
  if (bytes > remaining()) fail("unexpected end of file (needed " + std::to_string(bytes) +
                                " bytes, " + std::to_string(remaining()) + " left)");
  char* dst = static_cast<char*>(out);
  while (bytes > 0) {
    if (begin_ == end_) {
      // Large reads bypass the buffer.
      if (bytes >= buffer_.size()) {
        size_t got = std::fread(dst, 1, bytes, file_);
        offset_ += got;
        if (got != bytes) fail("read error");
        return;
      }
      refill();
      if (begin_ == end_) fail("unexpected end of file");
    }
    size_t n = std::min(bytes, end_ - begin_);
    std::memcpy(dst, buffer_.data() + begin_, n);
    begin_ += n;
    offset_ += n;
    dst += n;
    bytes -= n;
  }
}

void FileReader::skip(uint64_t bytes) {
  if (bytes > remaining()) fail("unexpected end of file (skipping " + std::to_string(bytes) +
                                " bytes, " + std::to_string(remaining()) + " left)");
  seek(offset_ + bytes);
}

void FileReader::seek(uint64_t target) {
  if (target > size_) fail("offset " + std::to_string(target) + " is past the end of the file");
  // Stay inside the buffer when we can.
  uint64_t buffer_start = offset_ - begin_;
  if (target >= buffer_start && target <= buffer_start + end_) {
    begin_ = static_cast<size_t>(target - buffer_start);
    offset_ = target;
    return;
  }
  if (std::fseek(file_, static_cast<long>(target), SEEK_SET) != 0) fail("cannot seek");
  begin_ = end_ = 0;
  offset_ = target;
}

std::string_view FileReader::peek(size_t max_bytes) {
  if (end_ - begin_ < max_bytes && end_ - begin_ < buffer_.size() && !atEnd()) refill();
  size_t n = std::min(max_bytes, end_ - begin_);
  return std::string_view(buffer_.data() + begin_, n);
}

void FileReader::consume(size_t bytes) {
  if (bytes > end_ - begin_) fail("internal: consumed more than peeked");
  begin_ += bytes;
  offset_ += bytes;
}

// Where the next line ends in the buffered bytes: "\n", "\r\n" or a lone "\r" (files written
// with classic Mac OS line ends). False when the buffer holds no complete line end yet.
bool FileReader::findLineEnd(size_t& length, size_t& consumed) const {
  const char* start = buffer_.data() + begin_;
  const size_t avail = end_ - begin_;
  const bool file_end_buffered = offset_ + avail >= size_;
  const char* nl = static_cast<const char*>(std::memchr(start, '\n', avail));
  const size_t before_nl = nl ? size_t(nl - start) : avail;
  const char* cr = static_cast<const char*>(std::memchr(start, '\r', before_nl));
  if (cr) {
    const size_t at = size_t(cr - start);
    if (nl && at + 1 == before_nl) {  // "\r\n"
      length = at;
      consumed = at + 2;
      return true;
    }
    if (at + 1 < avail || file_end_buffered) {  // a lone "\r" (the next byte is not "\n")
      length = at;
      consumed = at + 1;
      return true;
    }
    return false;  // "\r" as the last buffered byte: its "\n" may follow
  }
  if (nl) {
    length = before_nl;
    consumed = before_nl + 1;
    return true;
  }
  if (file_end_buffered) {  // the last line, without a line end
    length = avail;
    consumed = avail;
    return true;
  }
  return false;
}

bool FileReader::readLine(std::string_view& line) {
  if (atEnd()) return false;
  size_t length = 0, consumed = 0;
  if (!findLineEnd(length, consumed)) {
    refill();
    if (!findLineEnd(length, consumed))
      fail("line " + std::to_string(line_ + 1) + " is longer than " +
           std::to_string(buffer_.size()) + " bytes");
  }
  line = std::string_view(buffer_.data() + begin_, length);
  begin_ += consumed;
  offset_ += consumed;
  ++line_;
  return true;
}

void FileReader::fail(const std::string& reason) const { failAt(offset_, reason); }

void FileReader::failAt(uint64_t offset, const std::string& reason) const {
  throw FormatError::atByte(name_, offset, reason);
}

void FileReader::failAtLine(const std::string& reason) const {
  throw FormatError::atLine(name_, line_, reason);
}

}  // namespace tw
