// A brick's finished LOD DAG as bytes, for the resume store (brick_cache.h): a killed run
// restarted with --resume reloads finished bricks instead of rebuilding them.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "cluster_dag.h"

namespace tw {

// Every field of `dag`, little-endian, in a versioned layout private to this file.
std::vector<uint8_t> serializeClusterDag(const ClusterDag& dag);

// The inverse. Every count is checked against the bytes present; damaged input throws FormatError
// naming `source` and the byte offset.
ClusterDag deserializeClusterDag(std::span<const uint8_t> bytes,
                                 const std::string& source = "cluster DAG");

}  // namespace tw
