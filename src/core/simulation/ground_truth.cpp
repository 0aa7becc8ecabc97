#include "urban_detection/core/simulation/ground_truth.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "urban_detection/core/simulation/lidar_simulator.h"

namespace urban_detection {
namespace core {

namespace {

constexpr char kFileMagic[4] = {'U', 'D', 'G', 'T'};
constexpr char kFrameMagic[4] = {'G', 'T', 'F', 'R'};
constexpr std::uint32_t kVersion = 1;
constexpr std::uint32_t kMaxPoints = 16u * 1024u * 1024u;  // sanity bound per frame
constexpr std::uint32_t kMaxObjects = 1u << 20;

// The format is little-endian; the hosts we build for (x86-64, arm64) are too.
template <typename T>
void put(std::ofstream& o, const T& v) {
  o.write(reinterpret_cast<const char*>(&v), sizeof(T));
}
template <typename T>
bool get(std::ifstream& i, T* v) {
  return static_cast<bool>(i.read(reinterpret_cast<char*>(v), sizeof(T)));
}

}  // namespace

std::ptrdiff_t findGroundTruthFrame(const std::vector<GroundTruthFrame>& frames, double stamp_s,
                                    double tolerance_s) {
  const auto it =
      std::lower_bound(frames.begin(), frames.end(), stamp_s - tolerance_s,
                       [](const GroundTruthFrame& f, double s) { return f.stamp_s < s; });
  if (it == frames.end() || std::abs(it->stamp_s - stamp_s) > tolerance_s) return -1;
  return it - frames.begin();
}

void makeGroundTruthFrame(const LidarSimulator& sim, const SimRevolution& rev,
                          GroundTruthFrame* frame) {
  frame->revolution = rev.index;
  frame->stamp_s = rev.stamp_s;
  frame->num_packets = static_cast<std::uint32_t>(rev.packets.size());
  frame->sensor_pose = sim.sensorPose(rev.start_time_s);
  frame->instance_ids = rev.instance_ids;
  frame->classes = rev.classes;
  const Scene& scene = sim.scene();
  frame->objects.resize(scene.objects.size());
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    const SceneObject& so = scene.objects[i];
    GroundTruthObject& g = frame->objects[i];
    g.instance_id = so.instance_id;
    g.object_class = so.object_class;
    const Eigen::Vector3d pos = so.position + so.velocity * rev.start_time_s;
    g.center = (pos + Eigen::Vector3d(0, 0, 0.5 * so.size.z())).cast<float>();
    g.size = so.size.cast<float>();
    g.yaw_rad = static_cast<float>(so.yaw_rad);
    g.velocity = so.velocity.cast<float>();
    g.num_points = 0;
  }
  for (std::uint32_t id : rev.instance_ids) {
    if (id >= 1 && id <= frame->objects.size()) ++frame->objects[id - 1].num_points;
  }
}

GroundTruthWriter::GroundTruthWriter(const std::string& path)
    : path_(path), out_(path, std::ios::binary | std::ios::trunc) {
  if (!out_) throw GroundTruthError("ground truth: cannot create " + path);
  out_.write(kFileMagic, 4);
  put(out_, kVersion);
}

void GroundTruthWriter::write(const GroundTruthFrame& f) {
  if (f.classes.size() != f.instance_ids.size()) {
    throw GroundTruthError("ground truth: instance_ids and classes differ in length");
  }
  out_.write(kFrameMagic, 4);
  put(out_, f.revolution);
  put(out_, f.stamp_s);
  put(out_, f.num_packets);
  const Eigen::Vector3d t = f.sensor_pose.translation();
  const Eigen::Quaterniond q(f.sensor_pose.linear());
  const double pose[7] = {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()};
  out_.write(reinterpret_cast<const char*>(pose), sizeof(pose));
  put(out_, static_cast<std::uint32_t>(f.instance_ids.size()));
  out_.write(reinterpret_cast<const char*>(f.instance_ids.data()),
             static_cast<std::streamsize>(f.instance_ids.size() * sizeof(std::uint32_t)));
  out_.write(reinterpret_cast<const char*>(f.classes.data()),
             static_cast<std::streamsize>(f.classes.size()));
  put(out_, static_cast<std::uint32_t>(f.objects.size()));
  for (const GroundTruthObject& o : f.objects) {
    put(out_, o.instance_id);
    const std::uint8_t cls[4] = {static_cast<std::uint8_t>(o.object_class), 0, 0, 0};
    out_.write(reinterpret_cast<const char*>(cls), 4);
    out_.write(reinterpret_cast<const char*>(o.center.data()), 12);
    out_.write(reinterpret_cast<const char*>(o.size.data()), 12);
    put(out_, o.yaw_rad);
    out_.write(reinterpret_cast<const char*>(o.velocity.data()), 12);
    put(out_, o.num_points);
  }
  if (!out_) throw GroundTruthError("ground truth: write failed on " + path_);
}

void GroundTruthWriter::close() {
  out_.close();
}

GroundTruthReader::GroundTruthReader(const std::string& path)
    : path_(path), in_(path, std::ios::binary) {
  if (!in_) throw GroundTruthError("ground truth: cannot open " + path);
  char magic[4];
  std::uint32_t version = 0;
  if (!in_.read(magic, 4) || std::memcmp(magic, kFileMagic, 4) != 0) {
    throw GroundTruthError("ground truth: " + path + " is not a ground-truth file (bad magic)");
  }
  if (!get(in_, &version) || version != kVersion) {
    throw GroundTruthError("ground truth: " + path + " has unsupported version " +
                           std::to_string(version));
  }
}

GroundTruthReader::Result GroundTruthReader::next(GroundTruthFrame* f) {
  char magic[4];
  if (!in_.read(magic, 4)) {
    if (in_.gcount() == 0) return Result::kEnd;
    error_ = path_ + ": truncated frame header";
    return Result::kCorrupt;
  }
  if (std::memcmp(magic, kFrameMagic, 4) != 0) {
    error_ = path_ + ": bad frame magic";
    return Result::kCorrupt;
  }
  double pose[7];
  std::uint32_t n = 0, m = 0;
  if (!get(in_, &f->revolution) || !get(in_, &f->stamp_s) || !get(in_, &f->num_packets) ||
      !in_.read(reinterpret_cast<char*>(pose), sizeof(pose)) || !get(in_, &n)) {
    error_ = path_ + ": truncated frame header";
    return Result::kCorrupt;
  }
  if (n > kMaxPoints) {
    error_ = path_ + ": implausible point count " + std::to_string(n);
    return Result::kCorrupt;
  }
  Eigen::Quaterniond q(pose[6], pose[3], pose[4], pose[5]);
  if (!(std::abs(q.norm() - 1.0) < 1e-3)) {
    error_ = path_ + ": sensor pose quaternion not normalised";
    return Result::kCorrupt;
  }
  f->sensor_pose = Eigen::Isometry3d::Identity();
  f->sensor_pose.linear() = q.normalized().toRotationMatrix();
  f->sensor_pose.translation() = Eigen::Vector3d(pose[0], pose[1], pose[2]);
  f->instance_ids.resize(n);
  f->classes.resize(n);
  if (!in_.read(reinterpret_cast<char*>(f->instance_ids.data()),
                static_cast<std::streamsize>(n * sizeof(std::uint32_t))) ||
      !in_.read(reinterpret_cast<char*>(f->classes.data()), n) || !get(in_, &m)) {
    error_ = path_ + ": truncated point labels";
    return Result::kCorrupt;
  }
  if (m > kMaxObjects) {
    error_ = path_ + ": implausible object count " + std::to_string(m);
    return Result::kCorrupt;
  }
  f->objects.resize(m);
  for (GroundTruthObject& o : f->objects) {
    std::uint8_t cls[4];
    if (!get(in_, &o.instance_id) || !in_.read(reinterpret_cast<char*>(cls), 4) ||
        !in_.read(reinterpret_cast<char*>(o.center.data()), 12) ||
        !in_.read(reinterpret_cast<char*>(o.size.data()), 12) || !get(in_, &o.yaw_rad) ||
        !in_.read(reinterpret_cast<char*>(o.velocity.data()), 12) || !get(in_, &o.num_points)) {
      error_ = path_ + ": truncated object list";
      return Result::kCorrupt;
    }
    o.object_class = static_cast<ObjectClass>(cls[0]);
  }
  for (std::uint8_t c : f->classes) {
    if (c >= kNumObjectClasses) {
      error_ = path_ + ": unknown class value " + std::to_string(c);
      return Result::kCorrupt;
    }
  }
  return Result::kFrame;
}

std::vector<GroundTruthFrame> GroundTruthReader::readAll(const std::string& path) {
  GroundTruthReader reader(path);
  std::vector<GroundTruthFrame> frames;
  GroundTruthFrame f;
  for (;;) {
    const Result r = reader.next(&f);
    if (r == Result::kEnd) break;
    if (r == Result::kCorrupt) throw GroundTruthError("ground truth: " + reader.error());
    frames.push_back(f);
  }
  return frames;
}

}  // namespace core
}  // namespace urban_detection
