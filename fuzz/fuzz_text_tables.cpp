// libFuzzer target: the text tables a user hands in, each reader on the whole input: poses (TUM
// with interpolation, KITTI with and without stamps), stamps files, objects.csv, tracks.csv and
// MOTChallenge files (ground truth and results). An input holding a line "%%" is also split
// there into objects.csv and tracks.csv for the cross-table stamp check.
#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include "fuzz_support.hpp"
#include "ringtrack/io/mot_tables.hpp"
#include "ringtrack/io/poses.hpp"
#include "ringtrack/io/text.hpp"

using namespace ringtrack;

namespace {

void poses(const std::string& text) {
  const auto path = fuzz::write_scratch("poses.txt", text);
  fuzz::expect_errors([&] {
    const io::Trajectory t = io::read_tum(path);
    if (t.empty()) return;
    // Interpolation at the ends and between samples (the midpoint may overflow: use halves).
    (void)t.at(t.start_ns());
    (void)t.at(t.start_ns() / 2 + t.end_ns() / 2);
    (void)t.at(t.end_ns());
  });
  fuzz::expect_errors([&] {
    const auto kitti = io::read_kitti_poses(path);
    std::vector<std::int64_t> stamps(kitti.size());
    for (std::size_t i = 0; i < stamps.size(); ++i)
      stamps[i] = static_cast<std::int64_t>(i) * 100'000'000;
    (void)io::read_kitti(path, stamps);
  });
  fuzz::expect_errors([&] { (void)io::read_stamps(path); });
}

void tables(const std::string& objects_text, const std::string& tracks_text) {
  std::vector<io::ObjectRow> objects;
  std::vector<io::TrackRow> tracks;
  bool have_objects = false, have_tracks = false;
  fuzz::expect_errors([&] {
    std::istringstream in(objects_text);
    objects = io::read_objects_csv(in, "objects.csv");
    have_objects = true;
  });
  fuzz::expect_errors([&] {
    std::istringstream in(tracks_text);
    tracks = io::read_tracks_csv(in, "tracks.csv");
    have_tracks = true;
  });
  if (have_objects && have_tracks) {
    fuzz::expect_errors(
        [&] { io::check_scan_stamps(objects, "objects.csv", tracks, "tracks.csv"); });
  }
}

void motchallenge(const std::string& text) {
  for (const bool ground_truth : {true, false}) {
    fuzz::expect_errors([&] {
      std::istringstream in(text);
      (void)io::read_motchallenge(in, "gt.txt", ground_truth);
    });
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  poses(text);
  const std::size_t split = text.find("\n%%\n");
  if (split == std::string::npos) {
    tables(text, text);
  } else {
    tables(text.substr(0, split + 1), text.substr(split + 4));
  }
  motchallenge(text);
  return 0;
}
