// Fuzz target: BCF archives (`bcf list|import`, `render --viewpoint`). The bytes are read as a
// .bcfzip when they start like a zip, else as a markup and as a visualisation document.
#include <exception>
#include <string>
#include <vector>

#include "bcf_archive.h"
#include "bcf_xml.h"
#include "fuzz_input.h"

using namespace tw;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes = fuzz::all(data, size);
  try {
    if (bytes.starts_with("PK")) {
      std::vector<std::string> warnings;
      const bcf::Archive archive = bcf::readArchive(fuzz::writeFile("topics.bcfzip", bytes), warnings);
      (void)bcf::viewpointsInOrder(archive);
    } else {
      try {
        (void)bcf::readMarkupXml(bytes, "markup.bcf");
      } catch (const std::exception&) {
      }
      bcf::Viewpoint viewpoint;
      bcf::readVisinfoXml(bytes, "viewpoint.bcfv", bcf::Version::V3_0, viewpoint);
    }
  } catch (const std::exception&) {
    // A clear error is the right answer to a bad archive.
  }
  return 0;
}
