#include "support/nearest_distances.hpp"

#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace ringtrack::test {

std::vector<Eigen::Vector3d> read_pcd_xyz(const std::string& path) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) return {};
  std::string bytes(static_cast<std::size_t>(size), '\0');
  std::ifstream in(path, std::ios::binary);
  in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  const std::string marker = "DATA binary\n";
  const auto at = bytes.find(marker);
  if (at == std::string::npos) return {};
  // Record size from the SIZE and COUNT lines.
  std::size_t record = 0;
  std::vector<std::size_t> sizes;
  std::vector<std::size_t> counts;
  std::istringstream header(bytes.substr(0, at));
  std::string line;
  std::string fields;
  while (std::getline(header, line)) {
    std::istringstream ls(line);
    std::string word;
    ls >> word;
    if (word == "FIELDS") fields = line;
    if (word == "SIZE") {
      for (std::size_t v = 0; ls >> v;) sizes.push_back(v);
    }
    if (word == "COUNT") {
      for (std::size_t v = 0; ls >> v;) counts.push_back(v);
    }
  }
  if (fields.rfind("FIELDS x y z", 0) != 0 || sizes.size() < 3 || sizes[0] != 4) return {};
  for (std::size_t i = 0; i < sizes.size(); ++i) {
    record += sizes[i] * (i < counts.size() ? counts[i] : 1);
  }
  const std::size_t begin = at + marker.size();
  const std::size_t n = (bytes.size() - begin) / record;
  std::vector<Eigen::Vector3d> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    float xyz[3];
    std::memcpy(xyz, bytes.data() + begin + i * record, sizeof xyz);
    out[i] = Eigen::Vector3d(xyz[0], xyz[1], xyz[2]);
  }
  return out;
}

}  // namespace ringtrack::test
