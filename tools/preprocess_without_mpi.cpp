// `preprocess --mpi` in a terawalk built without MPI: a clear refusal.
#include <stdexcept>

#include "preprocess_mpi.h"

namespace tw {

bool haveMpi() { return false; }

int runPreprocessOverMpi(const PreprocessOptions&, const MpiPreprocessHooks&) {
  throw std::runtime_error(
      "preprocess --mpi: this terawalk was built without MPI (install libopenmpi-dev and "
      "openmpi-bin, then configure again)");
}

}  // namespace tw
