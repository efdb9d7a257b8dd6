#include "ringtrack/experiment/recorded_sequence.hpp"

#include <algorithm>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/mot_tables.hpp"
#include "ringtrack/io/sequence.hpp"
#include "ringtrack/pipeline/deskew.hpp"

namespace ringtrack::experiment {
namespace {

bool same_pose(const core::Pose& a, const core::Pose& b) {
  return a.translation == b.translation && a.rotation.coeffs() == b.rotation.coeffs();
}

}  // namespace

RecordedSequence::RecordedSequence(const std::filesystem::path& folder) {
  const io::SequenceReader reader(folder);
  name_ = std::filesystem::absolute(folder).lexically_normal().filename().string();
  if (name_.empty()) name_ = std::filesystem::absolute(folder).parent_path().filename().string();
  if (reader.size() == 0) throw core::InputError(folder.string() + ": no scans found");
  const auto objects = reader.objects_csv();
  if (!objects) {
    throw core::InputError(folder.string() +
                           ": no objects.csv: tuning and scoring need the sequence's ground truth");
  }
  for (const io::ObjectRow& r : io::read_objects_csv(*objects)) {
    ground_truth_.push_back({static_cast<std::int64_t>(r.scan), static_cast<std::int64_t>(r.id),
                             r.class_name, static_cast<std::int64_t>(r.points), r.centroid,
                             r.true_center});
  }
  model_ = reader.sensor();
  for (std::size_t k = 1; k < reader.size(); ++k) {
    moving_ = moving_ || !same_pose(reader.pose(0), reader.pose(k));
  }
  // `ringtrack run`'s rule: a sequence folder with poses is deskewed with this and the next
  // scan's pose (the last scan extrapolates from the one before).
  const bool deskew = reader.has_poses() && reader.is_sequence() && reader.size() >= 2;
  for (std::size_t k = 0; k < reader.size(); ++k) {
    io::SequenceScan s = reader.read(k);
    core::Pose pose = s.pose;
    const auto& stamps = s.scan.column_stamp_ns;
    const auto [first, last] = std::minmax_element(stamps.begin(), stamps.end());
    const bool timed = !stamps.empty() && *last > *first;
    if (deskew && timed) {
      const std::size_t a = k + 1 < reader.size() ? k : k - 1;
      pose = pipeline::deskew_scan(s.scan, reader.pose(a), reader.pose(a + 1));
    }
    scans_.push_back(std::move(s.scan));
    poses_.push_back(pose);
  }
}

std::size_t RecordedSequence::memory_bytes() const {
  std::size_t bytes = 0;
  for (const core::OrganizedScan& s : scans_) {
    bytes += s.size() * (5 * sizeof(float) + sizeof(core::ReturnStatus)) +
             s.columns() * (sizeof(double) + sizeof(std::int64_t));
  }
  return bytes;
}

}  // namespace ringtrack::experiment
