#include "ringtrack/core/config.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <sstream>
#include <utility>

#include "ringtrack/core/error.hpp"

namespace ringtrack::core {
namespace {

// One configurable value: how to print it, how to parse it (with range check) and its meaning.
struct Field {
  std::string section;
  std::string name;
  std::string description;
  std::function<std::string()> get;
  std::function<void(const std::string& text, const std::string& where)> set;
};

std::string format_double(double v) {
  std::ostringstream os;
  os.precision(std::numeric_limits<double>::max_digits10);
  os << v;
  // Shortest text that reads back to the same double, for readable dumps.
  for (int p = 1; p <= std::numeric_limits<double>::max_digits10; ++p) {
    std::ostringstream s;
    s.precision(p);
    s << v;
    if (std::stod(s.str()) == v) return s.str();
  }
  return os.str();
}

double parse_double(const std::string& text, const std::string& where) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(v)) {
    throw ConfigError(where + ": expected a finite number, got '" + text + "'");
  }
  return v;
}

// Collects the fields of every section; the single place that lists the configuration schema.
class Schema {
 public:
  explicit Schema(Config& c) { build(c); }
  [[nodiscard]] const std::vector<Field>& fields() const { return fields_; }
  [[nodiscard]] const Field* find(const std::string& section, const std::string& name) const {
    for (const auto& f : fields_) {
      if (f.section == section && f.name == name) return &f;
    }
    return nullptr;
  }
  [[nodiscard]] bool has_section(const std::string& section) const {
    for (const auto& f : fields_) {
      if (f.section == section) return true;
    }
    return false;
  }

 private:
  void number(const char* name, double& v, double lo, double hi, const std::string& doc) {
    add(
        name, doc + " [" + format_double(lo) + ", " + format_double(hi) + "]",
        [&v] { return format_double(v); },
        [&v, lo, hi](const std::string& text, const std::string& where) {
          const double x = parse_double(text, where);
          if (x < lo || x > hi) {
            throw ConfigError(where + ": " + text + " is out of range, expected " +
                              format_double(lo) + " to " + format_double(hi));
          }
          v = x;
        });
  }
  void integer(const char* name, int& v, int lo, int hi, const std::string& doc) {
    add(
        name, doc + " [" + std::to_string(lo) + ", " + std::to_string(hi) + "]",
        [&v] { return std::to_string(v); },
        [&v, lo, hi](const std::string& text, const std::string& where) {
          const double x = parse_double(text, where);
          if (x != std::floor(x))
            throw ConfigError(where + ": expected an integer, got '" + text + "'");
          if (x < lo || x > hi) {
            throw ConfigError(where + ": " + text + " is out of range, expected " +
                              std::to_string(lo) + " to " + std::to_string(hi));
          }
          v = static_cast<int>(x);
        });
  }
  void boolean(const char* name, bool& v, const std::string& doc) {
    add(
        name, doc + " {true | false}", [&v] { return std::string(v ? "true" : "false"); },
        [&v](const std::string& text, const std::string& where) {
          if (text == "true") {
            v = true;
          } else if (text == "false") {
            v = false;
          } else {
            throw ConfigError(where + ": '" + text + "' is not one of true | false");
          }
        });
  }
  template <class E>
  void choice(const char* name, E& v, std::vector<std::pair<std::string, E>> names,
              const std::string& doc) {
    std::string allowed;
    for (const auto& [n, e] : names) allowed += (allowed.empty() ? "" : " | ") + n;
    add(
        name, doc + " {" + allowed + "}",
        [&v, names] {
          for (const auto& [n, e] : names) {
            if (e == v) return n;
          }
          return std::string("?");
        },
        [&v, names, allowed](const std::string& text, const std::string& where) {
          for (const auto& [n, e] : names) {
            if (n == text) {
              v = e;
              return;
            }
          }
          throw ConfigError(where + ": '" + text + "' is not one of " + allowed);
        });
  }
  void add(const char* name, std::string doc, std::function<std::string()> get,
           std::function<void(const std::string&, const std::string&)> set) {
    fields_.push_back({section_, name, std::move(doc), std::move(get), std::move(set)});
  }

