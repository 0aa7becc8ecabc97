#include "urban_detection/core/evaluation/eval_datasets.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include <Eigen/Geometry>

#include "urban_detection/core/common/object_class.h"

namespace urban_detection {
namespace core {

namespace {

void setError(std::string* error, const std::string& what) {
  if (error) *error = what;
}

}  // namespace

// ------------------------------------------------------------------------------------------
// Point cloud files

std::vector<std::string> listFiles(const std::string& dir, const std::string& suffix) {
  std::vector<std::string> files;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.size() >= suffix.size() &&
        name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0) {
      files.push_back(e.path().string());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::vector<std::string> semanticKittiSequences(const std::string& dir) {
  if (std::filesystem::is_directory(dir + "/velodyne")) return {dir};
  std::vector<std::string> seqs;
  for (const auto& s : listFiles(dir + "/sequences", "")) {
    if (std::filesystem::is_directory(s + "/velodyne")) seqs.push_back(s);
  }
  return seqs;
}

// ------------------------------------------------------------------------------------------
// KITTI object

Eigen::Vector3d KittiCalibration::veloToRect(const Eigen::Vector3d& p_velo) const {
  return r0_rect * (tr_velo_to_cam.leftCols<3>() * p_velo + tr_velo_to_cam.col(3));
}

Eigen::Vector3d KittiCalibration::rectToVelo(const Eigen::Vector3d& p_rect) const {
  const Eigen::Vector3d p_cam = r0_rect.inverse() * p_rect;
  return tr_velo_to_cam.leftCols<3>().inverse() * (p_cam - tr_velo_to_cam.col(3));
}

bool KittiCalibration::project(const Eigen::Vector3d& p_velo, double* u, double* v,
                               double min_depth_m) const {
  const Eigen::Vector3d r = veloToRect(p_velo);
  if (!(r.z() > min_depth_m)) return false;
  const Eigen::Vector3d uvw = p2.leftCols<3>() * r + p2.col(3);
  if (!(uvw.z() > 0.0)) return false;
  *u = uvw.x() / uvw.z();
  *v = uvw.y() / uvw.z();
  return std::isfinite(*u) && std::isfinite(*v);
}

bool readKittiCalibration(const std::string& path, KittiCalibration* calib, std::string* error) {
  std::ifstream in(path);
  if (!in) {
    setError(error, "cannot open " + path);
    return false;
  }
  std::map<std::string, std::vector<double>> rows;
  std::string line;
  while (std::getline(in, line)) {
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    std::istringstream ss(line.substr(colon + 1));
    std::vector<double> values;
    double v;
    while (ss >> v) values.push_back(v);
    rows[line.substr(0, colon)] = values;
  }
  auto need = [&](const char* key, std::size_t count) -> const std::vector<double>* {
    auto it = rows.find(key);
    if (it == rows.end() || it->second.size() != count) {
      setError(error, path + ": missing or malformed " + key + " (need " + std::to_string(count) +
                          " numbers)");
      return nullptr;
    }
    for (double x : it->second) {
      if (!std::isfinite(x)) {
        setError(error, path + ": non-finite value in " + key);
        return nullptr;
      }
    }
    return &it->second;
  };
  const auto* p2 = need("P2", 12);
  if (!p2) return false;
  const auto* r0 = need("R0_rect", 9);
  if (!r0) return false;
  const auto* tr = need("Tr_velo_to_cam", 12);
  if (!tr) return false;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) {
      calib->p2(r, c) = (*p2)[r * 4 + c];
      calib->tr_velo_to_cam(r, c) = (*tr)[r * 4 + c];
    }
    for (int c = 0; c < 3; ++c) calib->r0_rect(r, c) = (*r0)[r * 3 + c];
  }
  if (std::abs(calib->r0_rect.determinant()) < 1e-6 ||
      std::abs(calib->tr_velo_to_cam.leftCols<3>().determinant()) < 1e-6) {
    setError(error, path + ": singular R0_rect or Tr_velo_to_cam rotation");
    return false;
  }
  return true;
}

bool parseKittiLabelLine(const std::string& line, KittiLabel* label) {
  std::istringstream ss(line);
  KittiLabel l;
  if (!(ss >> l.type >> l.truncated >> l.occluded >> l.alpha >> l.bbox[0] >> l.bbox[1] >>
        l.bbox[2] >> l.bbox[3] >> l.height_m >> l.width_m >> l.length_m >> l.location.x() >>
        l.location.y() >> l.location.z() >> l.rotation_y)) {
    return false;
  }
  *label = l;
  return true;
}

bool readKittiLabels(const std::string& path, std::vector<KittiLabel>* labels, std::string* error) {
  std::ifstream in(path);
  if (!in) {
    setError(error, "cannot open " + path);
    return false;
  }
  labels->clear();
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    KittiLabel l;
    if (!parseKittiLabelLine(line, &l)) {
      setError(error, path + ":" + std::to_string(number) + ": malformed label line");
      return false;
    }
    labels->push_back(l);
  }
  return true;
}

