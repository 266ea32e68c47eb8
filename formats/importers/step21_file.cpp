// A Part 21 parser over the whole text: one pass, a line counter for errors, nesting bounded.
// See step21_file.h.
#include "step21_file.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "format_error.h"

namespace tw {
namespace {

void appendUtf8(std::string& out, uint32_t c) {
  if (c < 0x80) {
    out += char(c);
  } else if (c < 0x800) {
    out += char(0xc0 | (c >> 6));
    out += char(0x80 | (c & 0x3f));
  } else {
    out += char(0xe0 | (c >> 12));
    out += char(0x80 | ((c >> 6) & 0x3f));
    out += char(0x80 | (c & 0x3f));
  }
}

class Parser {
 public:
  Parser(std::string_view text, const std::string& file) : s_(text), file_(file) {}

  void parse(std::string& schema, std::unordered_map<uint64_t, Step21Instance>& instances) {
    skipSpace();
    if (keyword() != "ISO-10303-21") fail("not a STEP file: it does not start with ISO-10303-21;");
    expect(';');
    skipSpace();
    if (keyword() != "HEADER") fail("expected HEADER;");
    expect(';');
    for (;;) {
      skipSpace();
      const std::string name = keyword();
      if (name == "ENDSEC") break;
      if (name.empty()) fail("expected a header entry or ENDSEC;");
      skipSpace();
      Step21Value args = value(0);
      if (name == "FILE_SCHEMA" && args.kind == Step21Value::Kind::List && !args.items.empty() &&
          args.items[0].kind == Step21Value::Kind::List && !args.items[0].items.empty()) {
        schema = args.items[0].items[0].text;
        std::transform(schema.begin(), schema.end(), schema.begin(),
                       [](unsigned char c) { return char(std::toupper(c)); });
      }
      expect(';');
    }
    expect(';');
    skipSpace();
    if (keyword() != "DATA") fail("expected DATA;");
    expect(';');
    for (;;) {
      skipSpace();
      if (atEnd()) fail("the file ends inside the DATA section (no ENDSEC;)");
      if (s_[i_] != '#') {
        if (keyword() == "ENDSEC") break;
        fail("expected an instance (#id=...) or ENDSEC;");
      }
      const uint64_t at_line = line_;
      ++i_;
      const uint64_t id = number();
      expect('=');
      skipSpace();
      Step21Instance instance;
      instance.line = at_line;
      if (!atEnd() && s_[i_] == '(') {  // complex instance: keep its first part
        ++i_;
        skipSpace();
        instance.type = keyword();
        if (instance.type.empty()) fail("a complex instance without a type");
        skipSpace();
        instance.args = std::move(value(0).items);
        for (skipSpace(); !atEnd() && s_[i_] != ')'; skipSpace()) {
          keyword();
          skipSpace();
          value(0);
        }
        expect(')');
      } else {
        instance.type = keyword();
        if (instance.type.empty()) fail("instance #" + std::to_string(id) + " has no type");
        skipSpace();
        Step21Value args = value(0);
        if (args.kind != Step21Value::Kind::List)
          fail("instance #" + std::to_string(id) + " has no argument list");
        instance.args = std::move(args.items);
      }
      expect(';');
      if (!instances.emplace(id, std::move(instance)).second)
        fail("instance #" + std::to_string(id) + " is defined twice");
    }
    expect(';');
    skipSpace();
    if (keyword() != "END-ISO-10303-21") fail("expected END-ISO-10303-21; after the DATA section");
  }

 private:
  [[noreturn]] void fail(const std::string& reason) const {
    throw FormatError::atLine(file_, line_, reason);
  }
  bool atEnd() const { return i_ >= s_.size(); }

