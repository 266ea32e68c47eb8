// Sealed-run roles of a parametric stream, as instance flags. See sealed_run_marking.h.
#include "sealed_run_marking.h"

#include <limits>
#include <stdexcept>

#include "package_writer.h"

namespace tw {

SealedRunMarking markSealedRuns(const ParametricStream& stream, const glm::dvec3& origin) {
  std::vector<pkg::InstanceRecord> records;
  stream([&](std::span<const ParametricItem> batch) {
    if (records.size() + batch.size() > std::numeric_limits<uint32_t>::max())
      throw std::invalid_argument("markSealedRuns: too many items");
    for (const ParametricItem& item : batch)
      records.push_back(placedInstanceRecord(item.primitive, item.transform, item.object, origin));
  });
  SealedRunMarking marking;
  const std::vector<uint8_t> roles = findSealedRuns(records, &marking.stats);
  records = {};
  marking.role_flags.resize(roles.size());
  for (size_t i = 0; i < roles.size(); ++i)
    marking.role_flags[i] = uint8_t(sealedRunInstanceFlags(roles[i]));
  return marking;
}

}  // namespace tw
