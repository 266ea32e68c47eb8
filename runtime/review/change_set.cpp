// The change set and its JSON file (change_set.h).
#include "change_set.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <glm/gtc/matrix_transform.hpp>
#include <nlohmann/json.hpp>

namespace tw {
namespace {

constexpr int kFormatVersion = 1;

const char* kindName(Change::Kind kind) {
  switch (kind) {
    case Change::Kind::Move: return "move";
    case Change::Kind::Hide: return "hide";
    case Change::Kind::Colour: return "colour";
    case Change::Kind::Comment: return "comment";
  }
  return "?";
}

nlohmann::json vec(const glm::dvec3& v) { return {v.x, v.y, v.z}; }

std::string rgbaText(uint32_t rgba) {  // 0xAABBGGRR as "RRGGBBAA"
  char text[9];
  std::snprintf(text, sizeof text, "%02X%02X%02X%02X", rgba & 0xff, (rgba >> 8) & 0xff,
                (rgba >> 16) & 0xff, rgba >> 24);
  return text;
}

[[noreturn]] void fail(const std::string& where, const std::string& reason) {
  throw std::runtime_error(where + ": " + reason);
}

std::vector<double> numbers(const nlohmann::json& j, const char* field, size_t count,
                            const std::string& where) {
  if (!j.contains(field)) fail(where, std::string("no '") + field + "'");
  const nlohmann::json& list = j.at(field);
  if (!list.is_array() || list.size() != count)
    fail(where, std::string("'") + field + "' is not " + std::to_string(count) + " numbers");
  std::vector<double> out;
  for (const nlohmann::json& n : list) {
    if (!n.is_number() || !std::isfinite(n.get<double>()))
      fail(where, std::string("'") + field + "' holds " + n.dump().substr(0, 40) +
                      ", not a finite number");
    out.push_back(n.get<double>());
  }
  return out;
}

std::string text(const nlohmann::json& j, const char* field, const std::string& where,
                 bool required) {
  if (!j.contains(field)) {
    if (required) fail(where, std::string("no '") + field + "'");
    return {};
  }
  if (!j.at(field).is_string()) fail(where, std::string("'") + field + "' is not text");
  return j.at(field).get<std::string>();
}

}  // namespace

glm::dmat4 moveTransform(const glm::dvec3& pivot, const glm::dvec3& translation,
                         const glm::dvec3& rotation_axis, double angle_rad, double scale) {
  glm::dmat4 m = glm::translate(glm::dmat4(1.0), pivot + translation);
  if (angle_rad != 0.0) m = glm::rotate(m, angle_rad, glm::normalize(rotation_axis));
  if (scale != 1.0) m = glm::scale(m, glm::dvec3(scale));
  return glm::translate(m, -pivot);
}

void ChangeSet::add(Change change) {
  changes_.push_back(std::move(change));
  undone_.clear();
}

bool ChangeSet::undo() {
  if (changes_.empty()) return false;
  undone_.push_back(std::move(changes_.back()));
  changes_.pop_back();
  return true;
}

bool ChangeSet::redo() {
  if (undone_.empty()) return false;
  changes_.push_back(std::move(undone_.back()));
  undone_.pop_back();
  return true;
}

glm::dmat4 ChangeSet::placement(const std::string& key) const {
  glm::dmat4 m(1.0);
  for (const Change& c : changes_)
    if (c.kind == Change::Kind::Move && c.key == key) m = c.transform * m;
  return m;
}

std::vector<std::string> ChangeSet::movedKeys() const {
  std::vector<std::string> keys;
  for (const Change& c : changes_)
    if (c.kind == Change::Kind::Move && std::find(keys.begin(), keys.end(), c.key) == keys.end())
      keys.push_back(c.key);
  return keys;
}

std::filesystem::path changeSetPathFor(const std::filesystem::path& package) {
  std::filesystem::path path = package;
  path.replace_extension(".changes.json");
  return path;
}

ChangeSet readChangeSet(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    if (!std::filesystem::exists(path)) return {};
    throw std::runtime_error(path.string() + ": cannot open the change set");
  }
  std::stringstream bytes;
  bytes << in.rdbuf();
  const nlohmann::json root = nlohmann::json::parse(bytes.str(), nullptr, false);
  if (root.is_discarded()) fail(path.string(), "not JSON (the change set is damaged)");
  if (!root.is_object() || !root.contains("terawalk_changes") ||
      root["terawalk_changes"] != kFormatVersion)
    fail(path.string(), "not a TeraWalk change set of version 1");
  if (!root.contains("changes") || !root["changes"].is_array())
    fail(path.string(), "'changes' is missing or not a list");
  ChangeSet set;
  for (size_t i = 0; i < root["changes"].size(); ++i) {
    const nlohmann::json& j = root["changes"][i];
    const std::string where = path.string() + ": change " + std::to_string(i + 1);
    if (!j.is_object()) fail(where, "not an object");
    Change c;
    const std::string kind = text(j, "kind", where, true);
    c.key = text(j, "key", where, true);
    if (c.key.empty()) fail(where, "the key is empty");
    c.author = text(j, "author", where, false);
    c.date = text(j, "date", where, false);
    if (kind == "move") {
      c.kind = Change::Kind::Move;
      const std::vector<double> m = numbers(j, "transform", 16, where);
      for (int col = 0; col < 4; ++col)
        for (int row = 0; row < 4; ++row) c.transform[col][row] = m[size_t(col * 4 + row)];
      const std::vector<double> a = numbers(j, "old_pivot", 3, where), b = numbers(j, "new_pivot", 3, where);
      c.old_pivot = {a[0], a[1], a[2]};
      c.new_pivot = {b[0], b[1], b[2]};
      if (c.transform[0][3] != 0.0 || c.transform[1][3] != 0.0 || c.transform[2][3] != 0.0 ||
          c.transform[3][3] != 1.0)
        fail(where, "the transform's last row is not 0 0 0 1");
    } else if (kind == "hide") {
      c.kind = Change::Kind::Hide;
      if (!j.contains("hidden") || !j["hidden"].is_boolean()) fail(where, "'hidden' is not true or false");
      c.hidden = j["hidden"].get<bool>();
    } else if (kind == "colour") {
      c.kind = Change::Kind::Colour;
      const std::string hex = text(j, "rgba", where, true);
      char* end = nullptr;
      const unsigned long v = std::strtoul(hex.c_str(), &end, 16);
      if (hex.size() != 8 || *end != '\0') fail(where, "'rgba' '" + hex + "' is not RRGGBBAA");
      c.rgba = static_cast<uint32_t>(((v >> 24) & 0xff) | (((v >> 16) & 0xff) << 8) |
                                     (((v >> 8) & 0xff) << 16) | ((v & 0xff) << 24));
    } else if (kind == "comment") {
      c.kind = Change::Kind::Comment;
      c.text = text(j, "text", where, true);
    } else {
      fail(where, "unknown kind '" + kind + "' (move, hide, colour, comment)");
    }
    set.add(std::move(c));
  }
  return set;
}

