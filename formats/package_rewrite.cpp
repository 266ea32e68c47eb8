// replacePackageSection: a package re-laid out with one section's bytes replaced (package_rewrite.h).
//
// The new file keeps the writer's layout rules (package_writer.cpp): header, table, then the
// sections in table order, each at a multiple of kSectionAlignment with zero padding, page data
// last. Every other section is copied from the original as stored (compressed tables stay
// compressed) in fixed-size chunks, so rewriting a
// package of many GB costs one sequential copy and a few MiB of memory.
#include "package_rewrite.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "format_error.h"
#include "package_view.h"

namespace tw {
namespace {

using namespace pkg;

constexpr size_t kCopyChunkBytes = size_t{4} << 20;

[[noreturn]] void ioFail(const std::filesystem::path& path, const std::string& what) {
  throw std::runtime_error(path.string() + ": " + what + ": " + std::strerror(errno));
}

// The temporary output: removed unless committed, so a failure leaves only the original.
class RewriteFile {
 public:
  RewriteFile(std::filesystem::path final_path)
      : final_(std::move(final_path)), temp_(final_.string() + ".tmp") {
    file_ = std::fopen(temp_.c_str(), "wb");
    if (!file_) ioFail(temp_, "cannot create");
  }
  ~RewriteFile() {
    if (file_) std::fclose(file_);
    if (!committed_) {
      std::error_code ec;
      std::filesystem::remove(temp_, ec);
    }
  }
  RewriteFile(const RewriteFile&) = delete;
  RewriteFile& operator=(const RewriteFile&) = delete;

  const std::filesystem::path& tempPath() const { return temp_; }
  uint64_t written() const { return written_; }

  void write(const void* data, uint64_t bytes) {
    if (bytes > 0 && std::fwrite(data, 1, bytes, file_) != bytes) ioFail(temp_, "cannot write");
    written_ += bytes;
  }
  void padTo(uint64_t offset) {
    static const uint8_t kZeros[kSectionAlignment] = {};
    while (written_ < offset) write(kZeros, std::min<uint64_t>(offset - written_, sizeof(kZeros)));
  }
  // Appends `bytes` bytes of `in` starting at `offset`, a chunk at a time.
  void copyFrom(std::FILE* in, const std::filesystem::path& in_path, uint64_t offset,
                uint64_t bytes, std::vector<uint8_t>& chunk) {
    if (bytes == 0) return;
    if (::fseeko(in, static_cast<off_t>(offset), SEEK_SET) != 0) ioFail(in_path, "cannot seek");
    while (bytes > 0) {
      const size_t n = static_cast<size_t>(std::min<uint64_t>(bytes, chunk.size()));
      if (std::fread(chunk.data(), 1, n, in) != n) ioFail(in_path, "short read");
      write(chunk.data(), n);
      bytes -= n;
    }
  }
  void close() {
    bool ok = std::fflush(file_) == 0 && ::fsync(::fileno(file_)) == 0;
    ok = std::fclose(file_) == 0 && ok;
    file_ = nullptr;
    if (!ok) ioFail(temp_, "cannot finish writing");
  }
  void commit() {
    std::error_code ec;
    std::filesystem::rename(temp_, final_, ec);
    if (ec)
      throw std::runtime_error(final_.string() + ": cannot rename " + temp_.string() + ": " +
                               ec.message());
    committed_ = true;
  }

 private:
  std::filesystem::path final_;
  std::filesystem::path temp_;
  std::FILE* file_ = nullptr;
  uint64_t written_ = 0;
  bool committed_ = false;
};

// Order in the new file: the known sections in table order with page data last, then any extra
// sections a newer minor version appended (kept, never interpreted), so the resident tables stay
// one contiguous prefix.
std::vector<uint32_t> fileOrder(uint32_t section_count) {
  std::vector<uint32_t> order;
  const uint32_t page_data = static_cast<uint32_t>(SectionType::PageData);
  for (uint32_t i = 0; i < section_count; ++i)
    if (i != page_data) order.push_back(i);
  order.push_back(page_data);
  return order;
}

}  // namespace

void replacePackageSection(const std::filesystem::path& package, pkg::SectionType type,
                           std::span<const uint8_t> bytes) {
  const uint32_t index = static_cast<uint32_t>(type);
  if (index >= kSectionCount)
    throw std::invalid_argument("replacePackageSection: unknown section type " +
                                std::to_string(index));
  const uint32_t record_bytes = kSectionRecordBytes[index];
  if (bytes.size() % record_bytes != 0)
    throw std::invalid_argument(std::string("replacePackageSection: ") + kSectionNames[index] +
                                " section of " + std::to_string(bytes.size()) +
                                " bytes is not a whole number of " +
                                std::to_string(record_bytes) + "-byte records");

  // New header and table, from the validated original.
  PackageHeader header{};
  std::vector<SectionEntry> old_table, table;
  {
    const PackageView view = PackageView::open(package, PackageView::Verify::Headers);
    header = view.header();
    for (uint32_t i = 0; i < header.section_count; ++i)
      old_table.push_back(view.section(static_cast<SectionType>(i)));
  }
  table = old_table;
  SectionEntry& replaced = table[index];
  replaced.bytes = bytes.size();
  replaced.count = bytes.size() / record_bytes;
  replaced.checksum = packageSectionChecksum(bytes);
  replaced.stored_bytes = 0;  // written as it is
  const std::vector<uint32_t> order = fileOrder(header.section_count);
  uint64_t cursor = sizeof(PackageHeader) + table.size() * sizeof(SectionEntry);
  for (uint32_t i : order) {
    table[i].offset = alignUp(cursor, kSectionAlignment);
    cursor = table[i].offset + storedBytes(table[i]);
  }
  header.file_bytes = cursor;
  // Filling a section is a compatible addition: the file is now of this writer's minor version.
  header.minor_version = std::max(header.minor_version, kMinorVersion);
  header.header_checksum = packageHeaderChecksum(header, table);

  // Copy.
  RewriteFile out(package);
  std::FILE* in = std::fopen(package.c_str(), "rb");
  if (!in) ioFail(package, "cannot open");
  try {
    std::vector<uint8_t> chunk(kCopyChunkBytes);
    out.write(&header, sizeof(header));
    out.write(table.data(), table.size() * sizeof(SectionEntry));
    for (uint32_t i : order) {
      out.padTo(table[i].offset);
      if (i == index)
        out.write(bytes.data(), bytes.size());
      else
        out.copyFrom(in, package, old_table[i].offset, storedBytes(old_table[i]), chunk);
    }
    if (out.written() != header.file_bytes)
      throw std::logic_error("replacePackageSection: wrote " + std::to_string(out.written()) +
                             " bytes, laid out " + std::to_string(header.file_bytes));
  } catch (...) {
    std::fclose(in);
    throw;
  }
  std::fclose(in);
  out.close();

  // As writePackage does: never publish a package the view rejects (a bad new section).
  try {
    PackageView::open(out.tempPath(), PackageView::Verify::Headers);
  } catch (const FormatError& e) {
    throw std::invalid_argument(std::string("replacePackageSection: the new ") +
                                kSectionNames[index] +
                                " section makes the package invalid: " + e.reason());
  }
  out.commit();
}

}  // namespace tw