  // Long because it is the schema: one registration per key, section by section in the order
  // `dump-config` prints them, each with its range and doc beside the key it checks.
  void build(Config& c) {
    auto& s = c.segmentation;
    section_ = "segmentation";
    number("min_width_m", s.min_width_m, 0.0, 10.0,
           "narrowest object width (m); the noise median removes narrower groups");
    number("max_width_m", s.max_width_m, 0.01, 20.0,
           "widest object width (m); the background median removes narrower groups, wider ones are "
           "background");
    integer("max_kernel_radius", s.max_kernel_radius, 1, 100000,
            "cap on a median window's half width (columns); also capped at half a ring");
    number("invalid_range_m", s.invalid_range_m, 1.0, 1e6,
           "range given to invalid returns (m) so neighbours still see background; must exceed the "
           "sensor's max range");
    number("delta_min_m", s.delta_min_m, -1e6, 1e6,
           "certainty is 0 below this background-minus-noise median difference (m)");
    number("delta_low_m", s.delta_low_m, -1e6, 1e6,
           "certainty rises linearly to 1 at this difference (m)");
    number("delta_high_m", s.delta_high_m, -1e6, 1e6,
           "certainty stays 1 up to this difference (m)");
    number("delta_max_m", s.delta_max_m, -1e6, 1e6,
           "certainty falls linearly to 0 at this difference (m)");
    number("certainty_threshold", s.certainty_threshold, 1e-6, 1.0,
           "a point is a segment point when its certainty is at least this (0 would make every "
           "point one)");

    auto& d = c.detection;
    section_ = "detection";
    integer(
        "neighbor_radius", d.neighbor_radius, 1, 50,
        "region growing joins segment points within this Manhattan distance on the grid (cells)");
    choice(
        "join_rule", d.join_rule,
        {{"range_difference", JoinRule::kRangeDifference}, {"euclidean", JoinRule::kEuclidean}},
        "what must stay below join_distance_m for two neighbours to join: their range difference "
        "(authors' code, robust to the sparse vertical spacing far away) or their 3-D distance "
        "(the paper)");
    number("join_distance_m", d.join_distance_m, 0.0, 100.0, "theta of region growing (m)");
    integer("min_cluster_points", d.min_cluster_points, 1, 100000, "smaller clusters are dropped");
    integer("relaxed_min_cluster_points", d.relaxed_min_cluster_points, 1, 1000000,
            "a cluster smaller than min_cluster_points but with at least this many points is "
            "kept as a relaxed detection when it lies near a predicted track (it confirms, never "
            "starts, a track); >= min_cluster_points disables this");
    integer("sparse_min_points", d.sparse_min_points, 1, 1000000,
            "a cluster smaller than min_cluster_points but with at least this many points is "
            "kept as a sparse detection, which may start a track, when every point lies at least "
            "background_margin_m in front of the background a static sensor has learned (section "
            "background: far people hit by one or two beams); >= min_cluster_points disables "
            "this");
    number("background_margin_m", d.background_margin_m, 0.0, 1000.0,
           "a point lies in front of the learned background when its range is at least this "
           "much shorter (m)");
    number("min_height_m", d.min_height_m, 0.0, 100.0,
           "object model: smallest vertical extent (m); not applied to clusters touching the top "
           "or bottom ring");
    number("max_height_m", d.max_height_m, 0.0, 100.0, "object model: largest vertical extent (m)");
    number("min_height_ring_gap_deg", d.min_height_ring_gap_deg, 0.0, 45.0,
           "the minimum-height test adds mean range * tan(this) to a cluster's extent, as rings "
           "this far apart see an object of height h as h minus up to two gaps (the sensor's "
           "ring spacing in degrees, VLP-16: 2; 0 tests the bare extent)");
    number("max_diagonal_m", d.max_diagonal_m, 0.0, 100.0,
           "object model: largest horizontal box diagonal (m)");
    number("max_altitude_m", d.max_altitude_m, -1e6, 1e6,
           "object model: largest height of a cluster's lowest point above the ground, taken as "
           "sensor_height_m below the first scan's sensor (m; not the world frame's z: poses "
           "from GNSS or a georeferenced map may be hundreds of metres up)");
    number("sensor_height_m", d.sensor_height_m, -1e4, 1e4,
           "height of the sensor above the ground at the first scan (m): where max_altitude_m "
           "counts from (the built-in scenarios: 2.5; a drone's take-off mount, a car roof: ~2)");
    number("relaxed_max_diagonal_m", d.relaxed_max_diagonal_m, 0.0, 100.0,
           "relaxed model (near predicted tracks, no minimum height; max height and altitude still "
           "apply): largest horizontal diagonal (m)");
    number("relaxed_radius_m", d.relaxed_radius_m, 0.0, 100.0,
           "a cluster whose centroid lies this close (horizontally) to a predicted track position "
           "may use the relaxed model (m)");
    number("min_position_stddev_m", d.min_position_stddev_m, 1e-6, 10.0,
           "floor on each axis of a detection's position standard deviation (m)");
    number("split_min_width_m", d.split_min_width_m, 0.0, 100.0,
           "a cluster whose extent along its principal horizontal axis exceeds this is split at "
           "the deepest density valley between two modes (people side by side), recursively; each "
           "part meets the object model on its own (m; 0 disables splitting)");
    number("split_bin_m", d.split_bin_m, 0.01, 10.0,
           "width of the split's sliding window along the principal axis (m), moved by a quarter "
           "of it over the points' coverage profile (each point spread over its column's "
           "footprint, so uniformly sampled surfaces have a flat profile)");
    number("split_valley_ratio", d.split_valley_ratio, 0.0, 0.99,
           "a valley window splits a cluster when its coverage is at most this fraction of the "
           "smaller of the highest windows on either side");
    number("complete_range_m", d.complete_range_m, 0.0, 10.0,
           "completion: a cell of the ring above or below a detection's cell (same column or "
           "one beside it) joins the detection when its range differs by at most this (m; the "
           "legs the segmentation left where the ground behind them gave no range jump); 0 "
           "disables");
    number("complete_margin_m", d.complete_margin_m, 0.0, 10.0,
           "completion: joining cells must lie inside the detection's box grown by this "
           "horizontally and above its top (m)");

    auto& t = c.tracking;
    section_ = "tracking";
    choice("cost", t.cost,
           {{"bhattacharyya", AssociationCost::kBhattacharyya},
            {"mahalanobis", AssociationCost::kMahalanobis},
            {"euclidean", AssociationCost::kEuclidean}},
           "assignment cost between a predicted hypothesis and a detection: Bhattacharyya "
           "distance of the two position distributions (the paper), Mahalanobis distance under "
           "the innovation covariance, or Euclidean distance");
    number("gate_bhattacharyya", t.gate_bhattacharyya, 1e-6, 1e6,
           "cost = bhattacharyya: pairs above this distance are forbidden; an unpaired "
           "hypothesis or detection costs this much");
    number("gate_mahalanobis", t.gate_mahalanobis, 1e-6, 1e6,
           "cost = mahalanobis: pairs above this distance (standard deviations) are forbidden");
    number("gate_euclidean_m", t.gate_euclidean_m, 1e-6, 1e6,
           "cost = euclidean: pairs farther apart than this (m) are forbidden");
    number("process_noise", t.process_noise, 1e-9, 1e6,
           "spectral density q of the white acceleration driving the constant-velocity model "
           "(m^2/s^3)");
    choice("vertical_motion", t.vertical_motion,
           {{"constant_position", VerticalMotion::kConstantPosition},
            {"constant_velocity", VerticalMotion::kConstantVelocity}},
           "height model of a hypothesis: constant_position holds the vertical velocity at zero "
           "(people, ground robots: the centroid's height jumps with the rings that hit them), "
           "constant_velocity treats z like x and y (drones)");
    number("vertical_position_noise", t.vertical_position_noise, 0.0, 1e6,
           "vertical_motion = constant_position: the height is a random walk of this density "
           "(m^2/s), so it follows the rings that hit the object without a velocity to drift on");
    number("initial_velocity_stddev_mps", t.initial_velocity_stddev_mps, 1e-6, 1e3,
           "standard deviation of a new hypothesis' velocity (m/s); its mean is zero");
    number("measurement_covariance_scale", t.measurement_covariance_scale, 1e-6, 1e6,
           "association: a detection's position uncertainty in the assignment cost is its point "
           "covariance times this (the object's extent, so a partial view still pairs)");
    number("centroid_noise_m", t.centroid_noise_m, 0.0, 10.0,
           "Kalman update: the measurement noise of a detection's centroid is its standard error "
           "(point covariance / points) plus this standard deviation per axis (m: limb swing, "
           "partial views); 0 = update with the association covariance instead");
    choice("reported_position", t.reported_position,
           {{"measured", ReportedPosition::kMeasured}, {"filtered", ReportedPosition::kFiltered}},
           "position a hypothesis reports in a scan that measured it: measured = the centroid of "
           "its detection (where the scan shows the object), filtered = the Kalman estimate "
           "(smoother, lags a turning walker); a missed hypothesis always reports the filter's "
           "prediction");
    number("few_point_stddev_m", t.few_point_stddev_m, 0.0, 100.0,
           "association: a detection of one or two points (a far person's sparse or relaxed "
           "cluster may be any part of the body) has at least this horizontal standard deviation "
           "(m)");
    number("reassociate_distance_m", t.reassociate_distance_m, 0.0, 100.0,
           "after the gated assignment, hypotheses and detections it left unpaired are paired "
           "greedily when this close horizontally (m): the Bhattacharyya gate also compares "
           "spreads and rejected a coasted track's own one-point detections; 0 disables");
    number("delete_eigenvalue_m2", t.delete_eigenvalue_m2, 1e-6, 1e6,
           "a hypothesis is deleted once an eigenvalue of its position covariance exceeds this "
           "(m^2); docs/tracking.md converts it to missed scans");
    number("merge_distance_m", t.merge_distance_m, 0.0, 100.0,
           "a younger hypothesis closer than this (horizontally, with overlapping heights) to an "
           "older one is deleted (m)");
    number("few_point_merge_distance_m", t.few_point_merge_distance_m, 0.0, 100.0,
           "a younger hypothesis is deleted this close (horizontally, with overlapping heights) "
           "to an older one when both were last measured by one or two points (a far person's "
           "hits fall anywhere on the body; two tracks on one such person took its hits in "
           "turns); never less than merge_distance_m (m)");
    number("min_speed_kmh", t.min_speed_kmh, 0.0, 1e4,
           "speeds up to this are reported as zero (km/h); the filter keeps its estimate");
    number("max_speed_kmh", t.max_speed_kmh, 1e-6, 1e4,
           "speeds are capped at this (km/h), in the filter state and in the report");
    number("dynamic_min_distance_m", t.dynamic_min_distance_m, 0.0, 100.0,
           "a hypothesis turns dynamic when its footprint no longer intersects its initial "
           "footprint and its position has moved at least this far (m)");
    integer("dynamic_confirm_scans", t.dynamic_confirm_scans, 1, 1000000,
            "the footprint and distance test must hold in this many consecutive scans with a "
            "strict (not relaxed) detection before a hypothesis turns dynamic");
    number("dynamic_streak_min_m", t.dynamic_streak_min_m, 0.0, 100.0,
           "box test: the measured centre must also cover this much (horizontally) between the "
           "first and the last scan of that streak, within 3 x dynamic_confirm_scans scans, "
           "else the streak starts over (m); static clutter re-acquired elsewhere stands still, "
           "a walker does not; 0 = off");
    integer("rest_scans_to_static", t.rest_scans_to_static, 0, 1000000,
            "a dynamic hypothesis whose reported speed stays zero this many scans is static again "
            "(ever_dynamic stays set); 0 = dynamic forever");

    choice("dynamic_test", t.dynamic_test,
           {{"free_space", DynamicTest::kFreeSpace}, {"box", DynamicTest::kBox}},
           "what turns a hypothesis dynamic: free_space = the scan sees through points the object "
           "occupied where it was anchored (occlusion and a moving viewpoint never do that); box "
           "= its footprint left the anchor footprint (the paper's test; also used without a "
           "scan)");
    number("free_space_margin_m", t.free_space_margin_m, 0.0, 100.0,
           "a beam ending more than this beyond a point sees the point free (m)");
    number("free_space_lateral_m", t.free_space_lateral_m, 0.0, 100.0,
           "a beam decides about a point only if it passes this close to it (m)");
    number("free_space_min_share", t.free_space_min_share, 0.0, 1.0,
           "free_space: share of the anchor's decided points (free or occupied) that must be "
           "seen free");
    integer("free_space_confirm_scans", t.free_space_confirm_scans, 1, 1000000,
            "free_space: consecutive scans with a detection in which the evidence must hold");
    number("free_space_min_distance_m", t.free_space_min_distance_m, 0.0, 100.0,
           "free_space: the measured centre must also be this far from the anchor (m)");
    number("free_space_max_viewpoint_shift_m", t.free_space_max_viewpoint_shift_m, 0.0, 1e6,
           "free_space: used while the sensor is within this distance of where it saw the "
           "anchor (m); beyond, beams pass beside the remembered points and the box test "
           "decides (a moving sensor)");
    integer("confirm_hits", t.confirm_hits, 1, 1000000,
            "a hypothesis is reported (tracks.csv, evaluation) once it had this many detections: "
            "one-scan blips never appear, new objects appear this many scans minus one late");
    integer("report_missed_scans", t.report_missed_scans, 0, 1000000,
            "a hypothesis missed in more consecutive scans than this is kept (for its id) but not "
            "reported, hidden (occluded) or not");
    integer("person_min_scans", t.person_min_scans, 1, 1000000,
            "a confirmed hypothesis is flagged person (tracks.csv column person, kept once set, "
            "moving or standing) once this many of its scans had a strict, person-shaped "
            "detection (relaxed ones do not count)");
    integer("occluded_coast_scans", t.occluded_coast_scans, 0, 1000000,
            "a hypothesis whose predicted points are occluded (something in front) is kept this "
            "many missed scans even when its covariance would delete it");
    integer("free_delete_scans", t.free_delete_scans, 0, 1000000,
            "a hypothesis missed in this many consecutive scans that see through its predicted "
            "points is deleted (0 = never)");
    number("relink_distance_m", t.relink_distance_m, 0.0, 100.0,
           "identity: a hypothesis confirmed this scan takes over the id (and the dynamic and "
           "person flags) of a confirmed hypothesis that has moved, was last measured no later "
           "than its birth and whose position, moved on by its velocity to that birth, lies this "
           "close horizontally (m): the same object, lost for a few scans and found again; 0 = "
           "off");
    number("relink_max_gap_s", t.relink_max_gap_s, 0.0, 1e6,
           "identity: ... when that hypothesis was last measured at most this long before the "
           "new one's birth (s)");
    boolean("rest_pairing", t.rest_pairing,
            "identity: a hypothesis that has moved and missed its last scan(s), or whose last "
            "detection lay outside the gate behind its prediction, may also pair, at rest, with "
            "a detection of three or more points where it was last measured, whichever costs "
            "less than at its prediction (a walker who stopped while hidden, merged with the "
            "structure beside it, or faster than the filter follows; its velocity restarts at "
            "zero)");
    boolean("hold_partly_hidden", t.hold_partly_hidden,
            "identity: a hypothesis at rest whose detection has fewer points than its last full "
            "view, while something nearer hides a quarter or more (two at least) of that view's "
            "remembered points, is measured where the full view put it, for up to 10 scans in a "
            "row (a standing person behind a passer-by: the visible edge's centroid would drag "
            "the track off the person)");

    auto& m = c.mapping;
    section_ = "mapping";
    // Bounded because every logged scan stays in memory (0.87 MB per VLP-16 scan, measured in
    // issue 16): 1000 scans, 100 s at 10 Hz, stay below 1 GB; the old bound allowed 87 GB.
    integer("log_delay_scans", m.log_delay_scans, 0, 1000,
            "filtered scans wait this many scans in the log, where late dynamic decisions still "
            "remove points, before they enter the static map");
    number("voxel_size_m", m.voxel_size_m, 1e-3, 100.0,
           "edge of a static-map voxel (m); each voxel keeps the mean position and intensity");
    number("box_margin_m", m.box_margin_m, 0.0, 10.0,
           "hypothesis boxes grow by this on every side before the points inside them are "
           "removed (m)");
    number("object_margin_m", m.object_margin_m, 0.0, 10.0,
           "the box of a dynamic hypothesis in the scan that measured it grows by this sideways "
           "and upward (not downward: the ground under its feet) and every point inside leaves "
           "that scan, segmented or not (a head above the cluster, an arm beside it); 0 removes "
           "only its detection's cells (m)");
    number("object_ground_clearance_m", m.object_ground_clearance_m, 0.0, 10.0,
           "that grown box also reaches down to this height above the ground around it (the "
           "lowest point of the scan within 1 m of its footprint): the legs below the cluster "
           "leave, the ground stays; 0 = not downward (m)");
    number("object_min_height_m", m.object_min_height_m, 0.0, 10.0,
           "and up to at least this height above that ground: the head of a walker whose "
           "cluster is only its legs; 0 = no (m)");
    number("object_outer_margin_m", m.object_outer_margin_m, 0.0, 10.0,
           "beyond object_margin_m and up to this sideways, points leave too unless their "
           "static-map voxel was seen free_space_protect_count times (structure beside the "
           "object: a wall, a post); not more than object_margin_m = no (m)");
    choice("remove", m.remove,
           {{"dynamic", RemovedObjects::kDynamic},
            {"person", RemovedObjects::kPerson},
            {"confirmed", RemovedObjects::kConfirmed}},
           "tracked objects whose points leave the scans and the map: dynamic = those that moved "
           "(the paper; people who stand all along stay), person = those and every hypothesis "
           "flagged person, confirmed = every confirmed hypothesis, moving or not; an object "
           "removed once is removed from its first scan on");
    boolean("free_space", m.free_space,
            "free-space line: a candidate point of a logged scan (a segmented point, or one near "
            "a hypothesis' box) that a later scan sees through (the beam ends beyond it) leaves "
            "that scan before it reaches the map; independent of the tracks");
    number("free_space_margin_m", m.free_space_margin_m, 0.0, 100.0,
           "free_space: the later beam must end more than this beyond the point (m)");
    number("free_space_lateral_m", m.free_space_lateral_m, 0.0, 10.0,
           "free_space: ... and pass this close to the point (m): a beam passing beside thin "
           "structure says nothing about it");
    boolean("free_space_moving", m.free_space_moving,
            "free_space also for a moving sensor, projecting each candidate into the later scan "
            "(off by default: the projection ignores the sensor's motion during a scan, up to "
            "half a metre at 5 m/s, and removed about 0.1 % of the static points in the "
            "benchmark; docs/tracking.md)");
    number("free_space_clearance_m", m.free_space_clearance_m, 0.0, 10.0,
           "free_space, a scan from another viewpoint: no beam through the cube of this half "
           "edge around the point may end in it (the nearest beam may pass beside a thin pole "
           "and see past it) (m)");
    integer("free_space_lag_scans", m.free_space_lag_scans, 1, 1000,
            "free_space: a logged scan's candidates are tested against the scan this many scans "
            "later, and again against the newest scan when it leaves the log");
    number("free_space_reach_m", m.free_space_reach_m, 0.0, 10.0,
           "free_space: points within this of any hypothesis' box are candidates too (heads, "
           "arms and legs outside the cluster) (m)");
    integer("free_space_protect_count", m.free_space_protect_count, 1, 1000000,
            "free_space: a point whose static-map voxel already holds this many points is "
            "structure seen occupied many times and stays");
    integer("transient_scans", m.transient_scans, 0, 1000,
            "transient line: a segmented point at least transient_min_height_m above the ground "
            "leaves its scan unless a scan this many scans or more before or after it (among "
            "the last minute's and the log's) segmented a point near it, or its static-map voxel "
            "holds free_space_protect_count points: a walker too far or too sparse to be "
            "tracked is seen once at each place, what stands is seen again; judged when the "
            "scan leaves the log and only with transient_scans later scans logged (so it needs "
            "log_delay_scans >= transient_scans, and a run's last scans are not judged); 0 = "
            "off");
    number("transient_cell_m", m.transient_cell_m, 0.01, 10.0,
           "transient line: near = in the same horizontal cell of this edge or one of the eight "
           "around it (m)");
    number("transient_min_height_m", m.transient_min_height_m, 0.0, 10.0,
           "transient line: points lower than this above the ground (the run's start altitude "
           "minus detection.sensor_height_m) are never transient: ground that a tilted "
           "sensor's rings segment (m)");
    number("map_radius_m", m.map_radius_m, 0.0, 1e6,
           "bounded memory: static-map voxels farther than this (horizontally) from the sensor "
           "leave memory (a sweep checks every voxel within 10 scans); run writes them into "
           "static_map.ply/.pcd, a library user takes them from DynamicObjectFilter::evicted(); "
           "choose it beyond the sensor's range, since a voxel seen again after it left is "
           "mapped anew (m); 0 = the whole map stays in memory");

    auto& b = c.background;
    section_ = "background";
    number("tolerance_m", b.tolerance_m, 0.0, 1000.0,
           "two ranges of a cell are one surface when within this plus relative_tolerance times "
           "the nearer range (m)");
    number("relative_tolerance", b.relative_tolerance, 0.0, 0.99,
           "range-proportional part of the tolerance (far and grazing returns are noisier)");
    integer("scans_to_learn", b.scans_to_learn, 1, 60000,
            "consecutive scans a range nearer than the background (or a cell's first range) must "
            "hold to become the background: passers-by stay in front, a parked car is learned");
    integer("scans_to_learn_behind", b.scans_to_learn_behind, 1, 60000,
            "consecutive scans a range behind the background must hold to replace it (seeing "
            "through the old background proves it gone)");
    number("smoothing", b.smoothing, 0.0, 1.0,
           "weight of a return matching the background in its running average (0 freezes it)");
    boolean("learn_no_return", b.learn_no_return,
            "a cell without returns for scans_to_learn scans learns an open background, in front "
            "of which every return counts");
    number("static_shift_m", b.static_shift_m, 0.0, 1000.0,
           "the background is learned while the sensor stays within this distance of the pose "
           "where it came to rest (m); a sensor moving farther forgets it and starts again when "
           "it rests");
    number("static_turn_deg", b.static_turn_deg, 0.0, 180.0,
           "... and within this rotation of that pose (degrees)");
    boolean("moving_memory", b.moving_memory,
            "a moving sensor keeps its recent scans instead and asks whether they saw through "
            "the points of a small cluster from their own viewpoints");
    integer("moving_lag_scans", b.moving_lag_scans, 1, 250,
            "moving_memory: the scans this many scans back, twice and four times as far back "
            "are asked (the largest sets how many scans are kept)");
    number("moving_lateral_m", b.moving_lateral_m, 0.0, 10.0,
           "moving_memory: an earlier scan's beam decides about a point passing this close (m)");
    number("moving_clearance_m", b.moving_clearance_m, 0.0, 10.0,
           "moving_memory: none of the earlier scan's beams through the cube of this half side "
           "around the point may end inside or before it (m)");
    number("moving_column_m", b.moving_column_m, 0.0, 10.0,
           "moving_memory: half width of the column under a point (m) whose earlier beams must "
           "all pass free, from moving_column_ground_m above the ground to the point; 0 = off");
    number("moving_column_ground_m", b.moving_column_ground_m, 0.0, 10.0,
           "moving_memory: the column test's column stops this far above the ground (m)");
    build_odometry(c.odometry);
  }

