// `ringtrack sensors`: the sensors ringtrack decodes, how each is recognised and what it needs.

#include <cstdio>

#include "commands.hpp"
#include "ringtrack/core/sensor_model.hpp"
#include "ringtrack/sensors/hesai/hesai_format.hpp"

namespace ringtrack::cli {
namespace {

void list_sensors() {
  std::printf("%-12s %-9s %5s %8s  %-13s %s\n", "sensor", "family", "rings", "columns", "range (m)",
              "recognised from / needs");
  for (const char* name : {"vlp16", "vlp32c", "hdl32e"}) {
    const auto m = core::SensorModel::by_name(name);
    std::printf("%-12s %-9s %5d %8d  %5.2f..%-6.0f %s\n", m.name.c_str(), "Velodyne", m.rings(),
                m.columns(), m.min_range_m, m.max_range_m,
                "the packets' product byte (docs/vlp16.md)");
  }
  for (const auto& f : sensors::hesai::hesai_formats()) {
    std::printf("%-12s %-9s %5d %8d  %5.2f..%-6.0f %s\n", f.name, "Hesai", f.channels,
                f.columns_at_10hz, f.default_min_range_m, f.default_max_range_m,
                "the packet header and size; --calibration FILE (docs/hesai.md)");
  }
  std::printf("%-12s %-9s %5s %8s  %5.2f..%-6.0f %s\n", "OS0/OS1/OS2", "Ouster", "32-128",
              "512-2048", 0.3, 250.0,
              "--metadata FILE (the sensor's JSON: beams, columns, profile; docs/ouster.md)");
  std::printf("columns at 10 Hz; name a sensor with --sensor when the data does not say it\n");
  std::printf(
      "clouds without rings (.bin folders, unorganized PCD, PointCloud2 without a ring field): "
      "the --sensor's grid, else a generic sensor measured on the first cloud (docs/inputs.md)\n");
}

}  // namespace

void register_sensors(CLI::App& app) {
  auto* cmd = app.add_subcommand("sensors", "list the sensors ringtrack decodes");
  cmd->callback([] { list_sensors(); });
}

}  // namespace ringtrack::cli
