#include "urban_detection/core/evaluation/detection_diagnostics.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace urban_detection {
namespace core {

void diagnose(const Frame& f, const Dataset& ds, const std::vector<SegmentClass>& seg,
              const std::vector<DetectedObject>& dets, const FrameMatch& m,
              const std::vector<DetectedObject>& classifier_rejected, const std::string& detector,
              DetectionDiagnostics* diag, std::FILE* out) {
  const std::size_t n = f.cloud.size();
  // Points of the detections the classifier rejected: the object it took, if any.
  std::vector<std::int32_t> rejected_of_point(n, -1);
  for (std::size_t d = 0; d < classifier_rejected.size(); ++d) {
    for (std::uint32_t idx : classifier_rejected[d].indices) {
      if (idx < n) rejected_of_point[idx] = static_cast<std::int32_t>(d);
    }
  }
  std::vector<std::int32_t> det_of_point(n, -1);
  for (std::size_t d = 0; d < dets.size(); ++d) {
    for (std::uint32_t idx : dets[d].indices) {
      if (idx < n) det_of_point[idx] = static_cast<std::int32_t>(d);
    }
  }
  const bool has_roles = f.gt.role.size() == n;
  // Points of each GT object.
  std::vector<std::vector<std::uint32_t>> pts(f.gt.objects.size());
  for (std::size_t i = 0; i < n; ++i) {
    const std::int32_t g = f.gt.object_of_point[i];
    if (g >= 0 && !(has_roles && f.gt.role[i] == PointRole::kExcluded)) {
      pts[g].push_back(static_cast<std::uint32_t>(i));
    }
  }
  for (std::size_t g = 0; g < f.gt.objects.size(); ++g) {
    const EvalObject& o = f.gt.objects[g];
    if (o.ignored || m.matched_detection[g] >= 0 || pts[g].empty()) continue;
    std::map<SegmentClass, std::size_t> seg_count;
    std::map<std::int32_t, std::size_t> det_count;
    double cx = 0, cy = 0;
    for (std::uint32_t i : pts[g]) {
      ++seg_count[i < seg.size() ? seg[i] : SegmentClass::kUnknown];
      if (det_of_point[i] >= 0) ++det_count[det_of_point[i]];
      cx += f.cloud[i].x;
      cy += f.cloud[i].y;
    }
    const double np = static_cast<double>(pts[g].size());
    const double range = std::hypot(cx / np, cy / np);
    const std::size_t fg = seg_count[SegmentClass::kShort];
    std::string cause;
    if (fg < 0.5 * np) {
      SegmentClass worst = SegmentClass::kUnknown;
      std::size_t most = 0;
      for (const auto& kv : seg_count) {
        if (kv.first != SegmentClass::kShort && kv.second > most) {
          most = kv.second;
          worst = kv.first;
        }
      }
      cause = std::string("segmentation:not_foreground(") + toString(worst) + ")";
    } else {
      std::int32_t best = -1;
      std::size_t best_n = 0, in_dets = 0;
      for (const auto& kv : det_count) {
        in_dets += kv.second;
        if (kv.second > best_n) {
          best_n = kv.second;
          best = kv.first;
        }
      }
      if (in_dets < 0.5 * fg) {
        std::size_t in_rejected = 0;
        for (std::uint32_t i : pts[g]) in_rejected += rejected_of_point[i] >= 0;
        cause = in_rejected >= 0.5 * fg ? "classifier:rejected_as_non_object"
                                        : "detector:dropped(small_or_noise)";
      } else if (best_n >= 0.5 * np) {
        // Holds most of the object but IoU < 0.5: the detection is much larger.
        std::map<std::string, std::size_t> content;
        for (std::uint32_t i : dets[best].indices) {
          if (i >= n) continue;
          const std::int32_t og = f.gt.object_of_point[i];
          if (og == static_cast<std::int32_t>(g)) continue;
          content[og >= 0 ? "other_object" : ds.className(f.point_class[i])]++;
        }
        cause = "detector:merged_with(" + mostCommon(content) + ")";
      } else if (det_count.size() >= 2) {
        cause = "detector:split";
      } else {
        cause = "partly_foreground";
      }
    }
    ++diag->missed_by_cause[cause];
    if (out) {
      // The detections holding its points: "points of this object/detection size" each.
      std::string pieces;
      for (const auto& kv : det_count) {
        pieces +=
            " " + std::to_string(kv.second) + "/" + std::to_string(dets[kv.first].indices.size());
      }
      std::fprintf(
          out,
          "  %s %-18s missed %-12s id %-5u %6zu pts %5.1f m (%.1f, %.1f)  fg %3.0f%%  %s  in:%s\n",
          f.id.c_str(), detector.c_str(), o.label.c_str(), o.id, pts[g].size(), range, cx / np,
          cy / np, 100.0 * fg / np, cause.c_str(), pieces.c_str());
    }
  }
  for (std::size_t d = 0; d < dets.size(); ++d) {
    if (m.verdict[d] != DetectionVerdict::kFalse) continue;
    const std::string what = detectionContent(f, ds, dets[d]);
    ++diag->false_by_class[what];
    // A false detection made mostly of a GT object's points: a merge of several objects, the
    // leftover of an object matched by another detection, or a piece of a missed object; with
    // the segmentation of the object's points outside this detection (what cut it off).
    std::string fragment;
    if (what.compare(0, 8, "part_of_") == 0) {
      std::map<std::int32_t, std::size_t> gt_count;
      for (std::uint32_t i : dets[d].indices) {
        if (i < n && f.gt.object_of_point[i] >= 0) ++gt_count[f.gt.object_of_point[i]];
      }
      std::int32_t g = -1;
      std::size_t gn = 0, objects_over_10 = 0;
      for (const auto& kv : gt_count) {
        if (kv.second >= 10) ++objects_over_10;
        if (kv.second > gn) {
          gn = kv.second;
          g = kv.first;
        }
      }
      std::map<SegmentClass, std::size_t> rest_seg;
      std::size_t rest_in_other_det = 0;
      for (std::uint32_t i : pts[g]) {
        if (det_of_point[i] == static_cast<std::int32_t>(d)) continue;
        ++rest_seg[i < seg.size() ? seg[i] : SegmentClass::kUnknown];
        if (det_of_point[i] >= 0) ++rest_in_other_det;
      }
      fragment = objects_over_10 >= 2          ? "merge"
                 : m.matched_detection[g] >= 0 ? "leftover_of_matched"
                 : 2 * gn >= pts[g].size()     ? "most_of_missed"
                                               : "piece_of_missed";
      ++diag->false_fragments[fragment];
      if (out) {
        char buf[160];
        std::snprintf(buf, sizeof(buf), " %s gt %u %zu/%zu, rest: other det %zu", fragment.c_str(),
                      f.gt.objects[g].id, gn, pts[g].size(), rest_in_other_det);
        fragment = buf;
        for (const auto& kv : rest_seg) {
          fragment += std::string(" ") + toString(kv.first) + " " + std::to_string(kv.second);
        }
        float zmin = 1e9f, zmax = -1e9f;
        for (std::uint32_t i : dets[d].indices) {
          if (i >= n) continue;
          zmin = std::min(zmin, f.cloud[i].z);
          zmax = std::max(zmax, f.cloud[i].z);
        }
        std::snprintf(buf, sizeof(buf), "; z %.2f..%.2f", zmin, zmax);
        fragment += buf;
      }
    }
    if (out) {
      const auto& c = dets[d].centroid;
      std::fprintf(out, "  %s %-18s false  %-28s %6zu pts %5.1f m  (%.1f, %.1f)%s\n", f.id.c_str(),
                   detector.c_str(), what.c_str(), dets[d].indices.size(), std::hypot(c.x(), c.y()),
                   c.x(), c.y(), fragment.c_str());
    }
  }
}

}  // namespace core
}  // namespace urban_detection
