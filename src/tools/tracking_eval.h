// Tracking evaluation of urban_detection_eval: the pipeline (segmentation, detector,
// classifier, box fitting) followed by the Tracker, scored with CLEAR-MOT
// (clear_mot.h). Not a tool itself (only src/tools/*.cpp are executables).
//
//   --tracking (with --sim GT --pcap PCAP): the simulated drive. The tracker gets each
//     revolution's sensor pose from the ground-truth file (world_T_velodyne), as the nodelet
//     gets odom -> velodyne from tf. GT objects are the scene's street objects (cars, vans,
//     pedestrians, cyclists, bins, benches) with at least --min-points returns in the
//     revolution, at their box centre in the world frame; street objects with fewer returns and
//     trunks, poles and signs are ignored (a track on them is neither true nor false); a track
//     anywhere else (vegetation, walls, ground) is a false positive. Hypotheses are the
//     confirmed tracks (detected in this revolution). Match: centre distance <= 2 m on the
//     ground plane. Speed error: |track speed - GT speed| of matched cars and vans that move
//     faster than 0.5 m/s. The detector's own recall and precision under the same matching
//     (every detection a hypothesis) are printed beside: MOTA cannot exceed that recall by
//     more than what coasting adds.
//   --tracking --semantic-kitti DIR (the dataset root with sequences/NN/, or one sequence
//     folder): each sequence's scans in order, the tracker in the world frame of poses.txt
//     (world_T_velodyne = Tr^-1 * pose_i * Tr, Tr from calib.txt, or the nominal KITTI
//     camera-from-LiDAR axes when calib.txt has no Tr), a fresh tracker per sequence. GT
//     objects: the thing instances (vehicles, persons, riders, two-wheelers; SemanticKITTI's
//     instance ids are stable through a sequence) with at least --min-points points, at the
//     centroid of their points in the world frame; emptier ones are ignored. Hypotheses:
//     confirmed tracks detected in this scan, at the centroid of their detection's points in
//     the world frame (SemanticKITTI has no boxes: both sides are centroids of points); one
//     whose detection is mostly don't-care points (poles, trunks, signs, other-object,
//     unlabelled) is not a false positive when unmatched. Match: distance <= 2 m.
//   --kitti-tracking DIR: velodyne/<seq>/*.bin, label_02/<seq>.txt, calib/<seq>.txt. No poses
//     are read (KITTI tracking's oxts are not used): the tracker runs in the sensor frame, so
//     velocities include the ego motion and are not scored. GT: Car and Van (vehicle),
//     Pedestrian and Cyclist labels with at least --min-points LiDAR points in their box;
//     Truck, Tram, Person_sitting, Misc and those with fewer points are ignored. Hypotheses:
//     confirmed tracks the classifier calls vehicle, pedestrian or cyclist (any confirmed
//     track with the classifier off) whose centre
//     projects into image 2 (1242 x 375); a hypothesis whose centre projects into a DontCare
//     rectangle is not a false positive when unmatched. Match: distance of the box centres on
//     the ground plane <= 2 m (not the devkit's image-box overlap).
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "urban_detection/core/common/object_class.h"
#include "urban_detection/core/evaluation/eval_datasets.h"
#include "urban_detection/core/pipeline/pipeline.h"
#include "urban_detection/core/sensor/kitti_io.h"
#include "urban_detection/core/tracking/clear_mot.h"
#include "urban_detection/core/tracking/kitti_tracking.h"
#include "urban_detection/core/tracking/tracker.h"

#include "tool_common.h"