  void build_odometry(OdometryConfig& o) {
    section_ = "odometry";
    number("voxel_size_m", o.voxel_size_m, 0.05, 20.0,
           "local-map voxel edge (m); correspondences are searched within half a voxel (one "
           "voxel until the first velocity is known), so this also caps the correspondence "
           "distance (outdoors about max range / 100, indoors smaller)");
    integer("max_points_per_voxel", o.max_points_per_voxel, 1, 1000,
            "points a map voxel keeps at most: bounds memory and the nearest-neighbour search");
    number("map_spacing_m", o.map_spacing_m, 0.01, 20.0,
           "scan points enter the local map at most one per cube of this edge (m)");
    number("source_voxel_m", o.source_voxel_m, 0.01, 20.0,
           "registration uses at most one scan point per cube of this edge (m): fewer points, "
           "faster ICP");
    integer("min_source_points", o.min_source_points, 0, 1000000,
            "a scan that leaves fewer registration points than this in the source grid (a "
            "small room or hall: 50-80 at 2 m, against 560-1650 outdoors) is sampled again "
            "with half the edge, down to map_spacing_m; 0 = never");
    number("map_radius_m", o.map_radius_m, 1.0, 10000.0,
           "map voxels farther than this from the sensor are dropped (m): bounded memory");
    number("min_range_m", o.min_range_m, 0.0, 1000.0,
           "nearer returns (the platform, the person carrying the sensor) are not used (m)");
    number("max_range_m", o.max_range_m, 0.1, 10000.0, "farther returns are not used (m)");
    number("initial_threshold_m", o.initial_threshold_m, 0.01, 100.0,
           "correspondence distance until the motion statistics exist (m)");
    number("min_motion_m", o.min_motion_m, 0.0, 100.0,
           "a scan whose prediction error (translation plus rotation times max range) is below "
           "this does not enter the adaptive threshold's statistics (m)");
    number("min_threshold_m", o.min_threshold_m, 0.0, 100.0,
           "floor of the adaptive correspondence distance (m)");
    integer("max_iterations", o.max_iterations, 1, 1000, "ICP iterations per scan at most");
    number("convergence_m", o.convergence_m, 1e-9, 1.0,
           "ICP stops when a step moves less than this (m, and rad for the rotation)");
    choice("residual", o.residual,
           {{"point_to_plane", OdometryResidual::kPointToPlane},
            {"point_to_point", OdometryResidual::kPointToPoint}},
           "what ICP minimises: the distance to the nearest map point (point_to_point, as "
           "KISS-ICP) or its component along the scan point's surface normal (point_to_plane: "
           "the rings a sparse sensor draws on the ground then cannot pull the estimate back to "
           "the previous pose; points without a normal are left out)");
    boolean("deskew", o.deskew,
            "motion-compensate each scan with the estimated velocity, per column time");
    number("deskew_acceleration", o.deskew_acceleration, 0.0, 1.0,
           "share of the change between the last two scan-to-scan motions that is extrapolated "
           "over a scan's own revolution when compensating it (its columns fire after its stamp, "
           "the motion known is the one before): 0 assumes constant velocity; larger values "
           "follow a changing turn rate (a banking MAV) more closely but amplify the estimates' "
           "noise (1 ran away on a figure 8); docs/odometry.md");
    boolean("exclude_tracks", o.exclude_tracks,
            "points inside the boxes of the previous scan's reported tracks, predicted to this "
            "scan, stay out of registration and the local map (walkers do not drag the estimate)");
    number("exclude_margin_m", o.exclude_margin_m, 0.0, 10.0,
           "those boxes grow by this on every side (m)");
    number("degeneracy_threshold", o.degeneracy_threshold, 0.0, 1.0,
           "a scan is flagged unreliable when the weakest translation direction holds less than "
           "this share of the squared surface normals (ground only: about 0)");
    number("weak_share_threshold", o.weak_share_threshold, 0.0, 1.0,
           "a registered scan whose weakest share is below this is flagged weak (odometry.csv, "
           "the run summary): its pose may slide along that direction, as on a courtyard whose "
           "long walls leave the other axis to a few trunks; the estimate is kept as it is. The "
           "built-in structured scenes stay above 0.11; 0 = never");
  }

