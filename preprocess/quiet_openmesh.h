// QuietOpenMesh: silences OpenMesh's error stream while a topology check runs. Refused faces are
// the expected outcome on a broken mesh, and the checks (watertight_check, patch_mesh_check)
// count them in their reports instead. One class for every check, so concurrent checks share
// one reference count and the stream's state is restored only when the last one ends.
// Include only from .cpp files that already use OpenMesh.
#pragma once

#include <mutex>

#include <OpenMesh/Core/System/omstream.hh>

namespace tw {

class QuietOpenMesh {
 public:
  QuietOpenMesh() {
    const std::lock_guard lock(mutex_);
    if (users_++ == 0) {
      was_enabled_ = ::omerr().is_enabled();
      ::omerr().disable();
    }
  }
  ~QuietOpenMesh() {
    const std::lock_guard lock(mutex_);
    if (--users_ == 0 && was_enabled_) ::omerr().enable();
  }
  QuietOpenMesh(const QuietOpenMesh&) = delete;
  QuietOpenMesh& operator=(const QuietOpenMesh&) = delete;

 private:
  static inline std::mutex mutex_;
  static inline int users_ = 0;
  static inline bool was_enabled_ = true;
};

}  // namespace tw
