// Prints the tracks of a recording, scan by scan: the library's shortest complete use.
//
//   print_tracks RECORDING [POSES.tum]
//
// RECORDING is anything io::open_source opens: a .pcap, a ROS 1 or ROS 2 bag, an MCAP file,
// a sequence folder or a folder of PCD files, or udp://0.0.0.0:2368. With a TUM pose file each
// scan is processed at the sensor's pose at its stamp; without, at the pose the input carries (a
// sequence folder's poses.txt), else the built-in LiDAR odometry estimates the poses, as
// `ringtrack run` does. `ringtrack run` adds motion compensation from the
// poses, skipping undecodable scans and the output files (apps/ringtrack/cmd_run.cpp).

#include <cstdio>
#include <exception>
#include <memory>
#include <optional>

#include "ringtrack/core/config.hpp"
#include "ringtrack/io/poses.hpp"
#include "ringtrack/io/scan_source.hpp"
#include "ringtrack/pipeline/pipeline.hpp"

int main(int argc, char** argv) {
  using namespace ringtrack;
  if (argc < 2 || argc > 3) {
    std::fprintf(stderr, "usage: print_tracks RECORDING [POSES.tum]\n");
    return 2;
  }
  try {
    // The defaults guess the format and the sensor; ringtrack run's --format, --model, --topic,
    // --calibration etc. are these options' fields.
    const io::ScanSourceOptions options;
    const std::unique_ptr<io::ScanSource> source = io::open_source(argv[1], options);
    std::optional<io::Trajectory> poses;
    if (argc == 3) poses = io::read_tum(argv[2]);
    // Built at the first scan: a recording names its sensor model only once it is decoded.
    std::optional<pipeline::Pipeline> pipeline;
    while (std::optional<core::OrganizedScan> scan = source->next()) {
      if (!pipeline) pipeline.emplace(core::Config{}, source->model());
      // The pose file's pose at the scan's stamp, else the one the input carries (a sequence
      // folder's poses.txt), else the odometry's estimate.
      std::optional<core::Pose> pose = source->pose();
      if (poses) pose = poses->at(scan->stamp_ns);
      const pipeline::FrameResult& frame =
          pose ? pipeline->process(*scan, *pose) : pipeline->process_with_odometry(*scan);
      if (frame.skipped) {
        std::printf("scan skipped: %s\n", frame.skip_reason.c_str());
        continue;
      }
      std::printf("scan at %.3f s: %zu detections\n", 1e-9 * static_cast<double>(frame.stamp_ns),
                  frame.detections.size());
      for (const tracking::Hypothesis& h : frame.hypotheses) {
        if (!h.reported) continue;  // the tracks `ringtrack run` lists in tracks.csv
        // The pipeline works in a local frame (float precision); its origin makes it the world's.
        const Eigen::Vector3d p = h.reported_position + frame.origin;
        std::printf("  track %llu at (%.2f, %.2f, %.2f) m, %.2f m/s%s%s\n",
                    static_cast<unsigned long long>(h.id), p.x(), p.y(), p.z(),
                    h.velocity_mps.norm(), h.dynamic ? ", moving" : "", h.person ? ", person" : "");
      }
    }
  } catch (const std::exception& e) {
    // The library's errors name the file, offset or key and what was expected.
    std::fprintf(stderr, "print_tracks: %s\n", e.what());
    return 1;
  }
  return 0;
}