void writeChangeSet(const std::filesystem::path& path, const ChangeSet& changes) {
  nlohmann::json list = nlohmann::json::array();
  for (const Change& c : changes.changes()) {
    nlohmann::json j = {{"kind", kindName(c.kind)}, {"key", c.key}, {"author", c.author}, {"date", c.date}};
    switch (c.kind) {
      case Change::Kind::Move: {
        nlohmann::json m = nlohmann::json::array();
        for (int col = 0; col < 4; ++col)
          for (int row = 0; row < 4; ++row) m.push_back(c.transform[col][row]);
        j["transform"] = m;
        j["old_pivot"] = vec(c.old_pivot);
        j["new_pivot"] = vec(c.new_pivot);
        break;
      }
      case Change::Kind::Hide: j["hidden"] = c.hidden; break;
      case Change::Kind::Colour: j["rgba"] = rgbaText(c.rgba); break;
      case Change::Kind::Comment: j["text"] = c.text; break;
    }
    list.push_back(j);
  }
  const nlohmann::json root = {{"terawalk_changes", kFormatVersion}, {"changes", list}};
  const std::filesystem::path temporary = path.string() + ".tmp";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out << root.dump(1) << "\n";
    if (!out) throw std::runtime_error(temporary.string() + ": cannot write the change set");
  }
  std::error_code error;
  std::filesystem::rename(temporary, path, error);
  if (error) throw std::runtime_error(path.string() + ": cannot write the change set: " + error.message());
}

}  // namespace tw
