#include "support/naive_visibility.hpp"

#include <algorithm>
#include <limits>

namespace ringtrack::testing {
namespace {

using core::BeamRay;
using core::ReturnStatus;
using core::Visibility;
using core::VisibilityCounts;

core::Visibility naive_classify(ReturnStatus status, double range, double entry, double exit,
                                double margin) {
  if (status == ReturnStatus::kTooClose) return Visibility::kUnknown;
  if (status != ReturnStatus::kValid) return Visibility::kNoReturn;
  if (range < entry - margin) return Visibility::kOccluded;
  if (range > exit + margin) return Visibility::kFree;
  return Visibility::kOccupied;
}

}  // namespace

core::VisibilityCounts naive_in_box(const core::VisibilityQuery& q, const core::Box3& box,
                                    double margin, std::vector<std::size_t>& cells) {
  const auto& scan = q.scan();
  const Eigen::Vector3d lo = box.min.cast<double>();
  const Eigen::Vector3d hi = box.max.cast<double>();
  VisibilityCounts counts;
  cells.clear();
  for (int r = 0; r < scan.rings(); ++r) {
    for (int c = 0; c < scan.columns(); ++c) {
      const BeamRay ray = q.cell_ray(r, c);
      double near = 0.0;
      double far = std::numeric_limits<double>::infinity();
      bool hit = true;
      for (int k = 0; k < 3 && hit; ++k) {
        if (ray.direction[k] == 0.0) {
          hit = ray.origin[k] >= lo[k] && ray.origin[k] <= hi[k];
          continue;
        }
        const double t_lo = (lo[k] - ray.origin[k]) / ray.direction[k];
        const double t_hi = (hi[k] - ray.origin[k]) / ray.direction[k];
        near = std::max(near, std::min(t_lo, t_hi));
        far = std::min(far, std::max(t_lo, t_hi));
        hit = near <= far;
      }
      if (!hit) continue;
      const auto i = scan.index(r, c);
      cells.push_back(i);
      counts.add(naive_classify(scan.status(i), scan.range_m(i), near, far, margin));
    }
  }
  return counts;
}

}  // namespace ringtrack::testing
