// IFC product semantics into the project database. See ifc_properties.h.
#include "ifc_properties.h"

#include <algorithm>
#include <cstdio>
#include <string>
#include <unordered_map>
#include <vector>

#include "format_error.h"
#include "ifc_importer.h"
#include "project_database.h"
#include "step21_file.h"

namespace tw {

using Kind = Step21Value::Kind;
using part21::arg;
using part21::textOf;

namespace {

// A property's value as text: numbers as written, booleans and logicals as words, labels as
// themselves; lists joined by ", ".
std::string valueText(const Step21Value& v) {
  switch (v.kind) {
    case Kind::Integer: return std::to_string(int64_t(v.number));
    case Kind::Real: {
      char buffer[32];
      std::snprintf(buffer, sizeof buffer, "%.10g", v.number);
      return buffer;
    }
    case Kind::String: return v.text;
    case Kind::Enum: return v.text == "T" ? "true" : v.text == "F" ? "false" : v.text;
    case Kind::Typed: return v.items.empty() ? "" : valueText(v.items[0]);
    case Kind::List: {
      std::string out;
      for (const Step21Value& item : v.items) out += (out.empty() ? "" : ", ") + valueText(item);
      return out;
    }
    default: return "";
  }
}

// A unit's short name: the SI name with its prefix, or a conversion-based unit's name.
std::string unitText(const Step21File& f, const Step21Value& v) {
  const Step21Instance* unit = f.deref(v);
  if (!unit) return "";
  if (unit->type == "IFCSIUNIT") return textOf(arg(unit, 2)) + textOf(arg(unit, 3));
  if (unit->type == "IFCCONVERSIONBASEDUNIT") return textOf(arg(unit, 2));
  return "";
}

}  // namespace

uint64_t writeIfcProperties(const std::filesystem::path& path, ProjectDatabase& database) {
  const Step21File f = Step21File::read(path);
  if (f.schema().rfind("IFC", 0) != 0)
    throw FormatError(path.string(), "not an IFC file: its FILE_SCHEMA is '" + f.schema() + "'");
  // The drawn products (the importer's rule), by id.
  std::unordered_map<uint64_t, std::string> keys;
  for (const auto& [id, in] : f.instances())
    if (isDrawnIfcProduct(f, in)) keys.emplace(id, in.args[0].text);
  std::vector<uint64_t> ids;
  for (const auto& [id, key] : keys) ids.push_back(id);
  std::sort(ids.begin(), ids.end());
  for (uint64_t id : ids) {
    const Step21Instance& in = *f.find(id);
    ProjectRecord record;
    record.db_key = keys[id];
    record.type = in.type;
    record.description = textOf(in.args[2]);
    database.put(record);
    database.putProperty({record.db_key, "IFC", "Class", in.type, ""});
    if (!record.description.empty())
      database.putProperty({record.db_key, "IFC", "Name", record.description, ""});
    if (const std::string type = textOf(in.args[4]); !type.empty())
      database.putProperty({record.db_key, "IFC", "ObjectType", type, ""});
  }
  // The storey (or other spatial structure) containing each product.
  for (uint64_t rel : f.idsOfType("IFCRELCONTAINEDINSPATIALSTRUCTURE")) {
    const Step21Instance* r = f.find(rel);
    const Step21Instance* structure = f.deref(arg(r, 5));
    if (!structure) continue;
    const std::string name = textOf(arg(structure, 2));
    for (const Step21Value& e : arg(r, 4).items)
      if (auto it = keys.find(e.ref); e.kind == Kind::Ref && it != keys.end())
        database.putProperty({it->second, "IFC", "Storey", name, ""});
  }
  // Property sets and quantities, by IfcRelDefinesByProperties.
  for (uint64_t rel : f.idsOfType("IFCRELDEFINESBYPROPERTIES")) {
    const Step21Instance* r = f.find(rel);
    const Step21Instance* definition = f.deref(arg(r, 5));
    if (!definition) continue;
    const std::string set = textOf(arg(definition, 2));
    std::vector<ProjectProperty> properties;
    if (definition->type == "IFCPROPERTYSET") {
      for (const Step21Value& pv : arg(definition, 4).items) {
        const Step21Instance* p = f.deref(pv);
        if (!p) continue;
        if (p->type == "IFCPROPERTYSINGLEVALUE")
          properties.push_back({"", set, textOf(arg(p, 0)), valueText(arg(p, 2)), unitText(f, arg(p, 3))});
        else if (p->type == "IFCPROPERTYENUMERATEDVALUE")
          properties.push_back({"", set, textOf(arg(p, 0)), valueText(arg(p, 2)), ""});
      }
    } else if (definition->type == "IFCELEMENTQUANTITY") {
      for (const Step21Value& qv : arg(definition, 5).items) {
        const Step21Instance* q = f.deref(qv);
        if (!q || q->type.rfind("IFCQUANTITY", 0) != 0) continue;
        properties.push_back({"", set, textOf(arg(q, 0)), valueText(arg(q, 3)), unitText(f, arg(q, 2))});
      }
    }
    for (const Step21Value& o : arg(r, 4).items) {
      auto it = keys.find(o.ref);
      if (o.kind != Kind::Ref || it == keys.end()) continue;
      for (ProjectProperty p : properties) {
        p.db_key = it->second;
        database.putProperty(p);
      }
    }
  }
  database.commit();
  return ids.size();
}

}  // namespace tw
