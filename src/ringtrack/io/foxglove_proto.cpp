#include "ringtrack/io/foxglove_proto.hpp"

#include <cmath>
#include <string>

namespace ringtrack::io::foxglove {
namespace {

// google/protobuf/descriptor.proto: FieldDescriptorProto.Type and .Label values.
enum Type : int { kDouble = 1, kInt64 = 3, kInt32 = 5, kFixed32 = 7, kBool = 8, kString = 9 };
enum : int { kMessage = 11, kBytes = 12, kEnum = 14 };
constexpr int kOptional = 1;
constexpr int kRepeated = 3;

struct FieldDef {
  const char* name;
  int number;
  int type;
  int label;
  const char* type_name;  // ".pkg.Message" for messages and enums, nullptr otherwise
};
struct EnumDef {
  const char* name;
  std::vector<std::pair<const char*, int>> values;
};
struct MessageDef {
  const char* name;
  std::vector<FieldDef> fields;
  std::vector<EnumDef> enums;
};

// Foxglove's schemas, field for field (schemas/proto/foxglove/*.proto of foxglove-sdk). Long
// because it is that table: one entry per message type, read against the .proto files.
const std::vector<MessageDef>& foxglove_messages() {
  static const std::vector<MessageDef> defs = {
      {"Vector3",
       {{"x", 1, kDouble, kOptional, nullptr},
        {"y", 2, kDouble, kOptional, nullptr},
        {"z", 3, kDouble, kOptional, nullptr}},
       {}},
      {"Point3",
       {{"x", 1, kDouble, kOptional, nullptr},
        {"y", 2, kDouble, kOptional, nullptr},
        {"z", 3, kDouble, kOptional, nullptr}},
       {}},
      {"Quaternion",
       {{"x", 1, kDouble, kOptional, nullptr},
        {"y", 2, kDouble, kOptional, nullptr},
        {"z", 3, kDouble, kOptional, nullptr},
        {"w", 4, kDouble, kOptional, nullptr}},
       {}},
      {"Color",
       {{"r", 1, kDouble, kOptional, nullptr},
        {"g", 2, kDouble, kOptional, nullptr},
        {"b", 3, kDouble, kOptional, nullptr},
        {"a", 4, kDouble, kOptional, nullptr}},
       {}},
      {"Pose",
       {{"position", 1, kMessage, kOptional, ".foxglove.Vector3"},
        {"orientation", 2, kMessage, kOptional, ".foxglove.Quaternion"}},
       {}},
      {"KeyValuePair",
       {{"key", 1, kString, kOptional, nullptr}, {"value", 2, kString, kOptional, nullptr}},
       {}},
      {"PackedElementField",
       {{"name", 1, kString, kOptional, nullptr},
        {"offset", 2, kFixed32, kOptional, nullptr},
        {"type", 3, kEnum, kOptional, ".foxglove.PackedElementField.NumericType"}},
       {{"NumericType",
         {{"UNKNOWN", 0},
          {"UINT8", 1},
          {"INT8", 2},
          {"UINT16", 3},
          {"INT16", 4},
          {"UINT32", 5},
          {"INT32", 6},
          {"FLOAT32", 7},
          {"FLOAT64", 8}}}}},
      {"PointCloud",
       {{"timestamp", 1, kMessage, kOptional, ".google.protobuf.Timestamp"},
        {"frame_id", 2, kString, kOptional, nullptr},
        {"pose", 3, kMessage, kOptional, ".foxglove.Pose"},
        {"point_stride", 4, kFixed32, kOptional, nullptr},
        {"fields", 5, kMessage, kRepeated, ".foxglove.PackedElementField"},
        {"data", 6, kBytes, kOptional, nullptr}},
       {}},
      {"FrameTransform",
       {{"timestamp", 1, kMessage, kOptional, ".google.protobuf.Timestamp"},
        {"parent_frame_id", 2, kString, kOptional, nullptr},
        {"child_frame_id", 3, kString, kOptional, nullptr},
        {"translation", 4, kMessage, kOptional, ".foxglove.Vector3"},
        {"rotation", 5, kMessage, kOptional, ".foxglove.Quaternion"}},
       {}},
      {"ArrowPrimitive",
       {{"pose", 1, kMessage, kOptional, ".foxglove.Pose"},
        {"shaft_length", 2, kDouble, kOptional, nullptr},
        {"shaft_diameter", 3, kDouble, kOptional, nullptr},
        {"head_length", 4, kDouble, kOptional, nullptr},
        {"head_diameter", 5, kDouble, kOptional, nullptr},
        {"color", 6, kMessage, kOptional, ".foxglove.Color"}},
       {}},
      {"CubePrimitive",
       {{"pose", 1, kMessage, kOptional, ".foxglove.Pose"},
        {"size", 2, kMessage, kOptional, ".foxglove.Vector3"},
        {"color", 3, kMessage, kOptional, ".foxglove.Color"}},
       {}},
      {"SpherePrimitive",
       {{"pose", 1, kMessage, kOptional, ".foxglove.Pose"},
        {"size", 2, kMessage, kOptional, ".foxglove.Vector3"},
        {"color", 3, kMessage, kOptional, ".foxglove.Color"}},
       {}},
      {"CylinderPrimitive",
       {{"pose", 1, kMessage, kOptional, ".foxglove.Pose"},
        {"size", 2, kMessage, kOptional, ".foxglove.Vector3"},
        {"bottom_scale", 3, kDouble, kOptional, nullptr},
        {"top_scale", 4, kDouble, kOptional, nullptr},
        {"color", 5, kMessage, kOptional, ".foxglove.Color"}},
       {}},
      {"LinePrimitive",
       {{"type", 1, kEnum, kOptional, ".foxglove.LinePrimitive.Type"},
        {"pose", 2, kMessage, kOptional, ".foxglove.Pose"},
        {"thickness", 3, kDouble, kOptional, nullptr},
        {"scale_invariant", 4, kBool, kOptional, nullptr},
        {"points", 5, kMessage, kRepeated, ".foxglove.Point3"},
        {"color", 6, kMessage, kOptional, ".foxglove.Color"},
        {"colors", 7, kMessage, kRepeated, ".foxglove.Color"},
        {"indices", 8, kFixed32, kRepeated, nullptr}},
       {{"Type", {{"LINE_STRIP", 0}, {"LINE_LOOP", 1}, {"LINE_LIST", 2}}}}},
      {"TriangleListPrimitive",
       {{"pose", 1, kMessage, kOptional, ".foxglove.Pose"},
        {"points", 2, kMessage, kRepeated, ".foxglove.Point3"},
        {"color", 3, kMessage, kOptional, ".foxglove.Color"},
        {"colors", 4, kMessage, kRepeated, ".foxglove.Color"},
        {"indices", 5, kFixed32, kRepeated, nullptr}},
       {}},
      {"TextPrimitive",
       {{"pose", 1, kMessage, kOptional, ".foxglove.Pose"},
        {"billboard", 2, kBool, kOptional, nullptr},
        {"font_size", 3, kDouble, kOptional, nullptr},
        {"scale_invariant", 4, kBool, kOptional, nullptr},
        {"color", 5, kMessage, kOptional, ".foxglove.Color"},
        {"text", 6, kString, kOptional, nullptr}},
       {}},
      {"ModelPrimitive",
       {{"pose", 1, kMessage, kOptional, ".foxglove.Pose"},
        {"scale", 2, kMessage, kOptional, ".foxglove.Vector3"},
        {"color", 3, kMessage, kOptional, ".foxglove.Color"},
        {"override_color", 4, kBool, kOptional, nullptr},
        {"url", 5, kString, kOptional, nullptr},
        {"media_type", 6, kString, kOptional, nullptr},
        {"data", 7, kBytes, kOptional, nullptr}},
       {}},
      {"SceneEntity",
       {{"timestamp", 1, kMessage, kOptional, ".google.protobuf.Timestamp"},
        {"frame_id", 2, kString, kOptional, nullptr},
        {"id", 3, kString, kOptional, nullptr},
        {"lifetime", 4, kMessage, kOptional, ".google.protobuf.Duration"},
        {"frame_locked", 5, kBool, kOptional, nullptr},
        {"metadata", 6, kMessage, kRepeated, ".foxglove.KeyValuePair"},
        {"arrows", 7, kMessage, kRepeated, ".foxglove.ArrowPrimitive"},
        {"cubes", 8, kMessage, kRepeated, ".foxglove.CubePrimitive"},
        {"spheres", 9, kMessage, kRepeated, ".foxglove.SpherePrimitive"},
        {"cylinders", 10, kMessage, kRepeated, ".foxglove.CylinderPrimitive"},
        {"lines", 11, kMessage, kRepeated, ".foxglove.LinePrimitive"},
        {"triangles", 12, kMessage, kRepeated, ".foxglove.TriangleListPrimitive"},
        {"texts", 13, kMessage, kRepeated, ".foxglove.TextPrimitive"},
        {"models", 14, kMessage, kRepeated, ".foxglove.ModelPrimitive"}},
       {}},
      {"SceneEntityDeletion",
       {{"timestamp", 1, kMessage, kOptional, ".google.protobuf.Timestamp"},
        {"type", 2, kEnum, kOptional, ".foxglove.SceneEntityDeletion.Type"},
        {"id", 3, kString, kOptional, nullptr}},
       {{"Type", {{"MATCHING_ID", 0}, {"ALL", 1}}}}},
      {"SceneUpdate",
       {{"deletions", 1, kMessage, kRepeated, ".foxglove.SceneEntityDeletion"},
        {"entities", 2, kMessage, kRepeated, ".foxglove.SceneEntity"}},
       {}},
  };
  return defs;
}

// DescriptorProto (name 1, field 2, enum_type 4) of one message.
void write_message_def(ProtoWriter& w, std::uint32_t field, const MessageDef& m) {
  const auto msg = w.begin(field);
  w.string(1, m.name);
  for (const auto& f : m.fields) {
    const auto fd = w.begin(2);  // FieldDescriptorProto
    w.string(1, f.name);
    w.varint(3, static_cast<std::uint64_t>(f.number));
    w.varint(4, static_cast<std::uint64_t>(f.label));
    w.varint(5, static_cast<std::uint64_t>(f.type));
    if (f.type_name != nullptr) w.string(6, f.type_name);
    w.string(10, f.name);  // json_name: the fields are snake_case in Foxglove's JSON too
    w.end(fd);
  }
  for (const auto& e : m.enums) {
    const auto ed = w.begin(4);  // EnumDescriptorProto
    w.string(1, e.name);
    for (const auto& [name, number] : e.values) {
      const auto vd = w.begin(2);  // EnumValueDescriptorProto
      w.string(1, name);
      w.varint(2, static_cast<std::uint64_t>(number));
      w.end(vd);
    }
    w.end(ed);
  }
  w.end(msg);
}

// FileDescriptorProto: name 1, package 2, dependency 3, message_type 4, syntax 12.
void write_file_descriptor(ProtoWriter& w, const char* name, const char* package,
                           const std::vector<const char*>& dependencies,
                           const std::vector<MessageDef>& messages) {
  const auto file = w.begin(1);  // FileDescriptorSet.file
  w.string(1, name);
  w.string(2, package);
  for (const char* d : dependencies) w.string(3, d);
  for (const auto& m : messages) write_message_def(w, 4, m);
  w.string(12, "proto3");
  w.end(file);
}

}  // namespace

const std::vector<std::uint8_t>& descriptor_set() {
  static const std::vector<std::uint8_t> set = [] {
    ProtoWriter w;
    const std::vector<FieldDef> seconds_nanos = {{"seconds", 1, kInt64, kOptional, nullptr},
                                                 {"nanos", 2, kInt32, kOptional, nullptr}};
    write_file_descriptor(w, "google/protobuf/timestamp.proto", "google.protobuf", {},
                          {{"Timestamp", seconds_nanos, {}}});
    write_file_descriptor(w, "google/protobuf/duration.proto", "google.protobuf", {},
                          {{"Duration", seconds_nanos, {}}});
    write_file_descriptor(w, "foxglove/ringtrack_schemas.proto", "foxglove",
                          {"google/protobuf/timestamp.proto", "google/protobuf/duration.proto"},
                          foxglove_messages());
    const auto bytes = w.bytes();
    return std::vector<std::uint8_t>(bytes.data(), bytes.data() + bytes.size());
  }();
  return set;
}

void timestamp(ProtoWriter& w, std::uint32_t field, std::int64_t stamp_ns) {
  std::int64_t seconds = stamp_ns / 1'000'000'000;
  std::int64_t nanos = stamp_ns % 1'000'000'000;
  if (nanos < 0) {  // Timestamp wants nanos in [0, 1e9)
    nanos += 1'000'000'000;
    --seconds;
  }
  const auto at = w.begin(field);
  w.varint_nonzero(1, static_cast<std::uint64_t>(seconds));
  w.varint_nonzero(2, static_cast<std::uint64_t>(nanos));
  w.end(at);
}

void duration(ProtoWriter& w, std::uint32_t field, std::int64_t ns) {
  const auto at = w.begin(field);
  w.varint_nonzero(1, static_cast<std::uint64_t>(ns / 1'000'000'000));
  w.varint_nonzero(2, static_cast<std::uint64_t>(ns % 1'000'000'000));
  w.end(at);
}

void vector3(ProtoWriter& w, std::uint32_t field, const Eigen::Vector3d& v) {
  const auto at = w.begin(field);
  w.double_field(1, v.x());
  w.double_field(2, v.y());
  w.double_field(3, v.z());
  w.end(at);
}

void quaternion(ProtoWriter& w, std::uint32_t field, const Eigen::Quaterniond& q) {
  const auto at = w.begin(field);
  w.double_field(1, q.x());
  w.double_field(2, q.y());
  w.double_field(3, q.z());
  w.double_field(4, q.w());
  w.end(at);
}

void pose(ProtoWriter& w, std::uint32_t field, const Eigen::Vector3d& position,
          const Eigen::Quaterniond& orientation) {
  const auto at = w.begin(field);
  vector3(w, 1, position);
  quaternion(w, 2, orientation);
  w.end(at);
}

void color(ProtoWriter& w, std::uint32_t field, const Color& c) {
  const auto at = w.begin(field);
  w.double_field(1, c.r);
  w.double_field(2, c.g);
  w.double_field(3, c.b);
  w.double_field(4, c.a);
  w.end(at);
}

void packed_field(ProtoWriter& w, std::uint32_t field, std::string_view name, std::uint32_t offset,
                  NumericType type) {
  const auto at = w.begin(field);
  w.string(1, name);
  w.fixed32(2, offset);
  w.varint(3, static_cast<std::uint64_t>(type));
  w.end(at);
}

}  // namespace ringtrack::io::foxglove
