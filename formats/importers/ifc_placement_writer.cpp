// Moved products written back into a copy of an IFC file (ifc_placement_writer.h).
#include "ifc_placement_writer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include "format_error.h"
#include "ifc_frames.h"
#include "step21_file.h"

namespace tw {
namespace {

std::string number(double v) {
  char text[40];
  std::snprintf(text, sizeof text, "%.17g", v);
  std::string s = text;
  if (s.find_first_of(".eEn") == std::string::npos) s += ".";  // a REAL, as Part 21 writes it
  return s;
}

// Where instance #id's text starts ("#id=") and ends (its ';'), found from its line.
std::pair<size_t, size_t> instanceSpan(const std::string& text, uint64_t id, uint64_t line,
                                       const std::string& name) {
  size_t at = 0;
  for (uint64_t l = 1; l < line && at != std::string::npos; ++l) at = text.find('\n', at) + 1;
  const std::string head = "#" + std::to_string(id);
  size_t start = text.find(head, at == std::string::npos ? 0 : at);
  while (start != std::string::npos) {
    size_t after = start + head.size();
    while (after < text.size() && (text[after] == ' ' || text[after] == '\t')) ++after;
    if (after < text.size() && text[after] == '=') break;
    start = text.find(head, start + 1);
  }
  if (start == std::string::npos) throw FormatError::atLine(name, line, "#" + std::to_string(id) + " not found");
  bool quoted = false;
  for (size_t i = start; i < text.size(); ++i) {
    if (text[i] == '\'') quoted = !quoted;  // '' inside a string toggles twice
    else if (!quoted && text[i] == ';') return {start, i};
  }
  throw FormatError::atLine(name, line, "#" + std::to_string(id) + " has no end");
}

// The span of argument `index` (0-based, top level) inside the instance text [start, end).
std::pair<size_t, size_t> argumentSpan(const std::string& text, size_t start, size_t end, size_t index) {
  const size_t open = text.find('(', start);
  int depth = 0;
  bool quoted = false;
  size_t arg = 0, arg_start = open + 1;
  for (size_t i = open; i < end; ++i) {
    const char c = text[i];
    if (c == '\'') quoted = !quoted;
    if (quoted) continue;
    if (c == '(') ++depth;
    else if (c == ')') {
      if (--depth == 0) return arg == index ? std::make_pair(arg_start, i) : std::make_pair(end, end);
    } else if (c == ',' && depth == 1) {
      if (arg == index) return {arg_start, i};
      ++arg;
      arg_start = i + 1;
    }
  }
  return {end, end};
}

}  // namespace

IfcMoveReport writeMovedIfc(const std::filesystem::path& in, const std::filesystem::path& out,
                            const std::vector<std::pair<std::string, glm::dmat4>>& moves) {
  const std::string name = in.string();
  std::string text;
  {
    std::ifstream f(in, std::ios::binary);
    if (!f) throw FormatError(name, "cannot be read");
    std::stringstream bytes;
    bytes << f.rdbuf();
    text = bytes.str();
  }
  const Step21File file = Step21File::parse(text, name);
  const IfcFrames frames(file);

  // Products by GlobalId: instances whose first argument is a GlobalId and sixth a placement.
  std::map<std::string, uint64_t> product_of;
  uint64_t largest = 0;
  for (const auto& [id, instance] : file.instances()) {
    largest = std::max(largest, id);
    if (instance.args.size() > 6 && instance.args[0].kind == Step21Value::Kind::String &&
        instance.args[5].kind == Step21Value::Kind::Ref)
      product_of.emplace(instance.args[0].text, id);
  }

  IfcMoveReport report;
  std::string added;
  std::vector<std::pair<std::pair<size_t, size_t>, std::string>> edits;  // spans to replace
  uint64_t next = largest + 1;
  for (const auto& [guid, move] : moves) {
    const auto it = product_of.find(guid);
    if (it == product_of.end()) {
      report.missing.push_back(guid);
      continue;
    }
    const Step21Instance& product = *file.find(it->second);
    const glm::dmat4 world = move * frames.placement(file.deref(product.args[5]));
    const glm::dmat3 r(world);
    const glm::dmat3 rtr = glm::transpose(r) * r;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        if (std::abs(rtr[a][b] - (a == b ? 1.0 : 0.0)) > 1e-9)
          throw std::invalid_argument(name + ": #" + std::to_string(it->second) + " (" + guid +
                                      "): the move scales it, which an IFC placement cannot say");
    const double unit = frames.metresPerUnit();
    const glm::dvec3 o = glm::dvec3(world[3]) / unit, z = glm::dvec3(world[2]), x = glm::dvec3(world[0]);
    const uint64_t p = next++, dz = next++, dx = next++, axis = next++, local = next++;
    added += "#" + std::to_string(p) + "= IFCCARTESIANPOINT((" + number(o.x) + "," + number(o.y) +
             "," + number(o.z) + "));\n";
    added += "#" + std::to_string(dz) + "= IFCDIRECTION((" + number(z.x) + "," + number(z.y) + "," +
             number(z.z) + "));\n";
    added += "#" + std::to_string(dx) + "= IFCDIRECTION((" + number(x.x) + "," + number(x.y) + "," +
             number(x.z) + "));\n";
    added += "#" + std::to_string(axis) + "= IFCAXIS2PLACEMENT3D(#" + std::to_string(p) + ",#" +
             std::to_string(dz) + ",#" + std::to_string(dx) + ");\n";
    added += "#" + std::to_string(local) + "= IFCLOCALPLACEMENT($,#" + std::to_string(axis) + ");\n";
    const auto span = instanceSpan(text, it->second, product.line, name);
    const auto arg = argumentSpan(text, span.first, span.second, 5);
    if (arg.first >= span.second) throw FormatError::atLine(name, product.line, "no ObjectPlacement to rewrite");
    edits.push_back({arg, "#" + std::to_string(local)});
    ++report.moved;
  }

  // The product edits from the back, so earlier offsets hold; then the new instances before the
  // DATA section's end.
  std::sort(edits.begin(), edits.end(), [](const auto& a, const auto& b) { return a.first.first > b.first.first; });
  for (const auto& [span, replacement] : edits) text.replace(span.first, span.second - span.first, replacement);
  const size_t end_of_data = text.rfind("ENDSEC;", text.find("END-ISO-10303-21"));
  if (end_of_data == std::string::npos) throw FormatError(name, "no end of its DATA section");
  text.insert(end_of_data, added);

  const std::filesystem::path temporary = out.string() + ".tmp";
  {
    std::ofstream f(temporary, std::ios::binary | std::ios::trunc);
    f << text;
    if (!f) throw std::runtime_error(out.string() + ": cannot be written");
  }
  std::error_code error;
  std::filesystem::rename(temporary, out, error);
  if (error) throw std::runtime_error(out.string() + ": cannot be written: " + error.message());
  return report;
}

}  // namespace tw
