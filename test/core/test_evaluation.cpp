// Detection scoring (paper Sec. 5): Hungarian assignment, NO/MO/FO and the rates, on hand-made
// frames whose expected counts are worked out in the comments.
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <numeric>
#include <random>

#include "urban_detection/core/evaluation/evaluation.h"

namespace urban_detection {
namespace core {
namespace {

DetectedObject det(std::uint32_t first, std::uint32_t last_inclusive) {
  DetectedObject o;
  for (std::uint32_t i = first; i <= last_inclusive; ++i) o.indices.push_back(i);
  return o;
}

// A frame of `n` points, GT objects given as inclusive index ranges.
EvalFrame frame(std::size_t n, const std::vector<std::pair<std::uint32_t, std::uint32_t>>& objects,
                std::size_t min_points = 1) {
  EvalFrame gt;
  gt.reset(n);
  for (std::size_t k = 0; k < objects.size(); ++k) {
    EvalObject o;
    o.label = "obj";
    o.id = static_cast<std::uint32_t>(k + 1);
    gt.objects.push_back(o);
    for (std::uint32_t i = objects[k].first; i <= objects[k].second; ++i) {
      gt.object_of_point[i] = static_cast<std::int32_t>(k);
    }
  }
  gt.finalize(min_points);
  return gt;
}

TEST(DetectionEvaluator, PerfectDetection) {
  const auto gt = frame(100, {{0, 9}, {10, 29}});
  DetectionEvaluator ev;
  FrameMatch m;
  ev.evaluate(gt, {det(10, 29), det(0, 9)}, &m);
  EXPECT_EQ(m.score.no, 2u);
  EXPECT_EQ(m.score.mo, 0u);
  EXPECT_EQ(m.score.fo, 0u);
  EXPECT_EQ(m.matched_gt, (std::vector<std::int32_t>{1, 0}));
  EXPECT_EQ(m.matched_detection, (std::vector<std::int32_t>{1, 0}));
  EXPECT_DOUBLE_EQ(m.iou[0], 1.0);
  EXPECT_DOUBLE_EQ(m.score.precision(), 1.0);
  EXPECT_DOUBLE_EQ(m.score.recall(), 1.0);
  EXPECT_DOUBLE_EQ(m.score.fRate(), 1.0);
}

TEST(DetectionEvaluator, OneSplitObject) {
  // GT of 20 points split 14 + 6: IoU 14/20 = 0.7 matches, 6/20 = 0.3 is a false object.
  const auto gt = frame(50, {{0, 19}});
  DetectionEvaluator ev;
  FrameMatch m;
  ev.evaluate(gt, {det(14, 19), det(0, 13)}, &m);
  EXPECT_EQ(m.score.no, 1u);
  EXPECT_EQ(m.score.mo, 0u);
  EXPECT_EQ(m.score.fo, 1u);
  EXPECT_EQ(m.verdict[0], DetectionVerdict::kFalse);
  EXPECT_EQ(m.verdict[1], DetectionVerdict::kTrue);
  EXPECT_NEAR(m.iou[1], 0.7, 1e-12);
  // P = 1/2, R = 1, F = 2 * 0.5 / 1.5.
  EXPECT_DOUBLE_EQ(m.score.precision(), 0.5);
  EXPECT_DOUBLE_EQ(m.score.recall(), 1.0);
  EXPECT_NEAR(m.score.fRate(), 2.0 / 3.0, 1e-12);
}

TEST(DetectionEvaluator, ShreddedObjectIsMissed) {
  // 21 points in three pieces of 7: every IoU is 1/3 < 0.5, so the object is missed and the
  // three pieces are false.
  const auto gt = frame(30, {{0, 20}});
  DetectionEvaluator ev;
  FrameMatch m;
  ev.evaluate(gt, {det(0, 6), det(7, 13), det(14, 20)}, &m);
  EXPECT_EQ(m.score.mo, 1u);
  EXPECT_EQ(m.score.fo, 3u);
  EXPECT_DOUBLE_EQ(m.score.fRate(), 0.0);
}

TEST(DetectionEvaluator, OneMergedPair) {
  // GT 30 + 20 points detected as one object: IoU 30/50 = 0.6 with the larger one (matched),
  // 20/50 = 0.4 with the smaller one (missed). No false object.
  const auto gt = frame(60, {{0, 29}, {30, 49}});
  DetectionEvaluator ev;
  FrameMatch m;
  ev.evaluate(gt, {det(0, 49)}, &m);
  EXPECT_EQ(m.score.no, 2u);
  EXPECT_EQ(m.score.mo, 1u);
  EXPECT_EQ(m.score.fo, 0u);
  EXPECT_EQ(m.matched_gt[0], 0);
  EXPECT_EQ(m.matched_detection[1], -1);
  EXPECT_NEAR(m.iou[0], 0.6, 1e-12);
  EXPECT_DOUBLE_EQ(m.score.precision(), 1.0);
  EXPECT_DOUBLE_EQ(m.score.recall(), 0.5);
}

TEST(DetectionEvaluator, OneMissedObject) {
  const auto gt = frame(40, {{0, 9}, {20, 29}});
  DetectionEvaluator ev;
  FrameMatch m;
  ev.evaluate(gt, {det(20, 29)}, &m);
  EXPECT_EQ(m.score.no, 2u);
  EXPECT_EQ(m.score.mo, 1u);
  EXPECT_EQ(m.score.fo, 0u);
  EXPECT_EQ(m.matched_detection, (std::vector<std::int32_t>{-1, 0}));
}

TEST(DetectionEvaluator, OneFalseObject) {
  // Points 30..39 belong to no object and are scored background (a wall, say).
  const auto gt = frame(40, {{0, 9}});
  DetectionEvaluator ev;
  FrameMatch m;
  ev.evaluate(gt, {det(0, 9), det(30, 39)}, &m);
  EXPECT_EQ(m.score.no, 1u);
  EXPECT_EQ(m.score.mo, 0u);
  EXPECT_EQ(m.score.fo, 1u);
  EXPECT_EQ(m.verdict[1], DetectionVerdict::kFalse);
  EXPECT_DOUBLE_EQ(m.score.precision(), 0.5);
}

TEST(DetectionEvaluator, DontCareDetectionIsIgnored) {
  auto gt = frame(40, {{0, 9}});
  for (std::uint32_t i = 30; i < 36; ++i) gt.role[i] = PointRole::kDontCare;
  DetectionEvaluator ev;
  FrameMatch m;
  // 30..39: 6 don't-care of 10 -> ignored; 33..39: 3 of 7 -> false.
  ev.evaluate(gt, {det(30, 39), det(33, 39)}, &m);
  EXPECT_EQ(m.verdict[0], DetectionVerdict::kIgnored);
  EXPECT_EQ(m.verdict[1], DetectionVerdict::kFalse);
  EXPECT_EQ(m.score.ignored, 1u);
  EXPECT_EQ(m.score.fo, 1u);
  EXPECT_EQ(m.score.mo, 1u);
}

TEST(DetectionEvaluator, ExcludedPointsLeaveIoU) {
  // The detection also holds 10 excluded points (road under the box): they count in neither
  // set, so IoU stays 1 instead of 10/20.
  auto gt = frame(40, {{0, 9}});
  for (std::uint32_t i = 10; i < 20; ++i) gt.role[i] = PointRole::kExcluded;
  DetectionEvaluator ev;
  FrameMatch m;
  ev.evaluate(gt, {det(0, 19), det(10, 19)}, &m);
  EXPECT_DOUBLE_EQ(m.iou[0], 1.0);
  EXPECT_EQ(m.verdict[0], DetectionVerdict::kTrue);
  // Made of excluded points only: nothing to score.
  EXPECT_EQ(m.verdict[1], DetectionVerdict::kIgnored);
}

TEST(DetectionEvaluator, SmallGroundTruthObjectsAreIgnored) {
  // Object 1 has 3 points < min_points 5: not counted in NO, its detection is ignored.
  const auto gt = frame(40, {{0, 9}, {20, 22}}, 5);
  EXPECT_FALSE(gt.objects[0].ignored);
  EXPECT_TRUE(gt.objects[1].ignored);
  DetectionEvaluator ev;
  FrameMatch m;
  ev.evaluate(gt, {det(20, 22)}, &m);
  EXPECT_EQ(m.score.no, 1u);
  EXPECT_EQ(m.score.mo, 1u);
  EXPECT_EQ(m.score.fo, 0u);
  EXPECT_EQ(m.verdict[0], DetectionVerdict::kIgnored);
}

TEST(DetectionEvaluator, OutOfRangeIndicesAndEmptyInputs) {
  const auto gt = frame(10, {{0, 4}});
  DetectionEvaluator ev;
  FrameMatch m;
  DetectedObject d = det(0, 4);
  d.indices.push_back(1000000);  // not a point of this frame: dropped
  ev.evaluate(gt, {d, DetectedObject()}, &m);
  EXPECT_EQ(m.verdict[0], DetectionVerdict::kTrue);
  EXPECT_EQ(m.verdict[1], DetectionVerdict::kIgnored);  // no points at all

  EvalFrame empty;
  ev.evaluate(empty, {}, &m);
  EXPECT_EQ(m.score.no, 0u);
  EXPECT_DOUBLE_EQ(m.score.precision(), 1.0);
  EXPECT_DOUBLE_EQ(m.score.recall(), 1.0);
}

TEST(DetectionEvaluator, AccumulatesOverFrames) {
  DetectionEvaluator ev;
  ev.evaluate(frame(60, {{0, 29}, {30, 49}}), {det(0, 49)}, nullptr);   // NO 2, MO 1
  ev.evaluate(frame(40, {{0, 9}}), {det(0, 9), det(30, 39)}, nullptr);  // NO 1, FO 1
  const DetectionScore& t = ev.total();
  EXPECT_EQ(t.no, 3u);
  EXPECT_EQ(t.mo, 1u);
  EXPECT_EQ(t.fo, 1u);
  EXPECT_EQ(t.tp, 2u);
  // Micro average: P = 2/3, R = 2/3.
  EXPECT_NEAR(t.precision(), 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(t.recall(), 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(t.fRate(), 2.0 / 3.0, 1e-12);
}

TEST(AssignMaxIou, PrefersMoreValidMatchesOverLargerIoUSum) {
  // Maximising the IoU sum alone would pick (0,1) + (1,0) = 0.9, two pairs below 0.5 and no
  // match; the valid pair (0,0) must win.
  const std::vector<std::vector<double>> iou = {{0.55, 0.45}, {0.45, 0.0}};
  EXPECT_EQ(assignMaxIou(iou, 0.5), (std::vector<std::int32_t>{0, -1}));
}

TEST(AssignMaxIou, RectangularAndEmpty) {
  EXPECT_TRUE(assignMaxIou({}, 0.5).empty());
  // 3 detections, 1 GT: the best of the three gets it.
  EXPECT_EQ(assignMaxIou({{0.6}, {0.9}, {0.7}}, 0.5), (std::vector<std::int32_t>{-1, 0, -1}));
  // 1 detection, 3 GT.
  EXPECT_EQ(assignMaxIou({{0.1, 0.8, 0.6}}, 0.5), (std::vector<std::int32_t>{1}));
}

// Brute force over all injective assignments as an independent oracle: the number of valid
// pairs and, among the best, the IoU sum of the valid pairs must agree with the Hungarian result.
TEST(AssignMaxIou, AgreesWithBruteForce) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const int rows = 1 + trial % 4, cols = 1 + (trial / 4) % 4;
    std::vector<std::vector<double>> iou(rows, std::vector<double>(cols));
    for (auto& r : iou) {
      for (auto& v : r) v = u(rng) < 0.4 ? 0.0 : u(rng);
    }
    // Enumerate: every row picks a distinct column or none (-1).
    int best_count = -1;
    double best_sum = -1.0;
    std::vector<int> pick(rows, -1);
    std::function<void(int, std::vector<bool>&)> rec = [&](int r, std::vector<bool>& used) {
      if (r == rows) {
        int count = 0;
        double sum = 0.0;
        for (int i = 0; i < rows; ++i) {
          if (pick[i] >= 0 && iou[i][pick[i]] >= 0.5) {
            ++count;
            sum += iou[i][pick[i]];
          }
        }
        if (count > best_count || (count == best_count && sum > best_sum)) {
          best_count = count;
          best_sum = sum;
        }
        return;
      }
      pick[r] = -1;
      rec(r + 1, used);
      for (int c = 0; c < cols; ++c) {
        if (used[c]) continue;
        used[c] = true;
        pick[r] = c;
        rec(r + 1, used);
        used[c] = false;
      }
      pick[r] = -1;
    };
    std::vector<bool> used(cols, false);
    rec(0, used);

    const auto a = assignMaxIou(iou, 0.5);
    int count = 0;
    double sum = 0.0;
    std::vector<bool> taken(cols, false);
    for (int i = 0; i < rows; ++i) {
      if (a[i] < 0) continue;
      ASSERT_FALSE(taken[a[i]]) << "column used twice";
      taken[a[i]] = true;
      ASSERT_GE(iou[i][a[i]], 0.5);
      ++count;
      sum += iou[i][a[i]];
    }
    EXPECT_EQ(count, best_count) << "trial " << trial;
    EXPECT_NEAR(sum, best_sum, 1e-5) << "trial " << trial;
  }
}

// ------------------------------------------------------------------------------------------
// Small objects count only when matched (min_points; SemanticKITTI's panoptic convention).

TEST(DetectionEvaluatorMinPoints, UnmatchedSmallDetectionIsNotFalse) {
  // A 29-point detection of background points: false with every object counting, ignored
  // under the 30-point rule.
  const auto gt = frame(200, {{0, 49}});
  EvaluationParams p;
  p.min_points = 30;
  DetectionEvaluator small_rule(p);
  DetectionEvaluator all;
  FrameMatch m;
  const std::vector<DetectedObject> dets = {det(0, 49), det(100, 128)};  // 50 + 29 points
  small_rule.evaluate(gt, dets, &m);
  EXPECT_EQ(m.score.no, 1u);
  EXPECT_EQ(m.score.tp, 1u);
  EXPECT_EQ(m.score.fo, 0u);
  EXPECT_EQ(m.score.ignored, 1u);
  EXPECT_EQ(m.verdict[1], DetectionVerdict::kIgnored);
  all.evaluate(gt, dets, &m);
  EXPECT_EQ(m.score.fo, 1u);
  EXPECT_EQ(m.verdict[1], DetectionVerdict::kFalse);
  // 30 points is not small: false under both rules.
  small_rule.evaluate(gt, {det(0, 49), det(100, 129)}, &m);
  EXPECT_EQ(m.score.fo, 1u);
}

TEST(DetectionEvaluatorMinPoints, MatchedSmallObjectCounts) {
  // GT objects of 20 and 40 points. Found: the small one counts as a true positive and in NO.
  const auto gt = frame(200, {{0, 19}, {50, 89}});
  EvaluationParams p;
  p.min_points = 30;
  DetectionEvaluator ev(p);
  FrameMatch m;
  ev.evaluate(gt, {det(0, 19), det(50, 89)}, &m);
  EXPECT_EQ(m.score.no, 2u);
  EXPECT_EQ(m.score.tp, 2u);
  EXPECT_EQ(m.verdict[0], DetectionVerdict::kTrue);
  // Missed: the small one is not counted at all, the large one is a miss.
  ev.evaluate(gt, {}, &m);
  EXPECT_EQ(m.score.no, 1u);
  EXPECT_EQ(m.score.mo, 1u);
  // A 29-point detection matching a 29-point object is a true positive.
  const auto gt29 = frame(200, {{0, 28}});
  ev.evaluate(gt29, {det(0, 28)}, &m);
  EXPECT_EQ(m.score.no, 1u);
  EXPECT_EQ(m.score.tp, 1u);
  EXPECT_EQ(m.score.fo, 0u);
  // Under N = 1 the missed small object is a miss too.
  DetectionEvaluator all;
  all.evaluate(gt, {}, &m);
  EXPECT_EQ(m.score.no, 2u);
  EXPECT_EQ(m.score.mo, 2u);
}

TEST(RecallBreakdown, CountsPerClassPointsAndRange) {
  EvalFrame gt = frame(400, {{0, 19}, {20, 119}, {200, 399}});
  gt.objects[0].label = "person";
  gt.objects[1].label = "person";
  gt.objects[2].label = "car";
  EvaluationParams p;
  p.min_points = 30;
  DetectionEvaluator ev(p);
  FrameMatch m;
  std::vector<DetectedObject> dets = {det(20, 119), det(200, 399)};
  dets[0].category = ObjectCategory::kPedestrian;
  dets[1].category = ObjectCategory::kPedestrian;  // a car called pedestrian
  ev.evaluate(gt, dets, &m);
  RecallBreakdown b;
  b.addFrame(gt, m, dets, {5.0f, 25.0f, 45.0f}, p.min_points);
  // Persons: the 20-point one is missed and small (not counted), the 100-point one found.
  EXPECT_EQ(b.by_class[1].total, 1u);
  EXPECT_EQ(b.by_class[1].found, 1u);
  EXPECT_EQ(b.by_class[0].total, 1u);
  EXPECT_EQ(b.by_class[0].found, 1u);
  EXPECT_EQ(b.class_kept[0], 1u);
  EXPECT_EQ(b.class_correct[0], 0u);
  EXPECT_DOUBLE_EQ(b.classAccuracy(1), 1.0);
  // By points and range every object counts: <30 (missed), 100-300 (found), >=300... the car
  // has 200 points: 100-300.
  EXPECT_EQ(b.by_points[0].total, 1u);
  EXPECT_EQ(b.by_points[0].found, 0u);
  EXPECT_EQ(b.by_points[2].total, 2u);
  EXPECT_EQ(b.by_points[2].found, 2u);
  EXPECT_EQ(b.by_range[0].found, 0u);
  EXPECT_EQ(b.by_range[1].found, 1u);
  EXPECT_EQ(b.by_range[2].found, 1u);
  EXPECT_EQ(b.class_by_range[1][0].total, 1u);
  RecallBreakdown twice = b;
  twice += b;
  EXPECT_EQ(twice.by_points[2].total, 4u);
  EXPECT_NE(b.json().find("\"pedestrian\""), std::string::npos);
}

}  // namespace
}  // namespace core
}  // namespace urban_detection