  std::string section_;
  std::vector<Field> fields_;
};

// A key must be a name. YAML allows lists and maps as keys, and as<std::string>() on one throws
// yaml-cpp's own exception, no ConfigError (the CLI's "internal error"; found by fuzzing).
std::string key_name(const YAML::Node& key, const std::string& source) {
  if (!key.IsScalar()) {
    throw ConfigError(source + ": line " + std::to_string(key.Mark().line + 1) +
                      ": expected a key name, got a list or map as key");
  }
  return key.Scalar();
}

void apply_node(Config& config, const YAML::Node& root, const std::string& source) {
  if (!root || root.IsNull()) return;
  if (!root.IsMap())
    throw ConfigError(source + ": expected a mapping of sections at the top level");
  Schema schema(config);
  for (const auto& section : root) {
    const auto section_name = key_name(section.first, source);
    if (!schema.has_section(section_name)) {
      throw ConfigError(source + ": unknown section '" + section_name + "'");
    }
    if (section.second.IsNull()) continue;
    if (!section.second.IsMap()) {
      throw ConfigError(source + ": section '" + section_name + "' must be a mapping of keys");
    }
    for (const auto& entry : section.second) {
      const auto key = key_name(entry.first, source);
      const std::string where = source + ": key '" + section_name + "." + key + "'";
      const Field* field = schema.find(section_name, key);
      if (field == nullptr)
        throw ConfigError(source + ": unknown key '" + section_name + "." + key + "'");
      if (!entry.second.IsScalar()) throw ConfigError(where + ": expected a single value");
      field->set(entry.second.Scalar(), where);
    }
  }
}

}  // namespace

