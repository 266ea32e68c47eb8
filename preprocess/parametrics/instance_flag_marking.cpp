// Sealed-run roles and covered box faces of a parametric stream, as instance flags. See
// instance_flag_marking.h.
#include "instance_flag_marking.h"

#include <limits>
#include <stdexcept>

#include "package_writer.h"

namespace tw {

InstanceFlagMarking markInstanceFlags(const ParametricStream& stream, const glm::dvec3& origin,
                                      std::span<const uint32_t> object_layers) {
  std::vector<pkg::InstanceRecord> records;
  stream([&](std::span<const ParametricItem> batch) {
    if (records.size() + batch.size() > std::numeric_limits<uint32_t>::max())
      throw std::invalid_argument("markInstanceFlags: too many items");
    for (const ParametricItem& item : batch)
      records.push_back(placedInstanceRecord(item.primitive, item.transform, item.object, origin));
  });
  InstanceFlagMarking marking;
  const std::vector<uint8_t> roles = findSealedRuns(records, &marking.sealed);
  const std::vector<uint8_t> faces = findCoveredBoxFaces(records, object_layers, &marking.covered);
  records = {};
  marking.role_flags.resize(roles.size());
  for (size_t i = 0; i < roles.size(); ++i)
    marking.role_flags[i] =
        uint16_t(sealedRunInstanceFlags(roles[i]) | coveredFaceInstanceFlags(faces[i]));
  return marking;
}

}  // namespace tw
