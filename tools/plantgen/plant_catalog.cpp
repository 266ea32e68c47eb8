// Engineering catalogue of the generated plant: process services, pipe sizes and line numbers.
//
// Keys follow plant practice so that the project database reads like a real one:
// size"-service-number-spec for lines (12"-HC-1001-A1).
#include "plant_parts.h"

namespace tw::plant {
namespace {

const Service kServices[] = {
    {"HC", "hydrocarbon", kLayerPipingProcess, 49.6f, 120.0f, "A1", "CS A106-B"},
    {"PG", "process gas", kLayerPipingProcess, 98.0f, 85.0f, "B2", "LTCS A333-6"},
    {"FL", "flare", kLayerPipingProcess, 6.0f, 180.0f, "A3", "CS A106-B"},
    {"PW", "produced water", kLayerPipingWater, 19.0f, 95.0f, "D1", "DSS 22Cr"},
    {"SW", "sea water", kLayerPipingWater, 10.0f, 30.0f, "C3", "CuNi 90/10"},
    {"CW", "cooling medium", kLayerPipingWater, 10.0f, 60.0f, "C1", "CS A106-B"},
    {"IA", "instrument air", kLayerPipingUtility, 10.0f, 50.0f, "U1", "SS 316L"},
    {"NG", "nitrogen", kLayerPipingUtility, 12.0f, 50.0f, "U1", "SS 316L"},
    {"CI", "chemical injection", kLayerPipingUtility, 200.0f, 50.0f, "U4", "SS 316L"},
    {"FW", "fire water", kLayerPipingFire, 16.0f, 30.0f, "F1", "GRE"},
};

// Outside diameters from ASME B36.10.
const PipeSize kSizes[] = {
    {"2", 50.0f, 0.0603f},   {"3", 80.0f, 0.0889f},   {"4", 100.0f, 0.1143f},
    {"6", 150.0f, 0.1683f},  {"8", 200.0f, 0.2191f},  {"10", 250.0f, 0.2730f},
    {"12", 300.0f, 0.3239f}, {"16", 400.0f, 0.4064f}, {"20", 500.0f, 0.5080f},
    {"24", 600.0f, 0.6096f},
};

}  // namespace

const Service& service(uint32_t index) { return kServices[index % std::size(kServices)]; }
uint32_t serviceCount() { return static_cast<uint32_t>(std::size(kServices)); }
const PipeSize& pipeSize(uint32_t index) {
  return kSizes[index < std::size(kSizes) ? index : std::size(kSizes) - 1];
}
uint32_t pipeSizeCount() { return static_cast<uint32_t>(std::size(kSizes)); }

PipeLine openLine(Emitter& out, uint32_t service_index, uint32_t size_index, const char* where) {
  const Service& s = service(service_index);
  const PipeSize& size = pipeSize(size_index);
  PipeLine line;
  line.number = out.next_line_number++;
  line.key = format("%s\"-%s-%u-%s", size.inch, s.code, line.number, s.spec);
  line.service = service_index % serviceCount();
  line.size = size_index < pipeSizeCount() ? size_index : pipeSizeCount() - 1;
  line.radius_m = size.od_m * 0.5f;
  line.where = where;
  return line;
}

void recordLine(Emitter& out, PipeLine& line) {
  if (line.recorded) return;
  line.recorded = true;
  const Service& s = service(line.service);
  const PipeSize& size = pipeSize(line.size);
  ProjectRecord r;
  r.db_key = line.key;
  r.type = "pipe";
  r.line_number = std::to_string(line.number);
  r.service = s.name;
  r.material = s.material;
  r.nominal_diameter_mm = size.nominal_mm;
  r.design_pressure_bar = s.pressure_bar;
  r.design_temperature_c = s.temperature_c;
  r.description = format("%s\" %s line, spec %s, %s", size.inch, s.name, s.spec, line.where);
  out.record(r);
}

}  // namespace tw::plant