Eigen::Vector3d kittiBoxLocal(const KittiLabel& label, const Eigen::Vector3d& p_rect) {
  // KITTI rotates a box by rotation_y about the camera y axis (pointing down):
  // p = Ry * local + location with Ry = [c 0 s; 0 1 0; -s 0 c]; invert with Ry^T. The box
  // frame's y is flipped so that it points up from the bottom face.
  const Eigen::Vector3d d = p_rect - label.location;
  const double c = std::cos(label.rotation_y), s = std::sin(label.rotation_y);
  return {c * d.x() - s * d.z(), -d.y(), s * d.x() + c * d.z()};
}

std::array<Eigen::Vector3d, 8> kittiBoxCornersVelo(const KittiLabel& label,
                                                   const KittiCalibration& calib) {
  const double c = std::cos(label.rotation_y), s = std::sin(label.rotation_y);
  const double hl = label.length_m / 2.0, hw = label.width_m / 2.0;
  const double xs[4] = {hl, hl, -hl, -hl};
  const double zs[4] = {hw, -hw, -hw, hw};
  std::array<Eigen::Vector3d, 8> corners;
  for (int k = 0; k < 8; ++k) {
    const double lx = xs[k % 4], lz = zs[k % 4];
    const double ly = k < 4 ? 0.0 : -label.height_m;  // camera y points down
    const Eigen::Vector3d rect(c * lx + s * lz + label.location.x(), ly + label.location.y(),
                               -s * lx + c * lz + label.location.z());
    corners[k] = calib.rectToVelo(rect);
  }
  return corners;
}

bool inKittiCameraFrustum(const KittiCalibration& calib, const Eigen::Vector3d& p_velo,
                          int width_px, int height_px) {
  double u, v;
  if (!calib.project(p_velo, &u, &v)) return false;
  return u >= 0.0 && u < width_px && v >= 0.0 && v < height_px;
}

void buildKittiGroundTruth(const CloudXYZIRT& cloud, const std::vector<KittiLabel>& labels,
                           const KittiCalibration& calib, const KittiGroundTruthParams& params,
                           int width_px, int height_px, EvalFrame* gt) {
  gt->reset(cloud.size());
  std::vector<const KittiLabel*> boxes, dont_care;
  for (std::size_t i = 0; i < labels.size(); ++i) {
    if (labels[i].type == "DontCare") {
      dont_care.push_back(&labels[i]);
      continue;
    }
    boxes.push_back(&labels[i]);
    EvalObject o;
    o.label = labels[i].type;
    o.id = static_cast<std::uint32_t>(i + 1);  // line number in label_2
    gt->objects.push_back(o);
  }
  const double m = params.box_margin_m;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const auto& p = cloud[i];
    if (!isFinitePoint(p)) {
      gt->role[i] = PointRole::kExcluded;
      continue;
    }
    const Eigen::Vector3d pv(p.x, p.y, p.z);
    const Eigen::Vector3d pr = calib.veloToRect(pv);
    bool in_box = false;
    for (std::size_t b = 0; b < boxes.size() && !in_box; ++b) {
      const KittiLabel& l = *boxes[b];
      const Eigen::Vector3d q = kittiBoxLocal(l, pr);
      if (std::abs(q.x()) <= l.length_m / 2.0 + m && std::abs(q.z()) <= l.width_m / 2.0 + m &&
          q.y() >= -m && q.y() <= l.height_m + m) {
        in_box = true;
        if (q.y() < params.ground_band_m) {
          gt->role[i] = PointRole::kExcluded;  // the road under the object
        } else {
          gt->object_of_point[i] = static_cast<std::int32_t>(b);
        }
      }
    }
    if (in_box) continue;
    double u, v;
    if (!calib.project(pv, &u, &v) || u < 0.0 || u >= width_px || v < 0.0 || v >= height_px) {
      gt->role[i] = PointRole::kDontCare;  // not labelled: outside the camera's view
      continue;
    }
    for (const KittiLabel* d : dont_care) {
      if (u >= d->bbox[0] && u <= d->bbox[2] && v >= d->bbox[1] && v <= d->bbox[3]) {
        gt->role[i] = PointRole::kDontCare;
        break;
      }
    }
  }
  gt->finalize(params.min_points);
}

