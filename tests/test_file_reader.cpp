// FileReader: exact reads, bounded lines, and errors that carry the file and offset.
#include <gtest/gtest.h>

#include <string>

#include "file_reader.h"
#include "test_support.h"

namespace tw {
namespace {

TEST(FileReader, ReadsValuesAcrossBufferBoundaries) {
  auto path = test::scratchDir() / "values.bin";
  std::string bytes;
  for (uint32_t i = 0; i < 10000; ++i) bytes.append(reinterpret_cast<const char*>(&i), 4);
  test::writeFile(path, bytes);
  FileReader reader(path, 4096);  // small buffer: many refills
  EXPECT_EQ(reader.size(), 40000u);
  for (uint32_t i = 0; i < 10000; ++i) ASSERT_EQ(reader.readValue<uint32_t>(), i);
  EXPECT_TRUE(reader.atEnd());
}

TEST(FileReader, LargeReadBypassesBufferAndSeekWorks) {
  auto path = test::scratchDir() / "big.bin";
  std::string bytes(100000, '\0');
  for (size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<char>(i * 7);
  test::writeFile(path, bytes);
  FileReader reader(path, 4096);
  std::string out(50000, '\0');
  reader.skip(10);
  reader.read(out.data(), out.size());
  EXPECT_EQ(out, bytes.substr(10, 50000));
  reader.seek(3);
  EXPECT_EQ(reader.readValue<char>(), bytes[3]);
  reader.seek(99999);
  EXPECT_EQ(reader.readValue<char>(), bytes[99999]);
}

TEST(FileReader, ReadPastEndNamesFileAndOffset) {
  auto path = test::scratchDir() / "short.bin";
  test::writeFile(path, "abcdef");
  FileReader reader(path);
  reader.skip(4);
  try {
    reader.readValue<uint32_t>();
    FAIL() << "expected FormatError";
  } catch (const FormatError& e) {
    EXPECT_EQ(e.where(), FormatError::Where::Byte);
    EXPECT_EQ(e.position(), 4u);
    EXPECT_NE(std::string(e.what()).find("short.bin: byte 4: unexpected end of file"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(reader.skip(100), FormatError);
  EXPECT_THROW(reader.seek(7), FormatError);
}

TEST(FileReader, MissingFileIsAFormatError) {
  try {
    FileReader reader(test::scratchDir() / "absent.ply");
    FAIL();
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("absent.ply: cannot open"), std::string::npos);
  }
  EXPECT_THROW(FileReader reader(test::scratchDir()), FormatError);
}

// The lines a FileReader gives for `text`.
std::vector<std::string> linesOf(const std::string& text) {
  auto path = test::scratchDir() / "lines.txt";
  test::writeFile(path, text);
  FileReader reader(path, 4096);
  std::string_view line;
  std::vector<std::string> lines;
  while (reader.readLine(line)) lines.emplace_back(line);
  return lines;
}

TEST(FileReader, ReadsLinesWithAnyEnding) {
  EXPECT_EQ(linesOf("one\r\ntwo\n\nfour"), (std::vector<std::string>{"one", "two", "", "four"}));
  // Lone CRs too, mixed with the others.
  EXPECT_EQ(linesOf("a\rb\r\nc\n\r\rd\r"), (std::vector<std::string>{"a", "b", "c", "", "", "d"}));
}

TEST(FileReader, ManyLinesAcrossRefills) {
  auto path = test::scratchDir() / "many.txt";
  std::string text;
  for (int i = 0; i < 5000; ++i) text += "line " + std::to_string(i) + "\n";
  test::writeFile(path, text);
  FileReader reader(path, 4096);
  std::string_view line;
  int n = 0;
  while (reader.readLine(line)) {
    ASSERT_EQ(line, "line " + std::to_string(n));
    ++n;
  }
  EXPECT_EQ(n, 5000);
}

// Lone CRs (classic Mac OS files: an OBJ written so once read as one empty line), CRLF and LF
// give the same lines and line numbers, also where a refill falls between a CR and its LF.
TEST(FileReader, CrCrlfAndLfLinesReadAlikeAcrossRefills) {
  for (const std::string& end : std::vector<std::string>{"\r", "\r\n", "\n"}) {
    auto path = test::scratchDir() / "ends.txt";
    std::string text;
    for (int i = 0; i < 5000; ++i) text += "v " + std::to_string(i) + std::string(size_t(i % 7), ' ') + end;
    text += "last";
    test::writeFile(path, text);
    FileReader reader(path, 4096);
    std::string_view line;
    int n = 0;
    while (reader.readLine(line)) {
      if (n < 5000) ASSERT_EQ(line, "v " + std::to_string(n) + std::string(size_t(n % 7), ' ')) << n;
      else EXPECT_EQ(line, "last");
      ++n;
    }
    EXPECT_EQ(n, 5001) << "ends of " << end.size() << " bytes";
    EXPECT_EQ(reader.line(), 5001u);
  }
}

TEST(FileReader, OverlongLineIsRejectedNotBuffered) {
  auto path = test::scratchDir() / "long.txt";
  test::writeFile(path, "ok\n" + std::string(10000, 'x') + "\n");
  FileReader reader(path, 4096);
  std::string_view line;
  ASSERT_TRUE(reader.readLine(line));
  EXPECT_THROW(reader.readLine(line), FormatError);
}

}  // namespace
}  // namespace tw
