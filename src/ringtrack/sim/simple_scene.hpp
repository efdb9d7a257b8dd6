#pragma once
/// A minimal analytic scene (ground, an enclosing wall, vertical cylinders) rendered into an
/// organized scan with per-cell labels: the demo's and the benchmarks' built-in input.

#include <cstdint>
#include <optional>
#include <vector>

#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/sensor_model.hpp"

namespace ringtrack::sim {

/// Upright cylinder in the sensor frame (people, poles, trunks).
struct Cylinder {
  double x_m{0}, y_m{0};
  double radius_m{0.25};
  double z_min_m{-1.5}, z_max_m{0.25};
  std::uint32_t label{0};  ///< object id written to the label image, 0 = background
};

/// Ground plane, optional circular wall around the sensor and cylinders; sensor at the origin.
struct SimpleScene {
  std::optional<double> ground_z_m;     ///< horizontal ground plane height, if any
  std::optional<double> wall_radius_m;  ///< a vertical wall all around at this distance
  std::vector<Cylinder> cylinders;
  double range_noise_m{0.0};  ///< Gaussian range noise (standard deviation)
  std::uint64_t seed{1};

  /// A person (1.75 m tall, 0.25 m radius) standing at (x, y) on ground at ground_z.
  static Cylinder person(double x_m, double y_m, double ground_z_m, std::uint32_t label);
  /// The demo scene: ground 1.5 m below the sensor, a wall at 12 m, five people and a pole.
  static SimpleScene demo();
  /// The hardest case for segmentation: a wall 1 m away all around and three people.
  static SimpleScene hard_wall();
  /// An open field: ground 2.5 m below, ten people at 5-40 m and nothing else.
  static SimpleScene open_field(int people = 10);
};

/// Rendered scan plus the label of the object each cell hit (0 = background / none).
struct RenderedScan {
  core::OrganizedScan scan;
  std::vector<std::uint32_t> labels;
};

/// Casts one ray per ring and column through the scene (columns at uniform azimuth steps).
RenderedScan render(const core::SensorModel& model, const SimpleScene& scene);

}  // namespace ringtrack::sim