bool readPngSize(const std::string& path, int* width_px, int* height_px) {
  std::ifstream in(path, std::ios::binary);
  unsigned char h[24];
  if (!in.read(reinterpret_cast<char*>(h), sizeof(h))) return false;
  static const unsigned char kSig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (std::memcmp(h, kSig, 8) != 0 || std::memcmp(h + 12, "IHDR", 4) != 0) return false;
  auto be32 = [](const unsigned char* b) {
    return (std::uint32_t(b[0]) << 24) | (std::uint32_t(b[1]) << 16) | (std::uint32_t(b[2]) << 8) |
           std::uint32_t(b[3]);
  };
  const std::uint32_t w = be32(h + 16), hh = be32(h + 20);
  if (w == 0 || hh == 0 || w > 100000 || hh > 100000) return false;
  *width_px = static_cast<int>(w);
  *height_px = static_cast<int>(hh);
  return true;
}

// ------------------------------------------------------------------------------------------
// SemanticKITTI

SemanticKittiCategory semanticKittiCategory(std::uint16_t c) {
  switch (c) {
    case 10:
    case 11:
    case 13:
    case 15:
    case 16:
    case 18:
    case 20:  // vehicles
    case 30:
    case 31:
    case 32:  // person, riders
    case 252:
    case 253:
    case 254:
    case 255:
    case 256:
    case 257:
    case 258:
    case 259:  // moving
      return SemanticKittiCategory::kThing;
    case 0:
    case 1:  // unlabeled, outlier
    case 71:
    case 80:
    case 81:  // trunk, pole, traffic-sign
    case 99:  // other-object
      return SemanticKittiCategory::kDontCare;
    default:  // building 50, fence 51, other-structure 52, vegetation 70, ground 40-49/60/72
      return SemanticKittiCategory::kBackground;
  }
}

bool readSemanticKittiPoses(const std::string& seq_dir, std::vector<Eigen::Isometry3d>* out,
                            bool* nominal_tr, std::string* error) {
  out->clear();
  Eigen::Isometry3d tr = Eigen::Isometry3d::Identity();
  tr.linear() << 0, -1, 0, 0, 0, -1, 1, 0, 0;
  *nominal_tr = true;
  {
    std::ifstream in(seq_dir + "/calib.txt");
    std::string line;
    while (std::getline(in, line)) {
      std::istringstream ls(line);
      std::string key;
      ls >> key;
      if (key != "Tr:" && key != "Tr") continue;
      double v[12];
      int k = 0;
      while (k < 12 && (ls >> v[k]) && std::isfinite(v[k])) ++k;
      if (k != 12) {
        setError(error, seq_dir + "/calib.txt: Tr needs 12 numbers");
        return false;
      }
      Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
      for (int j = 0; j < 12; ++j) m(j / 4, j % 4) = v[j];
      tr.matrix() = m;
      *nominal_tr = false;
    }
  }
  std::ifstream in(seq_dir + "/poses.txt");
  if (!in) {
    setError(error, seq_dir + "/poses.txt: cannot open");
    return false;
  }
  const Eigen::Isometry3d tr_inv = tr.inverse();
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::istringstream ls(line);
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    for (int j = 0; j < 12; ++j) {
      if (!(ls >> m(j / 4, j % 4)) || !std::isfinite(m(j / 4, j % 4))) {
        setError(error, seq_dir + "/poses.txt:" + std::to_string(number) + ": needs 12 numbers");
        return false;
      }
    }
    Eigen::Isometry3d pose;
    pose.matrix() = m;
    out->push_back(tr_inv * pose * tr);
  }
  return true;
}