std::vector<ConfigKeyInfo> describe_config(const Config& config) {
  Config copy = config;
  Schema schema(copy);
  std::vector<ConfigKeyInfo> out;
  for (const auto& f : schema.fields())
    out.push_back({f.section + "." + f.name, f.get(), f.description});
  return out;
}

void apply_config_yaml(Config& config, const std::string& yaml_text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(source + ": line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  Config next = config;  // all-or-nothing: a bad key leaves the caller's config untouched
  apply_node(next, root, source);
  try {
    validate_config(next);
  } catch (const ConfigError& e) {
    throw ConfigError(source + ": " + e.what());
  }
  config = next;
}

void apply_config_file(Config& config, const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot open the configuration file");
  std::stringstream text;
  text << in.rdbuf();
  apply_config_yaml(config, text.str(), path);
}

void apply_config_override(Config& config, const std::string& assignment) {
  const auto eq = assignment.find('=');
  const auto dot = assignment.find('.');
  if (eq == std::string::npos || dot == std::string::npos || dot > eq) {
    throw ConfigError("--set '" + assignment + "': expected section.key=value");
  }
  const std::string section = assignment.substr(0, dot);
  const std::string key = assignment.substr(dot + 1, eq - dot - 1);
  const std::string value = assignment.substr(eq + 1);
  Config next = config;
  Schema schema(next);
  const Field* field = schema.find(section, key);
  if (field == nullptr) throw ConfigError("--set: unknown key '" + section + "." + key + "'");
  field->set(value, "--set: key '" + section + "." + key + "'");
  validate_config(next);
  config = next;
}

void validate_config(const Config& c) {
  const auto& s = c.segmentation;
  if (!(s.min_width_m < s.max_width_m)) {
    throw ConfigError("key 'segmentation.min_width_m' must be below 'segmentation.max_width_m'");
  }
  if (!(s.delta_min_m <= s.delta_low_m && s.delta_low_m <= s.delta_high_m &&
        s.delta_high_m <= s.delta_max_m)) {
    throw ConfigError(
        "keys 'segmentation.delta_min_m <= delta_low_m <= delta_high_m <= delta_max_m' must be "
        "ordered");
  }
  const auto& d = c.detection;
  if (!(d.min_height_m <= d.max_height_m)) {
    throw ConfigError("key 'detection.min_height_m' must not exceed 'detection.max_height_m'");
  }
  const auto& t = c.tracking;
  if (!(t.min_speed_kmh < t.max_speed_kmh)) {
    throw ConfigError("key 'tracking.min_speed_kmh' must be below 'tracking.max_speed_kmh'");
  }
  const auto& o = c.odometry;
  if (!(o.min_range_m < o.max_range_m)) {
    throw ConfigError("key 'odometry.min_range_m' must be below 'odometry.max_range_m'");
  }
}

std::string dump_config(const Config& config) {
  std::ostringstream out;
  out << "# ringtrack configuration: every key with its value; comments give meaning and range.\n";
  std::string section;
  for (const auto& info : describe_config(config)) {
    const auto dot = info.key.find('.');
    const auto this_section = info.key.substr(0, dot);
    if (this_section != section) {
      section = this_section;
      out << section << ":\n";
    }
    out << "  # " << info.description << "\n";
    out << "  " << info.key.substr(dot + 1) << ": " << info.value << "\n";
  }
  return out.str();
}

}  // namespace ringtrack::core
