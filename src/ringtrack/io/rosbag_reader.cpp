#include "ringtrack/io/rosbag_reader.hpp"

#include <fstream>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/mcap_bag_reader.hpp"
#include "ringtrack/io/paths.hpp"
#include "ringtrack/io/rosbag1_reader.hpp"
#include "ringtrack/io/rosbag2_reader.hpp"

namespace ringtrack::io {

namespace fs = std::filesystem;

RosMessageCursor::RosMessageCursor(std::span<const std::uint8_t> message,
                                   RosSerialization serialization, std::string where)
    : body_(message), serialization_(serialization), where_(std::move(where)) {
  if (serialization_ == RosSerialization::kCdr) {
    if (message.size() < 4)
      fail("message of " + std::to_string(message.size()) +
           " bytes is shorter than the CDR encapsulation header");
    // 0x00 0x00: plain CDR big endian, 0x00 0x01: little endian.
    if (message[0] != 0 || message[1] > 1) {
      fail("unsupported CDR encapsulation " + std::to_string(message[0]) + "," +
           std::to_string(message[1]) + " (expected plain CDR: 0,0 or 0,1)");
    }
    little_ = message[1] == 1;
    body_ = message.subspan(4);
    origin_ = 4;
  }
}

void RosMessageCursor::fail(const std::string& what) const {
  throw core::InputError(where_ + ": " + what + " (at byte " + std::to_string(origin_ + at_) + ")");
}

void RosMessageCursor::align(std::size_t n) {
  if (serialization_ == RosSerialization::kCdr) at_ = (at_ + n - 1) / n * n;
}

void RosMessageCursor::need(std::size_t n, const char* what) const {
  if (at_ > body_.size() || body_.size() - at_ < n) {
    fail(std::string("truncated: ") + what + " needs " + std::to_string(n) + " bytes, " +
         std::to_string(at_ > body_.size() ? 0 : body_.size() - at_) + " left");
  }
}

std::uint8_t RosMessageCursor::u8() {
  need(1, "a uint8");
  return body_[at_++];
}

std::uint32_t RosMessageCursor::u32() {
  align(4);
  need(4, "a uint32");
  const std::uint8_t* p = body_.data() + at_;
  at_ += 4;
  if (little_) {
    return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
           (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
  }
  return static_cast<std::uint32_t>(p[3]) | (static_cast<std::uint32_t>(p[2]) << 8) |
         (static_cast<std::uint32_t>(p[1]) << 16) | (static_cast<std::uint32_t>(p[0]) << 24);
}

std::span<const std::uint8_t> RosMessageCursor::bytes(std::size_t n) {
  need(n, "a byte array");
  const auto out = body_.subspan(at_, n);
  at_ += n;
  return out;
}

std::string RosMessageCursor::string() {
  const std::uint32_t n = u32();
  if (n > remaining()) {
    fail("string of " + std::to_string(n) + " bytes, " + std::to_string(remaining()) + " left");
  }
  const auto b = bytes(n);
  std::string s(reinterpret_cast<const char*>(b.data()), b.size());
  if (serialization_ == RosSerialization::kCdr && !s.empty() && s.back() == '\0') s.pop_back();
  return s;
}

std::uint32_t RosMessageCursor::sequence_length(std::size_t min_element_bytes, const char* what) {
  const std::uint32_t n = u32();
  if (min_element_bytes > 0 && n > remaining() / min_element_bytes) {
    fail(std::string(what) + ": claims " + std::to_string(n) + " elements of at least " +
         std::to_string(min_element_bytes) + " bytes, " + std::to_string(remaining()) +
         " bytes left");
  }
  return n;
}

std::int64_t RosMessageCursor::time_ns() {
  const std::uint32_t sec = u32();
  const std::uint32_t nsec = u32();
  const std::int64_t s = serialization_ == RosSerialization::kCdr
                             ? static_cast<std::int64_t>(static_cast<std::int32_t>(sec))
                             : static_cast<std::int64_t>(sec);
  return s * 1'000'000'000 + nsec;
}

std::int64_t RosMessageCursor::header_stamp_ns(std::string* frame_id) {
  if (serialization_ == RosSerialization::kRos1) u32();  // seq
  const std::int64_t stamp = time_ns();
  std::string frame = string();
  if (frame_id != nullptr) *frame_id = std::move(frame);
  return stamp;
}

std::string normalize_ros_type(std::string_view type) {
  const auto at = type.find("/msg/");
  if (at == std::string_view::npos) return std::string(type);
  return std::string(type.substr(0, at)) + "/" + std::string(type.substr(at + 5));
}

bool is_rosbag1_file(const fs::path& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return false;
  std::ifstream in(path, std::ios::binary);
  char magic[9] = {};
  in.read(magic, sizeof magic);
  return in.gcount() == sizeof magic && std::string_view(magic, sizeof magic) == "#ROSBAG V";
}

bool is_rosbag2_path(const fs::path& path) {
  if (is_mcap_bag(path)) return true;
  if (is_folder(path)) {
    if (is_file(path / "metadata.yaml")) return true;
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(path, ec)) {
      if (entry.path().extension() == ".db3") return true;
    }
    return false;
  }
  return path.extension() == ".db3";
}

std::unique_ptr<RosbagReader> open_rosbag(const fs::path& path) {
  if (is_rosbag1_file(path)) return std::make_unique<Rosbag1Reader>(path);
  if (is_mcap_bag(path)) return std::make_unique<McapBagReader>(path);
  if (is_rosbag2_path(path)) return std::make_unique<Rosbag2Reader>(path);
  if (path.extension() == ".bag") return std::make_unique<Rosbag1Reader>(path);  // names the error
  throw core::InputError(path.string() +
                         ": not a ROS bag (expected a ROS 1 .bag file, a rosbag2 folder with "
                         "metadata.yaml, a .db3 file or an MCAP file)");
}

}  // namespace ringtrack::io