std::string semanticKittiClassName(std::uint16_t c) {
  switch (c) {
    case 0:
      return "unlabeled";
    case 1:
      return "outlier";
    case 10:
      return "car";
    case 11:
      return "bicycle";
    case 13:
      return "bus";
    case 15:
      return "motorcycle";
    case 16:
      return "on-rails";
    case 18:
      return "truck";
    case 20:
      return "other-vehicle";
    case 30:
      return "person";
    case 31:
      return "bicyclist";
    case 32:
      return "motorcyclist";
    case 40:
      return "road";
    case 44:
      return "parking";
    case 48:
      return "sidewalk";
    case 49:
      return "other-ground";
    case 50:
      return "building";
    case 51:
      return "fence";
    case 52:
      return "other-structure";
    case 60:
      return "lane-marking";
    case 70:
      return "vegetation";
    case 71:
      return "trunk";
    case 72:
      return "terrain";
    case 80:
      return "pole";
    case 81:
      return "traffic-sign";
    case 99:
      return "other-object";
    case 252:
      return "moving-car";
    case 253:
      return "moving-bicyclist";
    case 254:
      return "moving-person";
    case 255:
      return "moving-motorcyclist";
    case 256:
      return "moving-on-rails";
    case 257:
      return "moving-bus";
    case 258:
      return "moving-truck";
    case 259:
      return "moving-other-vehicle";
    default:
      return "class_" + std::to_string(c);
  }
}

void buildSemanticKittiGroundTruth(const std::vector<std::uint32_t>& labels,
                                   const SemanticKittiGroundTruthParams& params, EvalFrame* gt) {
  gt->reset(labels.size());
  std::map<std::uint32_t, std::int32_t> object_of_label;  // full label (class|instance) -> GT
  for (std::size_t i = 0; i < labels.size(); ++i) {
    const std::uint16_t c = semanticKittiClass(labels[i]);
    const std::uint16_t inst = semanticKittiInstance(labels[i]);
    switch (semanticKittiCategory(c)) {
      case SemanticKittiCategory::kThing: {
        if (inst == 0) {
          gt->role[i] = PointRole::kDontCare;  // a thing without an instance label
          break;
        }
        auto it = object_of_label.find(labels[i]);
        if (it == object_of_label.end()) {
          EvalObject o;
          o.label = semanticKittiClassName(c);
          o.id = inst;
          it = object_of_label.emplace(labels[i], static_cast<std::int32_t>(gt->objects.size()))
                   .first;
          gt->objects.push_back(o);
        }
        gt->object_of_point[i] = it->second;
        break;
      }
      case SemanticKittiCategory::kDontCare:
        gt->role[i] = PointRole::kDontCare;
        break;
      case SemanticKittiCategory::kBackground:
        break;
    }
  }
  gt->finalize(params.min_points);
}

// ------------------------------------------------------------------------------------------
// Simulated drives

