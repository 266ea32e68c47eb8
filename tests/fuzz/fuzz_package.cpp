// Fuzz target: the package reader as `verify`, `view` and `render` use it: open with every
// checksum checked, the whole consistency check (it decodes every page and cluster), and the
// finest cut under a triangle budget, as a first frame would pick it.
#include <exception>

#include "dag_front.h"
#include "fuzz_input.h"
#include "package_check.h"
#include "package_view.h"

using namespace tw;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto path = fuzz::writeFile("model.twk", fuzz::all(data, size));
  try {
    const PackageView view = PackageView::open(path, PackageView::Verify::All);
    const CheckReport report = checkPackage(view);
    if (report.ok()) (void)finestFrontWithin(view, 100000);
  } catch (const std::exception&) {
    // A clear error is the right answer to a bad package.
  }
  return 0;
}
