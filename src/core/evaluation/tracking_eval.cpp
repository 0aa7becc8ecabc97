#include "urban_detection/core/evaluation/tracking_eval.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "urban_detection/core/common/object_class.h"
#include "urban_detection/core/evaluation/eval_datasets.h"
#include "urban_detection/core/evaluation/report.h"
#include "urban_detection/core/sensor/calibration.h"
#include "urban_detection/core/sensor/kitti_io.h"
#include "urban_detection/core/tracking/kitti_tracking.h"
#include "urban_detection/core/tracking/tracker.h"

namespace urban_detection {
namespace core {

namespace fs = std::filesystem;

namespace {

// The pipeline of `params` with the tracker on.
std::unique_ptr<Pipeline> trackingPipeline(PipelineParams params) {
  params.tracking = true;
  return std::make_unique<Pipeline>(params);
}

}  // namespace

std::string motJson(const ClearMotResult& r) {
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

bool evaluateSimTracking(const TrackingEvalParams& p, const std::string& gt_path,
                         const std::string& pcap_path, const Calibration& calibration,
                         double cut_angle_deg, SimTrackingResult* out, std::string* error) {
  std::unique_ptr<SimulatedDriveReader> reader;
  try {
    reader.reset(new SimulatedDriveReader(pcap_path, gt_path, calibration, cut_angle_deg));
  } catch (const std::exception& e) {
    *error = e.what();
    return false;
  }
  const std::unique_ptr<Pipeline> pipeline = trackingPipeline(p.params);
  const Tracker& tracker = *pipeline->tracker();
  ClearMot mot, detections_mot, oracle_mot;
  Tracker oracle(
      p.params.tracker);  // fed the GT boxes themselves: the tracker without the detector
  std::vector<DetectedObject> gt_boxes;
  CloudXYZIRT cloud;
  GroundTruthFrame gt;
  std::vector<double>& speed_error = out->speed_error;
  std::vector<double>& static_speed = out->static_speed;
  std::vector<double>& update_ms = out->update_ms;
  speed_error.clear();
  static_speed.clear();
  update_ms.clear();
  std::size_t frames = 0, skipped = 0;
  std::uint32_t detection_ids = 0;
  // UD_TRACK_DEBUG=1: one line per identity switch, with the state of the previous track.
  std::map<std::string, std::map<std::uint32_t, std::uint32_t>> last_hyp;
  std::vector<const GroundTruthObject*> gt_of;
  auto debugSwitches = [&](const char* tag, const std::vector<MotGroundTruth>& gts,
                           const std::vector<MotHypothesis>& hyps, const std::vector<int>& matched,
                           const Tracker& tracker) {
    if (!std::getenv("UD_TRACK_DEBUG")) return;
    {
      std::map<std::uint32_t, std::uint32_t>& last = last_hyp[tag];
      for (std::size_t g = 0; g < gts.size(); ++g) {
        if (matched[g] < 0) continue;
        const std::uint32_t h = hyps[matched[g]].id;
        const auto it = last.find(gts[g].id);
        if (it != last.end() && it->second != h) {
          const Track* prev = nullptr;
          for (const Track& t : tracker.tracks()) {
            if (t.id == it->second) prev = &t;
          }
          const Eigen::Vector3d rel = gt.sensor_pose.inverse() * gt_of[g]->center.cast<double>();
          std::printf(
              "%s IDSW rev %zu gt %u %s pts %u at (%.1f, %.1f) sensor frame: %u -> %u "
              "(age %u hits %u); previous %s\n",
              tag, frames, gts[g].id, toString(gt_of[g]->object_class), gt_of[g]->num_points,
              rel.x(), rel.y(), it->second, h, 0u, 0u,
              prev ? (std::string(toString(prev->state)) + " misses " +
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
    if (status == SimulatedDriveReader::Result::kEnd) break;
    if (status == SimulatedDriveReader::Result::kSkipped) {
      ++skipped;
      continue;
    }
    ++frames;
    const PipelineResult& result = pipeline->process(cloud, gt.sensor_pose, gt.stamp_s);
    const std::vector<DetectedObject>& objects = result.objects;
    update_ms.push_back(result.wallMs("tracking"));

    std::vector<MotGroundTruth> gts;
    gt_of.clear();
    for (const GroundTruthObject& o : gt.objects) {
      if (o.num_points == 0) continue;
      const bool street = isStreetObject(o.object_class);
      const bool dont_care = o.object_class == ObjectClass::kTrunk ||
                             o.object_class == ObjectClass::kPole ||
                             o.object_class == ObjectClass::kSign;
      if (!street && !dont_care) continue;  // vegetation and the like: background
      MotGroundTruth g;
      g.id = o.instance_id;
      g.position = o.center.head<2>().cast<double>();
      g.ignored = !street || o.num_points < p.min_gt_points;
      gts.push_back(g);
      gt_of.push_back(&o);
    }
    std::vector<MotHypothesis> hyps;
    std::vector<const Track*> track_of;
    for (const Track& t : tracker.tracks()) {
      if (t.state != TrackState::kConfirmed) continue;
      MotHypothesis h;
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
      const GroundTruthObject& o = *gt_of[g];
      if (o.object_class != ObjectClass::kCar && o.object_class != ObjectClass::kVan) {
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
    std::vector<MotHypothesis> dets;
    for (const DetectedObject& o : objects) {
      if (!o.obb_center.allFinite()) continue;
      MotHypothesis h;
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
      DetectedObject o;
      o.obb_center = (sensor_T_world * gt_of[g]->center.cast<double>()).cast<float>();
      o.centroid = o.obb_center;
      o.obb_size = gt_of[g]->size;
      o.obb_yaw_rad = static_cast<float>(gt_of[g]->yaw_rad - pose_yaw);
      gt_boxes.push_back(o);
    }
    oracle.update(gt_boxes, gt.sensor_pose, gt.stamp_s);
    std::vector<MotHypothesis> oracle_hyps;
    for (const Track& t : oracle.tracks()) {
      if (t.state != TrackState::kConfirmed) continue;
      MotHypothesis h;
      h.id = t.id;
      h.position = t.center.head<2>();
      oracle_hyps.push_back(h);
    }
    std::vector<int> oracle_matched;
    oracle_mot.addFrame(gts, oracle_hyps, &oracle_matched);
    debugSwitches("oracle", gts, oracle_hyps, oracle_matched, oracle);
  }
  out->frames = frames;
  out->skipped = skipped;
  out->tracker = mot.result();
  out->detector = detections_mot.result();
  out->oracle = oracle_mot.result();
  if (frames == 0) {
    *error = "no revolution with ground truth in " + pcap_path;
    return false;
  }
  return true;
}

bool evaluateKittiTracking(const TrackingEvalParams& p, const std::string& dir,
                           KittiTrackingEvalResult* out, std::string* error) {
  const std::vector<std::string> label_files = listFiles(dir + "/label_02", ".txt");
  if (label_files.empty()) {
    *error = "no label_02/<seq>.txt in " + dir;
    return false;
  }
  const std::unique_ptr<Pipeline> pipeline = trackingPipeline(p.params);
  ClearMot mot;
  const int width = 1242, height = 375;
  std::size_t frames = 0, sequences = 0;
  CloudXYZIRT cloud;
  for (const std::string& label_file : label_files) {
    const std::string seq = fs::path(label_file).stem().string();
    std::map<int, std::vector<KittiTrackingLabel>> labels;
    KittiTrackingCalibration calib;
    std::string error;
    if (!readKittiTrackingLabels(label_file, &labels, &error) ||
        !readKittiTrackingCalibration(dir + "/calib/" + seq + ".txt", &calib, &error)) {
      std::fprintf(stderr, "warning: skipping sequence %s: %s\n", seq.c_str(), error.c_str());
      continue;
    }
    const std::vector<std::string> bins = listFiles(dir + "/velodyne/" + seq, ".bin");
    if (bins.empty()) {
      std::fprintf(stderr, "warning: skipping sequence %s: no velodyne/%s/*.bin\n", seq.c_str(),
                   seq.c_str());
      continue;
    }
    ++sequences;
    pipeline->restartTracker();  // a fresh tracker per sequence
    const Tracker& tracker = *pipeline->tracker();
    const std::uint32_t id_base = static_cast<std::uint32_t>(sequences) * 1000000u;
    for (const std::string& bin : bins) {
      if (frames >= p.max_frames) break;
      int frame = 0;
      try {
        frame = std::stoi(fs::path(bin).stem().string());
      } catch (const std::exception&) {
        continue;
      }
      if (!readKittiBin(bin, &cloud, &error)) {
        std::fprintf(stderr, "warning: skipping %s: %s\n", bin.c_str(), error.c_str());
        continue;
      }
      ++frames;
      pipeline->process(cloud, Eigen::Isometry3d::Identity(), 0.1 * frame);  // tracker updated
      const std::vector<KittiTrackingLabel>& frame_labels = labels[frame];
      std::vector<MotGroundTruth> gts;
      for (const KittiTrackingLabel& l : frame_labels) {
        if (l.dontCare() || l.track_id < 0) continue;
        const bool scored =
            l.type == "Car" || l.type == "Van" || l.type == "Pedestrian" || l.type == "Cyclist";
        std::size_t points = 0;
        if (scored) {
          for (const auto& pt : cloud) {
            points += insideKittiTrackingBox(l, calib, Eigen::Vector3d(pt.x, pt.y, pt.z));
          }
        }
        MotGroundTruth g;
        g.id = id_base + static_cast<std::uint32_t>(l.track_id);
        g.position = kittiTrackingBoxCenterVelo(l, calib).head<2>();
        g.ignored = !scored || points < p.min_gt_points;
        gts.push_back(g);
      }
      std::vector<MotHypothesis> hyps;
      for (const Track& t : tracker.tracks()) {
        if (t.state != TrackState::kConfirmed) continue;
        if (p.params.classifier.enabled && t.category != ObjectCategory::kVehicle &&
            t.category != ObjectCategory::kPedestrian && t.category != ObjectCategory::kCyclist) {
          continue;
        }
        double u, v;
        if (!calib.project(t.center, &u, &v) || u < 0 || u >= width || v < 0 || v >= height) {
          continue;  // outside the labelled camera view
        }
        MotHypothesis h;
        h.id = id_base + t.id;
        h.position = t.center.head<2>();
        for (const KittiTrackingLabel& l : frame_labels) {
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
  out->frames = frames;
  out->sequences = sequences;
  out->tracker = mot.result();
  if (frames == 0) {
    *error = "no frames read from " + dir;
    return false;
  }
  return true;
}

bool evaluateSemanticKittiTracking(const TrackingEvalParams& p, const std::string& dir,
                                   SemanticKittiTrackingEvalResult* out, std::string* error) {
  const std::vector<std::string> seqs = semanticKittiSequences(dir);
  if (seqs.empty()) {
    *error = "no SemanticKITTI sequence (velodyne/) in " + dir;
    return false;
  }
  const std::unique_ptr<Pipeline> pipeline = trackingPipeline(p.params);
  ClearMot pooled, detections_pooled;
  SemanticKittiGroundTruthParams gt_params;
  gt_params.min_points = p.min_gt_points;
  std::vector<std::pair<std::string, ClearMotResult>>& per_sequence = out->per_sequence;
  per_sequence.clear();
  std::size_t frames = 0;
  std::uint32_t next_gt_id = 1, detection_ids = 0, id_base = 0;
  std::vector<double>& update_ms = out->update_ms;
  update_ms.clear();
  CloudXYZIRT cloud;
  std::vector<std::uint32_t> labels;
  EvalFrame gt;
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
    const Tracker& tracker = *pipeline->tracker();
    ClearMot mot;
    std::map<std::uint32_t, std::uint32_t> gt_id;  // full label (class | instance) -> GT id
    id_base += 1000000u;
    for (const std::string& bin : listFiles(seq + "/velodyne", ".bin")) {
      if (frames >= p.max_frames) break;
      const std::string stem = fs::path(bin).stem().string();
      std::size_t scan = 0;
      try {
        scan = static_cast<std::size_t>(std::stoul(stem));
      } catch (const std::exception&) {
        continue;
      }
      if (scan >= poses.size() || !readKittiBin(bin, &cloud, &error) ||
          !readSemanticKittiLabels(seq + "/labels/" + stem + ".label", &labels, &error) ||
          labels.size() != cloud.size()) {
        std::fprintf(stderr, "warning: skipping %s/%s: %s\n", name.c_str(), stem.c_str(),
                     scan >= poses.size() ? "no pose" : error.c_str());
        continue;
      }
      ++frames;
      buildSemanticKittiGroundTruth(labels, gt_params, &gt);
      const Eigen::Isometry3d& pose = poses[scan];
      const PipelineResult& result =
          pipeline->process(cloud, pose, 0.1 * static_cast<double>(scan));
      const std::vector<DetectedObject>& objects = result.objects;
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
      std::vector<MotGroundTruth> gts;
      for (std::size_t g = 0; g < gt.objects.size(); ++g) {
        if (count[g] == 0) continue;
        auto it = gt_id.find(label_of[g]);
        if (it == gt_id.end()) it = gt_id.emplace(label_of[g], next_gt_id++).first;
        MotGroundTruth m;
        m.id = it->second;
        m.position = (pose * (sum[g] / static_cast<double>(count[g]))).head<2>();
        m.ignored = gt.objects[g].ignored;
        gts.push_back(m);
      }
      // A detection made mostly of don't-care points (poles, trunks, unlabelled) is neither
      // true nor false when it matches nothing.
      auto dontCare = [&](const DetectedObject& o) {
        std::size_t dc = 0;
        for (const std::uint32_t i : o.indices) {
          dc += i < gt.role.size() && gt.role[i] == PointRole::kDontCare;
        }
        return 2 * dc > o.indices.size();
      };
      std::vector<MotHypothesis> hyps;
      for (const Track& t : tracker.tracks()) {
        if (t.state != TrackState::kConfirmed || t.detection < 0) continue;
        // Like the GT, the centroid of its detection's points (SemanticKITTI has no boxes; the
        // box centres are scored against KITTI's boxes by --kitti-object).
        const DetectedObject& o = objects[static_cast<std::size_t>(t.detection)];
        MotHypothesis h;
        h.id = id_base + t.id;
        h.position = (pose * o.centroid.cast<double>()).head<2>();
        h.dont_care = dontCare(o);
        hyps.push_back(h);
      }
      mot.addFrame(gts, hyps);
      pooled.addFrame(gts, hyps);
      std::vector<MotHypothesis> dets;
      for (const DetectedObject& o : objects) {
        MotHypothesis h;
        h.id = ++detection_ids;
        h.position = (pose * o.centroid.cast<double>()).head<2>();
        h.dont_care = dontCare(o);
        dets.push_back(h);
      }
      detections_pooled.addFrame(gts, dets);
    }
    if (mot.result().frames > 0) per_sequence.emplace_back(name, mot.result());
  }
  out->frames = frames;
  out->nominal_tr = any_nominal;
  out->tracker = pooled.result();
  out->detector = detections_pooled.result();
  if (frames == 0) {
    *error = "no scans read from " + dir;
    return false;
  }
  return true;
}

std::string simTrackingJson(const SimTrackingResult& r, const std::string& pcap) {
  std::ostringstream out;
  out << "{\n  \"dataset\": \"sim\",\n  \"pcap\": \"" << jsonEscape(pcap)
      << "\",\n  \"revolutions\": " << r.frames << ",\n  \"tracker\": " << motJson(r.tracker)
      << ",\n  \"detector_alone\": " << motJson(r.detector)
      << ",\n  \"tracker_on_ground_truth_boxes\": " << motJson(r.oracle)
      << ",\n  \"moving_vehicle_speed_error_mps\": {\"median\": "
      << jsonNumber(median(r.speed_error))
      << ", \"p90\": " << jsonNumber(percentile(r.speed_error, 0.9))
      << ", \"n\": " << r.speed_error.size()
      << "},\n  \"parked_vehicle_speed_mps\": {\"median\": " << jsonNumber(median(r.static_speed))
      << ", \"n\": " << r.static_speed.size()
      << "},\n  \"tracker_update_ms_median\": " << jsonNumber(median(r.update_ms)) << "\n}\n";
  return out.str();
}

std::string kittiTrackingJson(const KittiTrackingEvalResult& r, const std::string& dir) {
  std::ostringstream out;
  out << "{\n  \"dataset\": \"kitti_tracking\",\n  \"path\": \"" << jsonEscape(dir)
      << "\",\n  \"sequences\": " << r.sequences << ",\n  \"tracker\": " << motJson(r.tracker)
      << "\n}\n";
  return out.str();
}

std::string semanticKittiTrackingJson(const SemanticKittiTrackingEvalResult& r,
                                      const std::string& dir, std::size_t min_gt_points) {
  std::ostringstream out;
  out << "{\n  \"dataset\": \"semantic_kitti_tracking\",\n  \"path\": \"" << jsonEscape(dir)
      << "\",\n  \"scans\": " << r.frames << ",\n  \"min_gt_points\": " << min_gt_points
      << ",\n  \"nominal_tr\": " << (r.nominal_tr ? "true" : "false")
      << ",\n  \"tracker\": " << motJson(r.tracker)
      << ",\n  \"detector_alone\": " << motJson(r.detector) << ",\n  \"by_sequence\": {";
  for (std::size_t k = 0; k < r.per_sequence.size(); ++k) {
    out << (k ? ",\n    " : "\n    ") << "\"" << jsonEscape(r.per_sequence[k].first)
        << "\": " << motJson(r.per_sequence[k].second);
  }
  out << "\n  }\n}\n";
  return out.str();
}

std::string motLine(const char* what, const ClearMotResult& r) {
  std::string out;
  appendf(&out,
          "%-28s frames %4zu  GT %6zu  GT tracks %4zu  MOTA %.3f  MOTP %.3f m  recall %.3f  "
          "precision %.3f  FN %zu  FP %zu  IDSW %zu (%.2f per 100 GT tracks)  frag %zu  "
          "MT %zu  PT %zu  ML %zu\n",
          what, r.frames, r.gt, r.gt_tracks, r.mota(), r.motp_m(), r.recall(), r.precision(),
          r.misses, r.false_positives, r.id_switches, r.idSwitchesPer100GtTracks(),
          r.fragmentations, r.mostly_tracked, r.partially_tracked, r.mostly_lost);
  return out;
}

bool runTrackingEvaluation(const TrackingEvalParams& p, const TrackingEvalInput& in,
                           std::string* text, std::string* json, std::string* error) {
  text->clear();
  const char* classifier = p.params.classifier.enabled ? "on" : "off";
  if (!in.kitti_tracking_dir.empty()) {
    KittiTrackingEvalResult r;
    if (!evaluateKittiTracking(p, in.kitti_tracking_dir, &r, error)) return false;
    appendf(text,
            "tracking on KITTI tracking (%zu sequences, %zu frames), sensor frame (no poses)\n",
            r.sequences, r.frames);
    *text += motLine("tracker (confirmed tracks)", r.tracker);
    *json = kittiTrackingJson(r, in.kitti_tracking_dir);
    return true;
  }
  if (!in.semantic_kitti_dir.empty()) {
    SemanticKittiTrackingEvalResult r;
    if (!evaluateSemanticKittiTracking(p, in.semantic_kitti_dir, &r, error)) return false;
    appendf(text,
            "tracking on SemanticKITTI (%zu sequences, %zu scans), world frame (poses.txt%s), "
            "detector %s, classifier %s, min GT points %zu\n",
            r.per_sequence.size(), r.frames, r.nominal_tr ? ", nominal Tr" : ", calib Tr",
            p.params.detector.c_str(), classifier, p.min_gt_points);
    for (const auto& s : r.per_sequence)
      *text += motLine(("  sequence " + s.first).c_str(), s.second);
    *text += motLine("tracker, pooled", r.tracker);
    appendf(text, "%-28s recall %.3f  precision %.3f\n", "detector alone", r.detector.recall(),
            r.detector.precision());
    appendf(text, "tracker update: median %.4f ms per scan\n", median(r.update_ms));
    *json = semanticKittiTrackingJson(r, in.semantic_kitti_dir, p.min_gt_points);
    return true;
  }
  SimTrackingResult r;
  try {
    if (!evaluateSimTracking(p, in.sim_gt, in.sim_pcap, loadCalibration(in.calibration_path),
                             in.cut_angle_deg, &r, error))
      return false;
  } catch (const std::exception& e) {
    *error = e.what();
    return false;
  }
  appendf(text,
          "tracking on the simulated drive (%zu revolutions, %zu skipped), detector %s, "
          "classifier %s\n",
          r.frames, r.skipped, p.params.detector.c_str(), classifier);
  *text += motLine("tracker (confirmed tracks)", r.tracker);
  appendf(text,
          "%-28s recall %.3f  precision %.3f  (MOTA <= recall of the tracks; the detector "
          "bounds it unless coasting fills its gaps)\n",
          "detector alone", r.detector.recall(), r.detector.precision());
  *text += motLine("tracker on GT boxes", r.oracle);
  appendf(text,
          "speed error of matched moving cars/vans: median %.3f m/s, p90 %.3f m/s "
          "(%zu matches); speed of matched parked cars/vans: median %.3f m/s, p90 %.3f m/s "
          "(%zu)\n",
          median(r.speed_error), percentile(r.speed_error, 0.9), r.speed_error.size(),
          median(r.static_speed), percentile(r.static_speed, 0.9), r.static_speed.size());
  appendf(text,
          "tracker update: median %.4f ms, max %.4f ms per revolution (wall clock, with "
          "the pipeline around it)\n",
          median(r.update_ms),
          r.update_ms.empty() ? 0.0 : *std::max_element(r.update_ms.begin(), r.update_ms.end()));
  *json = simTrackingJson(r, in.sim_pcap);
  return true;
}

}  // namespace core
}  // namespace urban_detection
