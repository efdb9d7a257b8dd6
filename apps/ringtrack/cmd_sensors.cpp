// `ringtrack sensors`: the sensors ringtrack decodes, how each is recognised and what it needs.

#include <cstdio>
#include <string>

#include "commands.hpp"
#include "ringtrack/core/sensor_model.hpp"
#include "ringtrack/sensors/hesai/hesai_format.hpp"

namespace ringtrack::cli {
namespace {

// One line per row of core::built_in_sensors(): the Velodyne rows with their nominal geometry,
// the Hesai rows with their packet format's channels and columns, Ouster as one family.
void list_sensors() {
  std::printf("%-12s %-9s %5s %8s  %-13s %s\n", "sensor", "family", "rings", "columns", "range (m)",
              "recognised from / needs");
  for (const auto& row : core::built_in_sensors()) {
    const std::string family = row.family;
    if (family == "Velodyne") {
      const auto m = row.make(10.0);
      const bool packets = m.rings() != 64;  // the HDL-64E is organized from clouds only
      std::printf("%-12s %-9s %5d %8d  %5.2f..%-6.0f %s\n", row.name, row.family, m.rings(),
                  m.columns(), m.min_range_m, m.max_range_m,
                  packets ? "the packets' product byte (docs/vlp16.md); clouds: --sensor"
                          : "clouds only: --sensor hdl64e (nominal geometry, docs/inputs.md)");
    } else if (family == "Hesai") {
      const auto* f = sensors::hesai::hesai_format_by_name(row.name);
      if (f == nullptr) continue;
      std::printf("%-12s %-9s %5d %8d  %5.2f..%-6.0f %s\n", f->name, row.family, f->channels,
                  f->columns_at_10hz, f->default_min_range_m, f->default_max_range_m,
                  "the packet header and size; --calibration FILE (docs/hesai.md)");
    } else {
      std::printf("%-12s %-9s %5s %8s  %5.2f..%-6.0f %s\n", row.name, row.family, "32-128",
                  "512-2048", 0.3, 250.0,
                  "--metadata FILE (the sensor's JSON: beams, columns, profile; docs/ouster.md)");
    }
  }
  std::printf("columns at 10 Hz; name a sensor with --sensor when the data does not say it\n");
  std::printf(
      "clouds without rings (.bin folders, unorganized PCD, PointCloud2 without a ring field): "
      "the --sensor's grid (%s), else a generic sensor measured on the first cloud "
      "(docs/inputs.md)\n",
      core::built_in_model_list().c_str());
}

}  // namespace

void register_sensors(CLI::App& app) {
  auto* cmd = app.add_subcommand("sensors", "list the sensors ringtrack decodes");
  cmd->callback([] { list_sensors(); });
}

}  // namespace ringtrack::cli
