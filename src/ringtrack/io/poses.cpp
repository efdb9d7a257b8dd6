#include "ringtrack/io/poses.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/output_file.hpp"
#include "ringtrack/io/text.hpp"

namespace ringtrack::io {
namespace {

// Pose files are written with a few decimals; a larger error means a wrong column order or junk.
constexpr double kUnitTolerance = 0.01;
constexpr double kRotationTolerance = 1e-3;

std::string where(const std::filesystem::path& path, std::size_t line) {
  return path.string() + ":" + std::to_string(line);
}

std::vector<double> parse_numbers(const std::vector<std::string_view>& tokens, std::size_t first,
                                  const char* const* names, const std::string& at) {
  std::vector<double> out;
  for (std::size_t k = first; k < tokens.size(); ++k) {
    const auto v = parse_double(tokens[k]);
    if (!v) {
      throw core::InputError(at + ": " + names[k] + " is not a number: '" + std::string(tokens[k]) +
                             "'");
    }
    if (!std::isfinite(*v)) {
      throw core::InputError(at + ": " + names[k] + " is " + std::string(tokens[k]) +
                             ", expected a finite number");
    }
    out.push_back(*v);
  }
  return out;
}

}  // namespace

Trajectory::Trajectory(std::vector<core::Pose> poses, std::string source)
    : poses_(std::move(poses)), source_(std::move(source)) {
  for (std::size_t i = 0; i < poses_.size(); ++i) {
    auto& p = poses_[i];
    const std::string at =
        source_ + ": pose " + std::to_string(i) + " at " + format_stamp(p.stamp_ns);
    if (!p.translation.allFinite() || !p.rotation.coeffs().allFinite()) {
      throw core::InputError(at + ": translation or rotation is not finite");
    }
    const double norm = p.rotation.norm();
    if (std::abs(norm - 1.0) > kUnitTolerance) {
      throw core::InputError(at + ": rotation quaternion has norm " + std::to_string(norm) +
                             ", expected 1");
    }
    p.rotation.normalize();
    if (i > 0 && p.stamp_ns <= poses_[i - 1].stamp_ns) {
      throw core::InputError(at + ": stamp does not increase (previous " +
                             format_stamp(poses_[i - 1].stamp_ns) + ")");
    }
  }
}

bool Trajectory::covers(std::int64_t stamp_ns) const {
  return !poses_.empty() && stamp_ns >= start_ns() && stamp_ns <= end_ns();
}

core::Pose Trajectory::at(std::int64_t stamp_ns) const {
  if (!covers(stamp_ns)) {
    throw core::InputError(source_ + ": no pose for stamp " + format_stamp(stamp_ns) +
                           (poses_.empty() ? std::string(" (no poses)")
                                           : " (poses cover " + format_stamp(start_ns()) + " to " +
                                                 format_stamp(end_ns()) + ")"));
  }
  const auto after =
      std::upper_bound(poses_.begin(), poses_.end(), stamp_ns,
                       [](std::int64_t t, const core::Pose& p) { return t < p.stamp_ns; });
  const core::Pose& a = *(after - 1);
  if (a.stamp_ns == stamp_ns || after == poses_.end()) return a;
  const core::Pose& b = *after;
  const double t =
      static_cast<double>(stamp_ns - a.stamp_ns) / static_cast<double>(b.stamp_ns - a.stamp_ns);
  core::Pose out = core::Pose::interpolate(a, b, t);
  out.stamp_ns = stamp_ns;
  out.rotation.normalize();
  return out;
}

Trajectory read_tum(const std::filesystem::path& path) {
  static const char* const kNames[] = {"t", "x", "y", "z", "qx", "qy", "qz", "qw"};
  const auto lines = read_lines(path);
  std::vector<core::Pose> poses;
  for (std::size_t n = 0; n < lines.size(); ++n) {
    const auto tokens = split_tokens(lines[n], true);
    if (tokens.empty() || tokens.front().front() == '#') continue;
    const std::string at = where(path, n + 1);
    if (tokens.size() != 8) {
      throw core::InputError(at + ": expected 8 values (t x y z qx qy qz qw), got " +
                             std::to_string(tokens.size()));
    }
    const auto stamp = parse_stamp_ns(tokens[0]);
    if (!stamp) {
      throw core::InputError(at + ": t is not a stamp in seconds: '" + std::string(tokens[0]) +
                             "'");
    }
    const auto v = parse_numbers(tokens, 1, kNames, at);
    core::Pose p;
    p.stamp_ns = *stamp;
    p.translation = Eigen::Vector3d(v[0], v[1], v[2]);
    p.rotation = Eigen::Quaterniond(v[6], v[3], v[4], v[5]);  // Eigen takes w first
    const double norm = p.rotation.norm();
    if (std::abs(norm - 1.0) > kUnitTolerance) {
      throw core::InputError(at + ": quaternion (qx qy qz qw) has norm " + std::to_string(norm) +
                             ", expected 1");
    }
    if (!poses.empty() && p.stamp_ns <= poses.back().stamp_ns) {
      throw core::InputError(at + ": stamp " + format_stamp(p.stamp_ns) +
                             " does not increase (previous " + format_stamp(poses.back().stamp_ns) +
                             ")");
    }
    poses.push_back(p);
  }
  return Trajectory(std::move(poses), path.string());
}

std::vector<core::Pose> read_kitti_poses(const std::filesystem::path& path) {
  static const char* const kNames[] = {"r11", "r12", "r13", "tx",  "r21", "r22",
                                       "r23", "ty",  "r31", "r32", "r33", "tz"};
  const auto lines = read_lines(path);
  std::vector<core::Pose> poses;
  for (std::size_t n = 0; n < lines.size(); ++n) {
    const auto tokens = split_tokens(lines[n]);
    if (tokens.empty() || tokens.front().front() == '#') continue;
    const std::string at = where(path, n + 1);
    if (tokens.size() != 12) {
      throw core::InputError(at + ": expected 12 values (row-major 3x4 matrix), got " +
                             std::to_string(tokens.size()));
    }
    const auto v = parse_numbers(tokens, 0, kNames, at);
    Eigen::Matrix3d r;
    r << v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10];
    const double error = (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    if (error > kRotationTolerance || r.determinant() < 0.0) {
      throw core::InputError(
          at + ": the 3x3 part is not a rotation matrix (|R^T R - I| = " + std::to_string(error) +
          ", det = " + std::to_string(r.determinant()) + ")");
    }
    core::Pose p;
    p.translation = Eigen::Vector3d(v[3], v[7], v[11]);
    p.rotation = Eigen::Quaterniond(r).normalized();
    poses.push_back(p);
  }
  return poses;
}

Trajectory read_kitti(const std::filesystem::path& path, std::span<const std::int64_t> stamps_ns) {
  auto poses = read_kitti_poses(path);
  if (poses.size() != stamps_ns.size()) {
    throw core::InputError(path.string() + ": " + std::to_string(poses.size()) +
                           " KITTI poses for " + std::to_string(stamps_ns.size()) +
                           " stamps; expected one pose per stamp");
  }
  for (std::size_t i = 0; i < poses.size(); ++i) poses[i].stamp_ns = stamps_ns[i];
  return Trajectory(std::move(poses), path.string());
}

std::string format_tum_line(const core::Pose& pose) {
  const Eigen::Quaterniond q = pose.rotation.normalized();
  std::string out = format_stamp(pose.stamp_ns);
  for (int k = 0; k < 3; ++k) {
    out += ' ';
    append_fixed(out, pose.translation[k], 6);
  }
  for (double c : {q.x(), q.y(), q.z(), q.w()}) {
    out += ' ';
    append_fixed(out, c, 9);
  }
  return out;
}

void write_tum(const std::filesystem::path& path, std::span<const core::Pose> poses) {
  std::string text = "# t x y z qx qy qz qw\n";
  for (const auto& p : poses) {
    text += format_tum_line(p);
    text += '\n';
  }
  write_file(path, text);
}

}  // namespace ringtrack::io
