// Test helper: copies a package with its DAG rearranged in ways the format allows, so tests can
// check that readers do not rely on the preprocessor's layout, and with one page per mesh
// cluster, so paging tests see fine-grained residency even on small models.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "package_view.h"
#include "package_writer.h"

namespace tw::test {

// Copies a package, optionally with its group table reversed and/or every mesh cluster in a page
// of its own (the preprocessor packs 128 KiB pages, so a small model has only a few; one page per
// cluster makes residency tests fine-grained).
inline void rewritePackage(const PackageView& view, const std::filesystem::path& file,
                           bool reverse_groups, bool page_per_cluster) {
  PackageStorage storage;
  storage.origin = view.origin();
  storage.position_step_m = view.positionStepM();
  storage.target_page_bytes = view.header().target_page_bytes;
  storage.input_hash = view.header().input_hash;
  const auto group_count = static_cast<uint32_t>(view.groups().size());
  auto flip = [&](uint32_t g) {
    return g == pkg::kNone || !reverse_groups ? g : group_count - 1 - g;
  };
  std::vector<std::vector<uint8_t>> raw_pages(view.pages().size());
  for (uint32_t p = 0; p < raw_pages.size(); ++p) view.readPage(p, raw_pages[p]);
  if (!page_per_cluster) storage.pages = raw_pages;
  for (pkg::ClusterRecord c : view.clusters()) {
    c.group = flip(c.group);
    c.parent_group = flip(c.parent_group);
    if (page_per_cluster && c.kind == static_cast<uint8_t>(pkg::ClusterKind::Mesh)) {
      const std::vector<uint8_t>& raw = raw_pages[c.page];
      storage.pages.emplace_back(raw.begin() + c.page_offset,
                                 raw.begin() + c.page_offset + c.encoded_bytes);
      c.page = static_cast<uint32_t>(storage.pages.size() - 1);
      c.page_offset = 0;
    }
    storage.clusters.push_back(c);
  }
  for (uint32_t g = 0; g < group_count; ++g) storage.groups.push_back(view.groups()[flip(g)]);
  storage.instances.assign(view.instances().begin(), view.instances().end());
  storage.profile_points.assign(view.profilePoints().begin(), view.profilePoints().end());
  storage.objects.assign(view.objects().begin(), view.objects().end());
  storage.layers.assign(view.layers().begin(), view.layers().end());
  storage.strings = std::string(view.strings());
  writePackage(storage, file);
}

}  // namespace tw::test