  void skipSpace() {
    while (!atEnd()) {
      const char c = s_[i_];
      if (c == '\n') {
        ++line_;
        ++i_;
      } else if (c == ' ' || c == '\t' || c == '\r') {
        ++i_;
      } else if (c == '/' && i_ + 1 < s_.size() && s_[i_ + 1] == '*') {
        const uint64_t start = line_;
        i_ += 2;
        while (!atEnd() && !(s_[i_] == '*' && i_ + 1 < s_.size() && s_[i_ + 1] == '/')) {
          if (s_[i_] == '\n') ++line_;
          ++i_;
        }
        if (atEnd()) {
          line_ = start;
          fail("unterminated comment");
        }
        i_ += 2;
      } else {
        break;
      }
    }
  }

  void expect(char c) {
    skipSpace();
    if (atEnd()) fail(std::string("the file ends where '") + c + "' was expected");
    if (s_[i_] != c) fail(std::string("expected '") + c + "', found '" + s_[i_] + "'");
    ++i_;
  }

  std::string keyword() {
    const size_t start = i_;
    while (!atEnd() && (std::isalnum(static_cast<unsigned char>(s_[i_])) || s_[i_] == '_' ||
                        s_[i_] == '-'))
      ++i_;
    std::string k(s_.substr(start, i_ - start));
    std::transform(k.begin(), k.end(), k.begin(),
                   [](unsigned char c) { return char(std::toupper(c)); });
    return k;
  }

  uint64_t number() {
    const size_t start = i_;
    uint64_t n = 0;
    while (!atEnd() && std::isdigit(static_cast<unsigned char>(s_[i_]))) {
      if (n > (UINT64_MAX - 9) / 10) fail("instance id is too large");
      n = n * 10 + uint64_t(s_[i_] - '0');
      ++i_;
    }
    if (i_ == start) fail("expected a number after '#'");
    return n;
  }

  std::string string() {
    const uint64_t start_line = line_;
    ++i_;  // the opening quote
    std::string out;
    for (;;) {
      if (atEnd()) {
        line_ = start_line;
        fail("unterminated string");
      }
      const char c = s_[i_++];
      if (c == '\n') ++line_;
      if (c == '\'') {
        if (!atEnd() && s_[i_] == '\'') {
          out += '\'';
          ++i_;
          continue;
        }
        return out;
      }
      if (c == '\\' && i_ + 2 < s_.size() && s_.substr(i_, 3) == "X2\\") {
        // \X2\ then groups of four hex digits, ended by \X0\.
        i_ += 3;
        while (i_ + 4 <= s_.size() && s_[i_] != '\\') {
          const std::string hex(s_.substr(i_, 4));
          char* end = nullptr;
          const unsigned long code = std::strtoul(hex.c_str(), &end, 16);
          if (end != hex.c_str() + 4) fail("bad \\X2\\ escape in a string");
          appendUtf8(out, uint32_t(code));
          i_ += 4;
        }
        if (i_ + 4 <= s_.size() && s_.substr(i_, 4) == "\\X0\\") i_ += 4;
        continue;
      }
      out += c;
    }
  }

