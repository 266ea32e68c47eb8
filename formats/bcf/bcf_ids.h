// Identifiers and dates as BCF writes them: topic, comment and viewpoint GUIDs (lower-case UUIDs,
// which 3.0's pattern requires), IFC GlobalIds (22 characters of IFC's base-64 alphabet), and
// xs:dateTime stamps.
#pragma once

#include <string>
#include <string_view>

namespace tw::bcf {

// A random (version 4) UUID, "xxxxxxxx-xxxx-4xxx-yxxx-xxxxxxxxxxxx", lower case.
std::string newGuid();
// Whether `text` is a UUID in the 8-4-4-4-12 hex form (either case).
bool isGuid(std::string_view text);
// Whether `text` is an IFC GlobalId: 22 characters of 0-9, A-Z, a-z, '_' and '$'.
bool isIfcGlobalId(std::string_view text);
// Now in UTC, "YYYY-MM-DDTHH:MM:SSZ".
std::string utcNow();

}  // namespace tw::bcf