namespace urban_detection {
namespace tools {

namespace core = urban_detection::core;

// The pipeline with its tracker (params.tracking is set by the runs below), and the scoring.
struct TrackingPipeline {
  core::PipelineParams params;
  std::size_t min_gt_points = 10;
  std::size_t max_frames = static_cast<std::size_t>(-1);
};

// The pipeline of `p` with the tracker on.
inline std::unique_ptr<core::Pipeline> trackingPipeline(const TrackingPipeline& p) {
  core::PipelineParams params = p.params;
  params.tracking = true;
  return std::make_unique<core::Pipeline>(params);
}

inline void printMot(const char* what, const core::ClearMotResult& r) {
  std::printf(
      "%-28s frames %4zu  GT %6zu  GT tracks %4zu  MOTA %.3f  MOTP %.3f m  recall %.3f  "
      "precision %.3f  FN %zu  FP %zu  IDSW %zu (%.2f per 100 GT tracks)  frag %zu  "
      "MT %zu  PT %zu  ML %zu\n",
      what, r.frames, r.gt, r.gt_tracks, r.mota(), r.motp_m(), r.recall(), r.precision(), r.misses,
      r.false_positives, r.id_switches, r.idSwitchesPer100GtTracks(), r.fragmentations,
      r.mostly_tracked, r.partially_tracked, r.mostly_lost);
}

inline std::string motJson(const core::ClearMotResult& r) {
  char buf[640];
  std::snprintf(
      buf, sizeof buf,
      "{\"frames\": %zu, \"gt\": %zu, \"gt_tracks\": %zu, \"matches\": %zu, \"mota\": %s, "
      "\"motp_m\": %s, "
      "\"recall\": %s, \"precision\": %s, \"misses\": %zu, \"false_positives\": %zu, "
      "\"id_switches\": %zu, \"id_switches_per_100_gt_tracks\": %s, "
      "\"fragmentations\": %zu, \"mostly_tracked\": %zu, \"partially_tracked\": %zu, "
      "\"mostly_lost\": %zu}",
      r.frames, r.gt, r.gt_tracks, r.matches, jsonNumber(r.mota()).c_str(),
      jsonNumber(r.motp_m()).c_str(), jsonNumber(r.recall()).c_str(),
      jsonNumber(r.precision()).c_str(), r.misses, r.false_positives, r.id_switches,
      jsonNumber(r.idSwitchesPer100GtTracks()).c_str(), r.fragmentations, r.mostly_tracked,
      r.partially_tracked, r.mostly_lost);
  return buf;
}

// --tracking on a simulated drive. Returns the process exit code.
inline int runSimTracking(const TrackingPipeline& p, const std::string& gt_path,
                          const std::string& pcap_path, const core::Calibration& calibration,
                          double cut_angle_deg, const std::string& json_path) {
  std::unique_ptr<core::SimulatedDriveReader> reader;
  try {
    reader.reset(new core::SimulatedDriveReader(pcap_path, gt_path, calibration, cut_angle_deg));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  const std::unique_ptr<core::Pipeline> pipeline = trackingPipeline(p);
  const core::Tracker& tracker = *pipeline->tracker();
  core::ClearMot mot, detections_mot, oracle_mot;
  core::Tracker oracle(
      p.params.tracker);  // fed the GT boxes themselves: the tracker without the detector
  std::vector<core::DetectedObject> gt_boxes;
  CloudXYZIRT cloud;
  core::GroundTruthFrame gt;
  std::vector<double> speed_error, static_speed, update_ms;
  std::size_t frames = 0, skipped = 0;
  std::uint32_t detection_ids = 0;
  // UD_TRACK_DEBUG=1: one line per identity switch, with the state of the previous track.
  std::map<std::string, std::map<std::uint32_t, std::uint32_t>> last_hyp;
  std::vector<const core::GroundTruthObject*> gt_of;
  auto debugSwitches = [&](const char* tag, const std::vector<core::MotGroundTruth>& gts,
                           const std::vector<core::MotHypothesis>& hyps,
                           const std::vector<int>& matched, const core::Tracker& tracker) {
    if (!std::getenv("UD_TRACK_DEBUG")) return;
    {
      std::map<std::uint32_t, std::uint32_t>& last = last_hyp[tag];
      for (std::size_t g = 0; g < gts.size(); ++g) {
        if (matched[g] < 0) continue;
        const std::uint32_t h = hyps[matched[g]].id;
        const auto it = last.find(gts[g].id);
        if (it != last.end() && it->second != h) {
          const core::Track* prev = nullptr;
          for (const core::Track& t : tracker.tracks()) {
            if (t.id == it->second) prev = &t;
          }
          const Eigen::Vector3d rel = gt.sensor_pose.inverse() * gt_of[g]->center.cast<double>();
          std::printf(
              "%s IDSW rev %zu gt %u %s pts %u at (%.1f, %.1f) sensor frame: %u -> %u "
              "(age %u hits %u); previous %s\n",
              tag, frames, gts[g].id, core::toString(gt_of[g]->object_class), gt_of[g]->num_points,
              rel.x(), rel.y(), it->second, h, 0u, 0u,
              prev ? (std::string(core::toString(prev->state)) + " misses " +
                      std::to_string(prev->misses) + " dist " +
                      std::to_string(
                          (prev->center - gt_of[g]->center.cast<double>()).head<2>().norm()))
                         .c_str()
                   : "dead");
        }
        last[gts[g].id] = h;
      }
    }
  };
  while (frames < p.max_frames) {
    std::string message;
    const auto status = reader->next(&cloud, &gt, &message);
    if (status == core::SimulatedDriveReader::Result::kEnd) break;
    if (status == core::SimulatedDriveReader::Result::kSkipped) {
      ++skipped;
      continue;
    }
    ++frames;
    const core::PipelineResult& result = pipeline->process(cloud, gt.sensor_pose, gt.stamp_s);
    const std::vector<core::DetectedObject>& objects = result.objects;
    update_ms.push_back(result.wallMs("tracking"));

    std::vector<core::MotGroundTruth> gts;
    gt_of.clear();
    for (const core::GroundTruthObject& o : gt.objects) {
      if (o.num_points == 0) continue;
      const bool street = core::isStreetObject(o.object_class);
      const bool dont_care = o.object_class == core::ObjectClass::kTrunk ||
                             o.object_class == core::ObjectClass::kPole ||
                             o.object_class == core::ObjectClass::kSign;
      if (!street && !dont_care) continue;  // vegetation and the like: background
      core::MotGroundTruth g;
      g.id = o.instance_id;
      g.position = o.center.head<2>().cast<double>();
      g.ignored = !street || o.num_points < p.min_gt_points;
      gts.push_back(g);
      gt_of.push_back(&o);
    }
    std::vector<core::MotHypothesis> hyps;
    std::vector<const core::Track*> track_of;
    for (const core::Track& t : tracker.tracks()) {
      if (t.state != core::TrackState::kConfirmed) continue;
      core::MotHypothesis h;
      h.id = t.id;
      h.position = t.center.head<2>();
      hyps.push_back(h);
      track_of.push_back(&t);
    }
    std::vector<int> matched;
    mot.addFrame(gts, hyps, &matched);
    debugSwitches("tracker", gts, hyps, matched, tracker);
    for (std::size_t g = 0; g < gts.size(); ++g) {
      if (matched[g] < 0) continue;
      const core::GroundTruthObject& o = *gt_of[g];
      if (o.object_class != core::ObjectClass::kCar && o.object_class != core::ObjectClass::kVan) {
        continue;
      }
      const double gt_speed = o.velocity.head<2>().norm();
      const double speed = track_of[matched[g]]->speed();
      if (gt_speed > 0.5) {
        speed_error.push_back(std::fabs(speed - gt_speed));
      } else {
        static_speed.push_back(speed);
      }
    }
    // The detector alone under the same matching: every detection a one-revolution hypothesis.
    std::vector<core::MotHypothesis> dets;
    for (const core::DetectedObject& o : objects) {
      if (!o.obb_center.allFinite()) continue;
      core::MotHypothesis h;
      h.id = ++detection_ids;
      h.position = (gt.sensor_pose * o.obb_center.cast<double>()).head<2>();
      dets.push_back(h);
    }
    detections_mot.addFrame(gts, dets);

    // The same tracker on the scored GT objects' own boxes (in the sensor frame, as a detector
    // would give them): what the tracker does when the detector is perfect.
    gt_boxes.clear();
    const Eigen::Isometry3d sensor_T_world = gt.sensor_pose.inverse();
    const double pose_yaw =
        std::atan2(gt.sensor_pose.linear()(1, 0), gt.sensor_pose.linear()(0, 0));
    for (std::size_t g = 0; g < gts.size(); ++g) {
      if (gts[g].ignored) continue;
      core::DetectedObject o;
      o.obb_center = (sensor_T_world * gt_of[g]->center.cast<double>()).cast<float>();
      o.centroid = o.obb_center;
      o.obb_size = gt_of[g]->size;
      o.obb_yaw_rad = static_cast<float>(gt_of[g]->yaw_rad - pose_yaw);
      gt_boxes.push_back(o);
    }
    oracle.update(gt_boxes, gt.sensor_pose, gt.stamp_s);
    std::vector<core::MotHypothesis> oracle_hyps;
    for (const core::Track& t : oracle.tracks()) {
      if (t.state != core::TrackState::kConfirmed) continue;
      core::MotHypothesis h;
      h.id = t.id;
      h.position = t.center.head<2>();
      oracle_hyps.push_back(h);
    }
    std::vector<int> oracle_matched;
    oracle_mot.addFrame(gts, oracle_hyps, &oracle_matched);
    debugSwitches("oracle", gts, oracle_hyps, oracle_matched, oracle);
  }
  if (frames == 0) {
    std::fprintf(stderr, "error: no revolution with ground truth in %s\n", pcap_path.c_str());
    return 1;
  }
  const core::ClearMotResult r = mot.result();
  const core::ClearMotResult d = detections_mot.result();
  const core::ClearMotResult o = oracle_mot.result();
  std::printf(
      "tracking on the simulated drive (%zu revolutions, %zu skipped), detector %s, "
      "classifier %s\n",
      frames, skipped, p.params.detector.c_str(), p.params.classifier.enabled ? "on" : "off");
  printMot("tracker (confirmed tracks)", r);
  std::printf(
      "%-28s recall %.3f  precision %.3f  (MOTA <= recall of the tracks; the detector "
      "bounds it unless coasting fills its gaps)\n",
      "detector alone", d.recall(), d.precision());
  printMot("tracker on GT boxes", o);
  std::printf(
      "speed error of matched moving cars/vans: median %.3f m/s, p90 %.3f m/s "
      "(%zu matches); speed of matched parked cars/vans: median %.3f m/s, p90 %.3f m/s "
      "(%zu)\n",
      median(speed_error), percentile(speed_error, 0.9), speed_error.size(), median(static_speed),
      percentile(static_speed, 0.9), static_speed.size());
  std::printf(
      "tracker update: median %.4f ms, max %.4f ms per revolution (wall clock, with "
      "the pipeline around it)\n",
      median(update_ms),
      update_ms.empty() ? 0.0 : *std::max_element(update_ms.begin(), update_ms.end()));
  if (!json_path.empty()) {
    std::ofstream out(json_path);
    out << "{\n  \"dataset\": \"sim\",\n  \"pcap\": \"" << jsonEscape(pcap_path)
        << "\",\n  \"revolutions\": " << frames << ",\n  \"tracker\": " << motJson(r)
        << ",\n  \"detector_alone\": " << motJson(d)
        << ",\n  \"tracker_on_ground_truth_boxes\": " << motJson(o)
        << ",\n  \"moving_vehicle_speed_error_mps\": {\"median\": "
        << jsonNumber(median(speed_error))
        << ", \"p90\": " << jsonNumber(percentile(speed_error, 0.9))
        << ", \"n\": " << speed_error.size()
        << "},\n  \"parked_vehicle_speed_mps\": {\"median\": " << jsonNumber(median(static_speed))
        << ", \"n\": " << static_speed.size()
        << "},\n  \"tracker_update_ms_median\": " << jsonNumber(median(update_ms)) << "\n}\n";
    if (!out) {
      std::fprintf(stderr, "error: cannot write %s\n", json_path.c_str());
      return 1;
    }
  }
  return 0;
}

// --kitti-tracking DIR. Returns the process exit code.
inline int runKittiTracking(const TrackingPipeline& p, const std::string& dir,
                            const std::string& json_path) {
  namespace fs = std::filesystem;
  const std::vector<std::string> label_files = core::listFiles(dir + "/label_02", ".txt");
  if (label_files.empty()) {
    std::fprintf(stderr, "error: no label_02/<seq>.txt in %s\n", dir.c_str());
    return 1;
  }
  const std::unique_ptr<core::Pipeline> pipeline = trackingPipeline(p);
  core::ClearMot mot;
  const int width = 1242, height = 375;
  std::size_t frames = 0, sequences = 0;
  CloudXYZIRT cloud;
  for (const std::string& label_file : label_files) {
    const std::string seq = fs::path(label_file).stem().string();
    std::map<int, std::vector<core::KittiTrackingLabel>> labels;
    core::KittiTrackingCalibration calib;
    std::string error;
    if (!core::readKittiTrackingLabels(label_file, &labels, &error) ||
        !core::readKittiTrackingCalibration(dir + "/calib/" + seq + ".txt", &calib, &error)) {
      std::fprintf(stderr, "warning: skipping sequence %s: %s\n", seq.c_str(), error.c_str());
      continue;
    }
    const std::vector<std::string> bins = core::listFiles(dir + "/velodyne/" + seq, ".bin");
    if (bins.empty()) {
      std::fprintf(stderr, "warning: skipping sequence %s: no velodyne/%s/*.bin\n", seq.c_str(),
                   seq.c_str());
      continue;
    }
    ++sequences;
    pipeline->restartTracker();  // a fresh tracker per sequence
    const core::Tracker& tracker = *pipeline->tracker();
    const std::uint32_t id_base = static_cast<std::uint32_t>(sequences) * 1000000u;
    for (const std::string& bin : bins) {
      if (frames >= p.max_frames) break;
      int frame = 0;
      try {
        frame = std::stoi(fs::path(bin).stem().string());
      } catch (const std::exception&) {
        continue;
      }
      if (!core::readKittiBin(bin, &cloud, &error)) {
        std::fprintf(stderr, "warning: skipping %s: %s\n", bin.c_str(), error.c_str());
        continue;
      }
      ++frames;
      pipeline->process(cloud, Eigen::Isometry3d::Identity(), 0.1 * frame);  // tracker updated
      const std::vector<core::KittiTrackingLabel>& frame_labels = labels[frame];
      std::vector<core::MotGroundTruth> gts;
      for (const core::KittiTrackingLabel& l : frame_labels) {
        if (l.dontCare() || l.track_id < 0) continue;
        const bool scored =
            l.type == "Car" || l.type == "Van" || l.type == "Pedestrian" || l.type == "Cyclist";
        std::size_t points = 0;
        if (scored) {
          for (const auto& pt : cloud) {
            points += core::insideKittiTrackingBox(l, calib, Eigen::Vector3d(pt.x, pt.y, pt.z));
          }
        }
        core::MotGroundTruth g;
        g.id = id_base + static_cast<std::uint32_t>(l.track_id);
        g.position = core::kittiTrackingBoxCenterVelo(l, calib).head<2>();
        g.ignored = !scored || points < p.min_gt_points;
        gts.push_back(g);
      }
      std::vector<core::MotHypothesis> hyps;
      for (const core::Track& t : tracker.tracks()) {
        if (t.state != core::TrackState::kConfirmed) continue;
        if (p.params.classifier.enabled && t.category != core::ObjectCategory::kVehicle &&
            t.category != core::ObjectCategory::kPedestrian &&
            t.category != core::ObjectCategory::kCyclist) {
          continue;
        }
        double u, v;
        if (!calib.project(t.center, &u, &v) || u < 0 || u >= width || v < 0 || v >= height) {
          continue;  // outside the labelled camera view
        }
        core::MotHypothesis h;
        h.id = id_base + t.id;
        h.position = t.center.head<2>();
        for (const core::KittiTrackingLabel& l : frame_labels) {
          if (l.dontCare() && u >= l.bbox[0] && u <= l.bbox[2] && v >= l.bbox[1] &&
              v <= l.bbox[3]) {
            h.dont_care = true;
          }
        }
        hyps.push_back(h);
      }
      mot.addFrame(gts, hyps);
    }
  }
  if (frames == 0) {
    std::fprintf(stderr, "error: no frames read from %s\n", dir.c_str());
    return 1;
  }
  const core::ClearMotResult r = mot.result();
  std::printf("tracking on KITTI tracking (%zu sequences, %zu frames), sensor frame (no poses)\n",
              sequences, frames);
  printMot("tracker (confirmed tracks)", r);
  if (!json_path.empty()) {
    std::ofstream out(json_path);
    out << "{\n  \"dataset\": \"kitti_tracking\",\n  \"path\": \"" << jsonEscape(dir)
        << "\",\n  \"sequences\": " << sequences << ",\n  \"tracker\": " << motJson(r) << "\n}\n";
    if (!out) {
      std::fprintf(stderr, "error: cannot write %s\n", json_path.c_str());
      return 1;
    }
  }
  return 0;
}

// world_T_velodyne of every scan of a SemanticKITTI sequence folder (core/evaluation).
inline bool readSemanticKittiPoses(const std::string& seq_dir, std::vector<Eigen::Isometry3d>* out,
                                   bool* nominal_tr, std::string* error) {
  return core::readSemanticKittiPoses(seq_dir, out, nominal_tr, error);
}

// --tracking --semantic-kitti DIR. Returns the process exit code.
inline int runSemanticKittiTracking(const TrackingPipeline& p, const std::string& dir,
                                    const std::string& json_path) {
  namespace fs = std::filesystem;
  std::vector<std::string> seqs;
  if (fs::is_directory(dir + "/velodyne")) {
    seqs.push_back(dir);
  } else {
    for (const auto& s : core::listFiles(dir + "/sequences", "")) {
      if (fs::is_directory(s + "/velodyne")) seqs.push_back(s);
    }
  }
  if (seqs.empty()) {
    std::fprintf(stderr, "error: no SemanticKITTI sequence (velodyne/) in %s\n", dir.c_str());
    return 1;
  }
  const std::unique_ptr<core::Pipeline> pipeline = trackingPipeline(p);
  core::ClearMot pooled, detections_pooled;
  core::SemanticKittiGroundTruthParams gt_params;
  gt_params.min_points = p.min_gt_points;
  std::vector<std::pair<std::string, core::ClearMotResult>> per_sequence;
  std::size_t frames = 0;
  std::uint32_t next_gt_id = 1, detection_ids = 0, id_base = 0;
  std::vector<double> update_ms;
  CloudXYZIRT cloud;
  std::vector<std::uint32_t> labels;
  core::EvalFrame gt;
  bool any_nominal = false;
  for (const std::string& seq : seqs) {
    const std::string name = fs::path(seq).filename().string();
    std::vector<Eigen::Isometry3d> poses;
    bool nominal = false;
    std::string error;
    if (!readSemanticKittiPoses(seq, &poses, &nominal, &error)) {
      std::fprintf(stderr, "warning: skipping sequence %s: %s\n", name.c_str(), error.c_str());
      continue;
    }
    any_nominal = any_nominal || nominal;
    pipeline->restartTracker();  // a fresh tracker per sequence
    const core::Tracker& tracker = *pipeline->tracker();
    core::ClearMot mot;
    std::map<std::uint32_t, std::uint32_t> gt_id;  // full label (class | instance) -> GT id
    id_base += 1000000u;
    for (const std::string& bin : core::listFiles(seq + "/velodyne", ".bin")) {
      if (frames >= p.max_frames) break;
      const std::string stem = fs::path(bin).stem().string();
      std::size_t scan = 0;
      try {
        scan = static_cast<std::size_t>(std::stoul(stem));
      } catch (const std::exception&) {
        continue;
      }
      if (scan >= poses.size() || !core::readKittiBin(bin, &cloud, &error) ||
          !core::readSemanticKittiLabels(seq + "/labels/" + stem + ".label", &labels, &error) ||
          labels.size() != cloud.size()) {
        std::fprintf(stderr, "warning: skipping %s/%s: %s\n", name.c_str(), stem.c_str(),
                     scan >= poses.size() ? "no pose" : error.c_str());
        continue;
      }
      ++frames;
      core::buildSemanticKittiGroundTruth(labels, gt_params, &gt);
      const Eigen::Isometry3d& pose = poses[scan];
      const core::PipelineResult& result =
          pipeline->process(cloud, pose, 0.1 * static_cast<double>(scan));
      const std::vector<core::DetectedObject>& objects = result.objects;
      update_ms.push_back(result.wallMs("tracking"));

      // GT: centroids of the instances' points, in the world frame.
      std::vector<Eigen::Vector3d> sum(gt.objects.size(), Eigen::Vector3d::Zero());
      std::vector<std::size_t> count(gt.objects.size(), 0);
      std::vector<std::uint32_t> label_of(gt.objects.size(), 0);
      for (std::size_t i = 0; i < cloud.size(); ++i) {
        const std::int32_t g = gt.object_of_point[i];
        if (g < 0) continue;
        sum[g] += Eigen::Vector3d(cloud[i].x, cloud[i].y, cloud[i].z);
        ++count[g];
        label_of[g] = labels[i];
      }
      std::vector<core::MotGroundTruth> gts;
      for (std::size_t g = 0; g < gt.objects.size(); ++g) {
        if (count[g] == 0) continue;
        auto it = gt_id.find(label_of[g]);
        if (it == gt_id.end()) it = gt_id.emplace(label_of[g], next_gt_id++).first;
        core::MotGroundTruth m;
        m.id = it->second;
        m.position = (pose * (sum[g] / static_cast<double>(count[g]))).head<2>();
        m.ignored = gt.objects[g].ignored;
        gts.push_back(m);
      }
      // A detection made mostly of don't-care points (poles, trunks, unlabelled) is neither
      // true nor false when it matches nothing.
      auto dontCare = [&](const core::DetectedObject& o) {
        std::size_t dc = 0;
        for (const std::uint32_t i : o.indices) {
          dc += i < gt.role.size() && gt.role[i] == core::PointRole::kDontCare;
        }
        return 2 * dc > o.indices.size();
      };
      std::vector<core::MotHypothesis> hyps;
      for (const core::Track& t : tracker.tracks()) {
        if (t.state != core::TrackState::kConfirmed || t.detection < 0) continue;
        // Like the GT, the centroid of its detection's points (SemanticKITTI has no boxes; the
        // box centres are scored against KITTI's boxes by --kitti-object).
        const core::DetectedObject& o = objects[static_cast<std::size_t>(t.detection)];
        core::MotHypothesis h;
        h.id = id_base + t.id;
        h.position = (pose * o.centroid.cast<double>()).head<2>();
        h.dont_care = dontCare(o);
        hyps.push_back(h);
      }
      mot.addFrame(gts, hyps);
      pooled.addFrame(gts, hyps);
      std::vector<core::MotHypothesis> dets;
      for (const core::DetectedObject& o : objects) {
        core::MotHypothesis h;
        h.id = ++detection_ids;
        h.position = (pose * o.centroid.cast<double>()).head<2>();
        h.dont_care = dontCare(o);
        dets.push_back(h);
      }
      detections_pooled.addFrame(gts, dets);
    }
    if (mot.result().frames > 0) per_sequence.emplace_back(name, mot.result());
  }
  if (frames == 0) {
    std::fprintf(stderr, "error: no scans read from %s\n", dir.c_str());
    return 1;
  }
  const core::ClearMotResult r = pooled.result();
  const core::ClearMotResult d = detections_pooled.result();
  std::printf(
      "tracking on SemanticKITTI (%zu sequences, %zu scans), world frame (poses.txt%s), "
      "detector %s, classifier %s, min GT points %zu\n",
      per_sequence.size(), frames, any_nominal ? ", nominal Tr" : ", calib Tr",
      p.params.detector.c_str(), p.params.classifier.enabled ? "on" : "off", p.min_gt_points);
  for (const auto& s : per_sequence) printMot(("  sequence " + s.first).c_str(), s.second);
  printMot("tracker, pooled", r);
  std::printf("%-28s recall %.3f  precision %.3f\n", "detector alone", d.recall(), d.precision());
  std::printf("tracker update: median %.4f ms per scan\n", median(update_ms));
  if (!json_path.empty()) {
    std::ofstream out(json_path);
    out << "{\n  \"dataset\": \"semantic_kitti_tracking\",\n  \"path\": \"" << jsonEscape(dir)
        << "\",\n  \"scans\": " << frames << ",\n  \"min_gt_points\": " << p.min_gt_points
        << ",\n  \"nominal_tr\": " << (any_nominal ? "true" : "false")
        << ",\n  \"tracker\": " << motJson(r) << ",\n  \"detector_alone\": " << motJson(d)
        << ",\n  \"by_sequence\": {";
    for (std::size_t k = 0; k < per_sequence.size(); ++k) {
      out << (k ? ",\n    " : "\n    ") << "\"" << jsonEscape(per_sequence[k].first)
          << "\": " << motJson(per_sequence[k].second);
    }
    out << "\n  }\n}\n";
    if (!out) {
      std::fprintf(stderr, "error: cannot write %s\n", json_path.c_str());
      return 1;
    }
  }
  return 0;
}

}  // namespace tools
}  // namespace urban_detection