  Step21Value value(int depth) {
    if (depth > Step21File::kMaxNesting) fail("lists nested too deep");
    skipSpace();
    if (atEnd()) fail("the file ends inside a value");
    Step21Value v;
    const char c = s_[i_];
    if (c == '$') {
      ++i_;
      v.kind = Step21Value::Kind::Null;
    } else if (c == '*') {
      ++i_;
      v.kind = Step21Value::Kind::Derived;
    } else if (c == '\'') {
      v.kind = Step21Value::Kind::String;
      v.text = string();
    } else if (c == '"') {  // binary: kept as text
      const size_t end = s_.find('"', i_ + 1);
      if (end == std::string_view::npos) fail("unterminated binary value");
      v.kind = Step21Value::Kind::String;
      v.text = std::string(s_.substr(i_ + 1, end - i_ - 1));
      i_ = end + 1;
    } else if (c == '.') {
      const size_t end = s_.find('.', i_ + 1);
      if (end == std::string_view::npos || end - i_ > 256) fail("unterminated enumeration");
      v.kind = Step21Value::Kind::Enum;
      v.text = std::string(s_.substr(i_ + 1, end - i_ - 1));
      i_ = end + 1;
    } else if (c == '#') {
      ++i_;
      v.kind = Step21Value::Kind::Ref;
      v.ref = number();
    } else if (c == '(') {
      ++i_;
      v.kind = Step21Value::Kind::List;
      skipSpace();
      if (!atEnd() && s_[i_] == ')') {
        ++i_;
        return v;
      }
      for (;;) {
        v.items.push_back(value(depth + 1));
        skipSpace();
        if (atEnd()) fail("the file ends inside a list");
        if (s_[i_] == ',') {
          ++i_;
          continue;
        }
        if (s_[i_] == ')') {
          ++i_;
          break;
        }
        fail(std::string("expected ',' or ')' in a list, found '") + s_[i_] + "'");
      }
    } else if (c == '+' || c == '-' || std::isdigit(static_cast<unsigned char>(c))) {
      const size_t start = i_;
      bool real = false;
      ++i_;
      while (!atEnd()) {
        const char d = s_[i_];
        if (std::isdigit(static_cast<unsigned char>(d))) {
          ++i_;
        } else if (d == '.' || d == 'E' || d == 'e') {
          real = true;
          ++i_;
          if ((d == 'E' || d == 'e') && !atEnd() && (s_[i_] == '+' || s_[i_] == '-')) ++i_;
        } else {
          break;
        }
      }
      const std::string text(s_.substr(start, i_ - start));
      char* end = nullptr;
      v.number = std::strtod(text.c_str(), &end);
      if (end != text.c_str() + text.size()) fail("bad number '" + text + "'");
      v.kind = real ? Step21Value::Kind::Real : Step21Value::Kind::Integer;
    } else if (std::isalpha(static_cast<unsigned char>(c))) {
      v.kind = Step21Value::Kind::Typed;
      v.text = keyword();
      skipSpace();
      Step21Value inner = value(depth + 1);
      if (inner.kind != Step21Value::Kind::List) fail("typed value " + v.text + " without '('");
      v.items = std::move(inner.items);
    } else {
      fail(std::string("unexpected '") + c + "'");
    }
    return v;
  }

  std::string_view s_;
  const std::string& file_;
  size_t i_ = 0;
  uint64_t line_ = 1;
};

}  // namespace

Step21File Step21File::parse(std::string_view text, const std::string& file_name) {
  Step21File f;
  f.file_ = file_name;
  Parser(text, f.file_).parse(f.schema_, f.instances_);
  return f;
}

Step21File Step21File::read(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FormatError(path.string(), "cannot open");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw FormatError(path.string(), "read failed");
  return parse(buffer.str(), path.string());
}

namespace part21 {

const Step21Value& arg(const Step21Instance* instance, size_t i) {
  static const Step21Value null_value;
  return instance && i < instance->args.size() ? instance->args[i] : null_value;
}

double numberOf(const Step21Value& v, double fallback) {
  if (v.isNumber()) return v.number;
  if (v.kind == Step21Value::Kind::Typed && !v.items.empty() && v.items[0].isNumber())
    return v.items[0].number;
  return fallback;
}

std::string textOf(const Step21Value& v) {
  if (v.kind == Step21Value::Kind::String || v.kind == Step21Value::Kind::Enum) return v.text;
  if (v.kind == Step21Value::Kind::Typed && !v.items.empty()) return textOf(v.items[0]);
  return "";
}

}  // namespace part21

const Step21Instance* Step21File::find(uint64_t id) const {
  auto it = instances_.find(id);
  return it == instances_.end() ? nullptr : &it->second;
}

const Step21Instance* Step21File::deref(const Step21Value& value) const {
  return value.kind == Step21Value::Kind::Ref ? find(value.ref) : nullptr;
}

std::vector<uint64_t> Step21File::idsOfType(const std::string& type) const {
  std::vector<uint64_t> ids;
  for (const auto& [id, instance] : instances_)
    if (instance.type == type) ids.push_back(id);
  std::sort(ids.begin(), ids.end());
  return ids;
}

}  // namespace tw
