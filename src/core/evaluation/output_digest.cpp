#include "urban_detection/core/evaluation/output_digest.h"

namespace urban_detection {
namespace core {

std::uint64_t detectionsDigest(ObjectDetector* det, const std::vector<LabeledCloud>& frames,
                               std::FILE* dump) {
  Fnv1aDigest d;
  std::vector<DetectedObject> objects;
  for (std::size_t frame = 0; frame < frames.size(); ++frame) {
    det->detect(frames[frame], &objects);
    d.add(static_cast<std::uint64_t>(objects.size()));
    for (const DetectedObject& o : objects) {
      d.add(o.id);
      d.add(static_cast<std::uint64_t>(o.indices.size()));
      for (const std::uint32_t i : o.indices) d.add(i);
      d.add(o.centroid);
      d.add(o.min_pt);
      d.add(o.max_pt);
      d.add(o.obb_center);
      d.add(o.obb_size);
      d.add(o.obb_yaw_rad);
      if (!dump) continue;
      std::fprintf(dump, "%zu %u %zu", frame, o.id, o.indices.size());
      for (const Eigen::Vector3f* v :
           {&o.centroid, &o.min_pt, &o.max_pt, &o.obb_center, &o.obb_size}) {
        std::fprintf(dump, " %.9g %.9g %.9g", (*v)[0], (*v)[1], (*v)[2]);
      }
      std::fprintf(dump, " %.9g\n", o.obb_yaw_rad);
    }
  }
  return d.value();
}

}  // namespace core
}  // namespace urban_detection
