// The selection-sets file; see selection_sets.h.
#include "selection_sets.h"

#include <fstream>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace tw {
namespace {

constexpr int kFormatVersion = 1;

std::vector<uint32_t> readIds(const nlohmann::json& set, const char* field,
                              const std::string& where) {
  std::vector<uint32_t> ids;
  if (!set.contains(field)) return ids;
  const nlohmann::json& list = set.at(field);
  if (!list.is_array()) throw std::runtime_error(where + ": '" + field + "' is not a list");
  for (const nlohmann::json& id : list) {
    if (!id.is_number_unsigned() || id.get<uint64_t>() > UINT32_MAX)
      throw std::runtime_error(where + ": '" + field + "' holds " + id.dump(-1).substr(0, 40) +
                               ", not an object id");
    ids.push_back(id.get<uint32_t>());
  }
  return ids;
}

}  // namespace

std::filesystem::path selectionSetsPathFor(const std::filesystem::path& package) {
  std::filesystem::path path = package;
  path.replace_extension(".sets.json");
  return path;
}

std::vector<SelectionSet> readSelectionSets(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    if (!std::filesystem::exists(path)) return {};
    throw std::runtime_error(path.string() + ": cannot open the selection sets");
  }
  std::stringstream text;
  text << in.rdbuf();
  const nlohmann::json root = nlohmann::json::parse(text.str(), nullptr, false);
  if (root.is_discarded())
    throw std::runtime_error(path.string() + ": not JSON (the selection sets file is damaged)");
  if (!root.is_object() || !root.contains("terawalk_selection_sets") ||
      root["terawalk_selection_sets"] != kFormatVersion)
    throw std::runtime_error(path.string() +
                             ": not a TeraWalk selection sets file of version 1");
  if (!root.contains("sets") || !root["sets"].is_array())
    throw std::runtime_error(path.string() + ": 'sets' is missing or not a list");
  std::vector<SelectionSet> sets;
  for (size_t i = 0; i < root["sets"].size(); ++i) {
    const nlohmann::json& s = root["sets"][i];
    const std::string where = path.string() + ": set " + std::to_string(i + 1);
    if (!s.is_object() || !s.contains("name") || !s["name"].is_string())
      throw std::runtime_error(where + ": no name");
    SelectionSet set;
    set.name = s["name"].get<std::string>();
    const std::string kind = s.value("kind", std::string());
    if (kind == "selection") set.kind = SelectionSet::Kind::Selection;
    else if (kind == "visibility") set.kind = SelectionSet::Kind::Visibility;
    else throw std::runtime_error(where + ": kind '" + kind + "' is not selection or visibility");
    set.selected = readIds(s, "selected", where);
    set.hidden = readIds(s, "hidden", where);
    set.xray = readIds(s, "xray", where);
    sets.push_back(std::move(set));
  }
  return sets;
}

void writeSelectionSets(const std::filesystem::path& path, const std::vector<SelectionSet>& sets) {
  nlohmann::json list = nlohmann::json::array();
  for (const SelectionSet& set : sets) {
    nlohmann::json s = {{"name", set.name}};
    if (set.kind == SelectionSet::Kind::Selection) {
      s["kind"] = "selection";
      s["selected"] = set.selected;
    } else {
      s["kind"] = "visibility";
      s["hidden"] = set.hidden;
      s["xray"] = set.xray;
    }
    list.push_back(std::move(s));
  }
  const nlohmann::json root = {{"terawalk_selection_sets", kFormatVersion}, {"sets", list}};
  const std::filesystem::path temporary = path.string() + ".tmp";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out << root.dump(1) << "\n";
    out.flush();
    if (!out) throw std::runtime_error(temporary.string() + ": cannot write the selection sets");
  }
  std::error_code error;
  std::filesystem::rename(temporary, path, error);
  if (error)
    throw std::runtime_error(path.string() + ": cannot replace the selection sets: " +
                             error.message());
}

}  // namespace tw
