// The clear-text encoding of STEP (ISO 10303-21), as IFC files use it: a HEADER section and a
// DATA section of instances `#12=IFCWALL('2O2Fr$t4X7Zf8NOew3FLOH',#5,'Wall',$,$,#30,#40,$,$);`.
//
// Why our own: IFC++ (Debian's IFC reader) needs a process-wide UTF-8 locale, takes a truncated
// file for a complete one, and ships without a build configuration; the text itself is simple,
// and the importer needs only the instance graph (docs/importers.md, "IFC").
//
// Values are kept as parsed: numbers, strings (the ISO escapes '' and \X2\...\X0\ decoded to
// UTF-8 for the common cases), enumerations (.T.), references (#12), $ and *, nested lists and
// typed values (IFCLABEL('x'), kept as a one-element list under their type name). Complex
// instances (`#5=(A(...)B(...));`) are kept with the type of their first part and its arguments.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <unordered_map>
#include <vector>

namespace tw {

struct Step21Value {
  enum class Kind : uint8_t { Null, Derived, Integer, Real, String, Enum, Ref, List, Typed };
  Kind kind = Kind::Null;
  double number = 0.0;   // Integer, Real
  uint64_t ref = 0;      // Ref
  std::string text;      // String, Enum (without dots), Typed (the type name)
  std::vector<Step21Value> items;  // List, Typed (its one argument)

  bool isNull() const { return kind == Kind::Null || kind == Kind::Derived; }
  bool isNumber() const { return kind == Kind::Integer || kind == Kind::Real; }
};

struct Step21Instance {
  std::string type;  // upper case, as written
  std::vector<Step21Value> args;
  uint64_t line = 0;  // where it starts, 1-based
};

// Reading instance arguments without checking each one: an argument past the end is $, a
// number or text wrapped in a typed value (IFCLENGTHMEASURE(2.5)) is unwrapped, anything else
// gives the fallback or "".
namespace part21 {
const Step21Value& arg(const Step21Instance* instance, size_t i);
double numberOf(const Step21Value& value, double fallback);
std::string textOf(const Step21Value& value);  // strings and enumerations
}  // namespace part21

class Step21File {
 public:
  // Parses `path`. Throws FormatError naming the file and line for text that is not Part 21
  // (no ISO-10303-21 header, an unterminated string or list, a bad instance, lists nested past
  // kMaxNesting, a repeated instance id) or that ends before END-ISO-10303-21.
  static Step21File read(const std::filesystem::path& path);
  static Step21File parse(std::string_view text, const std::string& file_name);

  static constexpr int kMaxNesting = 64;

  const std::string& fileName() const { return file_; }
  // FILE_SCHEMA's first entry, upper case ("IFC2X3", "IFC4"); empty when absent.
  const std::string& schema() const { return schema_; }
  const std::unordered_map<uint64_t, Step21Instance>& instances() const { return instances_; }
  // The instance #id, or nullptr.
  const Step21Instance* find(uint64_t id) const;
  // The instance a reference value names, or nullptr (not a reference, or dangling).
  const Step21Instance* deref(const Step21Value& value) const;
  // Ids of every instance of `type`, ascending.
  std::vector<uint64_t> idsOfType(const std::string& type) const;

 private:
  std::string file_;
  std::string schema_;
  std::unordered_map<uint64_t, Step21Instance> instances_;
};

}  // namespace tw