void buildSimulatedGroundTruth(const GroundTruthFrame& frame,
                               const SimulatedGroundTruthParams& params, EvalFrame* gt) {
  const std::size_t n = frame.instance_ids.size();
  gt->reset(n);
  std::map<std::uint32_t, std::int32_t> object_of_instance;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t id = frame.instance_ids[i];
    const auto cls = static_cast<ObjectClass>(i < frame.classes.size() ? frame.classes[i] : 0);
    // Scored background: ground, terrain, walls and foliage (crowns, hedges, bushes), as
    // SemanticKITTI's vegetation and terrain.
    if (id == 0 || cls == ObjectClass::kGround || cls == ObjectClass::kWall ||
        cls == ObjectClass::kTerrain || cls == ObjectClass::kVegetation) {
      continue;
    }
    if (!isStreetObject(cls)) {
      gt->role[i] = PointRole::kDontCare;  // trunks, poles, signs
      continue;
    }
    auto it = object_of_instance.find(id);
    if (it == object_of_instance.end()) {
      EvalObject o;
      o.label = toString(cls);
      o.id = id;
      it = object_of_instance.emplace(id, static_cast<std::int32_t>(gt->objects.size())).first;
      gt->objects.push_back(o);
    }
    gt->object_of_point[i] = it->second;
  }
  gt->finalize(params.min_points);
}

SimulatedDriveReader::SimulatedDriveReader(const std::string& pcap_path, const std::string& gt_path,
                                           const Calibration& calibration, double cut_angle_deg,
                                           const DecoderParams& decoder_params)
    : pcap_(pcap_path, cut_angle_deg), gt_reader_(gt_path), decoder_(calibration, decoder_params) {}

bool SimulatedDriveReader::fillWindow(double stamp_s) {
  // Drop frames older than this revolution (revolutions the pcap does not hold), then read
  // until the window reaches past its stamp.
  constexpr double kTolS = 5e-5;  // findGroundTruthFrame's default tolerance
  while (!window_.empty() && window_.front().stamp_s < stamp_s - kTolS) {
    window_.erase(window_.begin());
  }
  while (!gt_end_ && (window_.empty() || window_.back().stamp_s <= stamp_s + kTolS)) {
    GroundTruthFrame f;
    const GroundTruthReader::Result r = gt_reader_.next(&f);
    if (r != GroundTruthReader::Result::kFrame) {
      gt_end_ = true;
      if (r == GroundTruthReader::Result::kCorrupt) end_message_ = gt_reader_.error();
      break;
    }
    if (f.stamp_s < stamp_s - kTolS) continue;
    window_.push_back(std::move(f));
  }
  return !window_.empty();
}

SimulatedDriveReader::Result SimulatedDriveReader::next(CloudXYZIRT* cloud, GroundTruthFrame* gt,
                                                        std::string* message) {
  message->clear();
  cloud->clear();
  const PcapRevolutionReader::Result r = pcap_.next(&packets_);
  if (r != PcapRevolutionReader::Result::kRevolution) {
    if (r == PcapRevolutionReader::Result::kTruncated) end_message_ = "truncated pcap";
    *message = end_message_;
    return Result::kEnd;
  }
  const double stamp_s = packets_.front().stamp_s;
  for (const PcapPacket& p : packets_) {
    if (decoder_.decode(p.data.data(), p.data.size(), p.stamp_s - stamp_s, cloud, nullptr) !=
        PacketStatus::kOk) {
      ++bad_packets_;
    }
  }
  char stamp[32];
  std::snprintf(stamp, sizeof(stamp), "%.6f", stamp_s);
  if (!fillWindow(stamp_s)) {
    *message = std::string("revolution at ") + stamp + " s: no ground-truth frame left";
    return Result::kSkipped;
  }
  const std::ptrdiff_t k = findGroundTruthFrame(window_, stamp_s);
  if (k < 0) {
    *message = std::string("revolution at ") + stamp +
               " s: no ground-truth frame of this stamp (partial revolution?)";
    return Result::kSkipped;
  }
  if (window_[k].instance_ids.size() != cloud->size()) {
    *message = std::string("revolution at ") + stamp + " s: " + std::to_string(cloud->size()) +
               " decoded points but " + std::to_string(window_[k].instance_ids.size()) +
               " labels in its ground-truth frame";
    window_.erase(window_.begin(), window_.begin() + k + 1);
    return Result::kSkipped;
  }
  *gt = std::move(window_[k]);
  window_.erase(window_.begin(), window_.begin() + k + 1);
  return Result::kFrame;
}

}  // namespace core
}  // namespace urban_detection
