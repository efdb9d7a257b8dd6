#pragma once
/// Foxglove's protobuf schemas (github.com/foxglove/foxglove-sdk, schemas/proto/foxglove) as an
/// embedded FileDescriptorSet, and encoders of their building blocks. The field numbers must
/// equal Foxglove's: viewers decode by the descriptor but recognise panels by the schema name.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "ringtrack/io/protobuf_writer.hpp"

namespace ringtrack::io::foxglove {

/// Schema names of the messages ringtrack writes.
inline constexpr std::string_view kPointCloud = "foxglove.PointCloud";
/// Boxes, arrows, texts and lines of the tracks.
inline constexpr std::string_view kSceneUpdate = "foxglove.SceneUpdate";
/// A transform between two frames.
inline constexpr std::string_view kFrameTransform = "foxglove.FrameTransform";

/// A FileDescriptorSet (binary protobuf) declaring google.protobuf.Timestamp/Duration and the
/// foxglove messages PointCloud, SceneUpdate (with every primitive) and FrameTransform: the
/// Schema data of each of those schemas (encoding "protobuf").
const std::vector<std::uint8_t>& descriptor_set();

/// Numeric types of foxglove.PackedElementField.
enum class NumericType : std::uint8_t {
  kUint8 = 1,
  kInt8 = 2,
  kUint16 = 3,
  kInt16 = 4,
  kUint32 = 5,
  kInt32 = 6,
  kFloat32 = 7,
  kFloat64 = 8,
};

/// An RGBA colour, components in [0, 1].
struct Color {
  double r{1}, g{1}, b{1}, a{1};
};

/// google.protobuf.Timestamp field from ns since the epoch (negative stamps floor to seconds).
void timestamp(ProtoWriter& w, std::uint32_t field, std::int64_t stamp_ns);
/// google.protobuf.Duration field.
void duration(ProtoWriter& w, std::uint32_t field, std::int64_t ns);
/// foxglove.Vector3 (or Point3: same fields) field.
void vector3(ProtoWriter& w, std::uint32_t field, const Eigen::Vector3d& v);
/// foxglove.Quaternion field.
void quaternion(ProtoWriter& w, std::uint32_t field, const Eigen::Quaterniond& q);
/// foxglove.Pose field.
void pose(ProtoWriter& w, std::uint32_t field, const Eigen::Vector3d& position,
          const Eigen::Quaterniond& orientation = Eigen::Quaterniond::Identity());
/// foxglove.Color field.
void color(ProtoWriter& w, std::uint32_t field, const Color& c);
/// foxglove.PackedElementField field (in PointCloud.fields, number 5).
void packed_field(ProtoWriter& w, std::uint32_t field, std::string_view name, std::uint32_t offset,
                  NumericType type);

}  // namespace ringtrack::io::foxglove
