// The classifier's training protocol as a library (core/evaluation/training.h): training
// labels by the evaluation's verdicts, folds over sequences that never test a sequence they
// trained on, the paper's scoring of the kept detections, and leave-one-sequence-out
// predictions that come from a forest which never saw the held-out sequence.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "urban_detection/core/evaluation/training.h"

namespace ud = urban_detection::core;

namespace {

// A frame of `group` with one GT object per entry of `gt_labels` (10 points each) and one
// detection per GT object that covers exactly its points (features `feature`, label `label`),
// plus `false_detections` detections of 10 background points each.
ud::TrainingFrame frameOf(const std::string& group, const std::vector<std::string>& gt_labels,
                          int false_detections, float feature, ud::ObjectCategory label) {
  ud::TrainingFrame f;
  f.id = group + "/000000";
  f.group = group;
  const std::size_t n = 10 * (gt_labels.size() + static_cast<std::size_t>(false_detections));
  f.gt.reset(n);
  f.detectors.resize(1);
  ud::TrainingDetections& d = f.detectors[0];
  for (std::size_t g = 0; g < gt_labels.size(); ++g) {
    f.gt.objects.push_back({gt_labels[g], static_cast<std::uint32_t>(g + 1), false, 0});
  }
  for (std::size_t k = 0; k < gt_labels.size() + static_cast<std::size_t>(false_detections); ++k) {
    ud::DetectedObject o;
    for (std::uint32_t i = 0; i < 10; ++i) {
      const std::uint32_t p = static_cast<std::uint32_t>(10 * k) + i;
      o.indices.push_back(p);
      if (k < gt_labels.size()) f.gt.object_of_point[p] = static_cast<std::int32_t>(k);
    }
    d.objects.push_back(o);
    ud::ObjectFeatureVector x{};
    x.fill(feature);
    x[0] = feature + 0.01f * static_cast<float>(k);
    d.features.push_back(x);
    d.labels.push_back(k < gt_labels.size() ? label : ud::ObjectCategory::kNonObject);
  }
  f.gt.finalize(1);
  f.gt_range.assign(gt_labels.size(), 10.0f);
  return f;
}

ud::ClassProbabilities onlyClass(ud::ObjectCategory c) {
  ud::ClassProbabilities p{};
  p[static_cast<int>(c)] = 1.0f;
  return p;
}

}  // namespace

TEST(TrainingProtocol, LabelsFollowTheVerdicts) {
  ud::EvalFrame gt;
  gt.objects = {{"car", 1, false, 10}};
  ud::FrameMatch m;
  m.verdict = {ud::DetectionVerdict::kTrue, ud::DetectionVerdict::kIgnored,
               ud::DetectionVerdict::kIgnored, ud::DetectionVerdict::kFalse,
               ud::DetectionVerdict::kFalse};
  m.matched_gt = {0, -1, -1, -1, -1};
  const auto skip = ud::FragmentRule::kSkip;
  EXPECT_EQ(ud::trainingLabel(m, 0, gt, "part_of_car", skip), ud::ObjectCategory::kVehicle);
  EXPECT_EQ(ud::trainingLabel(m, 1, gt, "other-object", skip), ud::ObjectCategory::kOtherObject);
  EXPECT_EQ(ud::trainingLabel(m, 2, gt, "pole", skip), ud::ObjectCategory::kUnknown);
  EXPECT_EQ(ud::trainingLabel(m, 3, gt, "vegetation", skip), ud::ObjectCategory::kNonObject);
  EXPECT_EQ(ud::trainingLabel(m, 4, gt, "part_of_car", skip), ud::ObjectCategory::kUnknown);
  EXPECT_EQ(ud::trainingLabel(m, 4, gt, "part_of_car", ud::FragmentRule::kReject),
            ud::ObjectCategory::kNonObject);
}

TEST(TrainingProtocol, FoldsNeverTestWhatTheyTrainOn) {
  const std::vector<std::string> groups = {"00", "01", "02", "03", "04", "05", "07"};
  for (const std::string& held : groups) {
    const std::vector<std::string> train = ud::leaveOneOut(groups, held);
    EXPECT_EQ(train.size(), groups.size() - 1);
    EXPECT_EQ(std::count(train.begin(), train.end(), held), 0) << held;
  }
  const std::vector<ud::GroupFold> folds = ud::crossValidationFolds(groups, 3);
  ASSERT_EQ(folds.size(), 3u);
  std::map<std::string, int> tested;
  for (const ud::GroupFold& f : folds) {
    for (const std::string& g : f.test) {
      ++tested[g];
      EXPECT_EQ(f.train.count(g), 0u) << g;
    }
    EXPECT_EQ(f.train.size() + f.test.size(), groups.size());
  }
  for (const std::string& g : groups) EXPECT_EQ(tested[g], 1) << g;
  EXPECT_EQ(folds[0].test, (std::set<std::string>{"00", "03", "07"}));
}

TEST(TrainingProtocol, ScoredGroupsLeaveAugmentedFramesOut) {
  std::vector<ud::TrainingFrame> frames = {
      frameOf("00", {"car"}, 0, 1.0f, ud::ObjectCategory::kVehicle),
      frameOf("00", {"car"}, 0, 1.0f, ud::ObjectCategory::kVehicle),
      frameOf("sim", {"car"}, 0, 1.0f, ud::ObjectCategory::kVehicle),
      frameOf("05", {"car"}, 0, 1.0f, ud::ObjectCategory::kVehicle)};
  frames[2].augmented = true;
  EXPECT_EQ(ud::scoredGroups(frames), (std::vector<std::string>{"00", "05"}));
  std::vector<ud::ObjectFeatureVector> x;
  std::vector<ud::ObjectCategory> y;
  ud::trainingSet(frames, {"05"}, &x, &y);
  EXPECT_EQ(y.size(), 1u);
  frames[2].always_train = true;  // simulated: in every fold's training set
  ud::trainingSet(frames, {"05"}, &x, &y);
  EXPECT_EQ(y.size(), 2u);
}

TEST(TrainingProtocol, ScoringCountsKeptDetectionsByThePaperRule) {
  // Two cars and a person, each covered exactly by a detection, and two false detections.
  // The probabilities keep the cars and one false detection and reject the person.
  std::vector<ud::TrainingFrame> frames = {
      frameOf("00", {"car", "car", "person"}, 2, 1.0f, ud::ObjectCategory::kVehicle)};
  const ud::ProbabilityFn probs = [](std::size_t, std::size_t i) {
    return onlyClass(i == 2 || i == 4 ? ud::ObjectCategory::kNonObject
                                      : ud::ObjectCategory::kVehicle);
  };
  ud::EvaluationParams ep;
  ep.min_points = 1;
  const ud::TrainingScore alone = ud::scoreFrames(frames, {"00"}, 0, nullptr, probs, ep, nullptr);
  EXPECT_EQ(alone.score.no, 3u);
  EXPECT_EQ(alone.score.mo, 0u);
  EXPECT_EQ(alone.score.fo, 2u);
  ud::ClassDecision decision;
  decision.object_threshold = 0.5;
  std::map<std::string, ud::TrainingScore> by_group;
  const ud::TrainingScore kept =
      ud::scoreFrames(frames, {"00"}, 0, &decision, probs, ep, &by_group);
  EXPECT_EQ(kept.score.no, 3u);
  EXPECT_EQ(kept.score.mo, 1u);
  EXPECT_EQ(kept.score.fo, 1u);
  EXPECT_NEAR(kept.score.recall(), 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(kept.score.precision(), 2.0 / 3.0, 1e-12);
  EXPECT_EQ(by_group.at("00").score.mo, 1u);
  // A later stage's class overrides the decision: the person kept as a pedestrian.
  ud::ClassOverride over = {{0,
                             {ud::ObjectCategory::kUnknown, ud::ObjectCategory::kUnknown,
                              ud::ObjectCategory::kPedestrian}}};
  const ud::TrainingScore overridden =
      ud::scoreFrames(frames, {"00"}, 0, &decision, probs, ep, nullptr, &over);
  EXPECT_EQ(overridden.score.mo, 0u);
  // Frames of other groups are not scored.
  EXPECT_EQ(ud::scoreFrames(frames, {"01"}, 0, &decision, probs, ep, nullptr).score.no, 0u);
  EXPECT_EQ(ud::thresholdGrid().size(), 19u);
}

TEST(TrainingProtocol, HeldOutPredictionsComeFromAForestThatNeverSawTheSequence) {
  // Sequence "ped" alone has pedestrians (features near 5); "a" and "b" have vehicles (near 1)
  // and non-objects. A forest trained with "ped" gives its detections P(pedestrian) > 0; the
  // leave-one-sequence-out forest of "ped" never saw a pedestrian and gives 0.
  std::vector<ud::TrainingFrame> frames;  // each sequence's scans in order, as they are read
  for (const char* g : {"a", "b"}) {
    for (int k = 0; k < 3; ++k) {
      frames.push_back(frameOf(g, {"car", "car"}, 2, 1.0f, ud::ObjectCategory::kVehicle));
    }
  }
  for (int k = 0; k < 3; ++k) {
    frames.push_back(
        frameOf("ped", {"person", "person"}, 2, 5.0f, ud::ObjectCategory::kPedestrian));
  }
  ud::ClassifierTrainingParams tp;
  tp.trees = 8;
  tp.min_sample_count = 1;
  const ud::ObjectFeatureParams fp;
  const ud::EvaluationParams ep;
  const std::vector<std::string> groups = ud::scoredGroups(frames);
  ASSERT_EQ(groups, (std::vector<std::string>{"a", "b", "ped"}));
  const std::map<std::string, ud::ClassDecision> decisions =
      ud::leaveOneSequenceOut(&frames, groups, tp, fp, ep, false, ud::DecisionRule::kObject, 0.0);
  ASSERT_EQ(decisions.size(), 3u);
  EXPECT_DOUBLE_EQ(decisions.at("ped").object_threshold, tp.object_threshold);
  const int ped = static_cast<int>(ud::ObjectCategory::kPedestrian);
  const ud::ObjectClassifierModel all = ud::trainOn(frames, {"a", "b", "ped"}, tp, fp);
  for (const ud::TrainingFrame& f : frames) {
    const ud::TrainingDetections& d = f.detectors[0];
    ASSERT_EQ(d.held_out.size(), d.objects.size()) << f.group;
    if (f.group != "ped") continue;
    std::vector<ud::ClassProbabilities> with_ped;
    all.predict(d.features, &with_ped);
    EXPECT_GT(with_ped[0][ped], 0.5f);
    for (const ud::ClassProbabilities& p : d.held_out) EXPECT_EQ(p[ped], 0.0f);
  }
  // The held-out confusion: the pedestrians (labelled) are never predicted as pedestrians.
  const ud::CategoryConfusion confusion = ud::heldOutConfusion(frames, decisions);
  std::size_t pedestrians = 0;
  for (int c = 0; c < ud::kNumObjectCategories; ++c) pedestrians += confusion[ped][c];
  EXPECT_EQ(pedestrians, 6u);
  EXPECT_EQ(confusion[ped][ped], 0u);
  const ud::ProbabilityFn held = ud::heldOutProbabilities(frames, 0);
  EXPECT_EQ(held(6, 0), frames[6].detectors[0].held_out[0]);
}

TEST(TrainingProtocol, LabelCountsAndDecisionText) {
  std::vector<ud::TrainingFrame> frames = {
      frameOf("00", {"car", "person"}, 1, 1.0f, ud::ObjectCategory::kVehicle)};
  frames[0].detectors[0].labels[1] = ud::ObjectCategory::kUnknown;
  std::size_t unknown = 0;
  const ud::LabelCounts counts = ud::trainingLabelCounts(frames, &unknown);
  EXPECT_EQ(unknown, 1u);
  EXPECT_EQ(counts[static_cast<int>(ud::ObjectCategory::kVehicle)], 1u);
  EXPECT_EQ(counts[static_cast<int>(ud::ObjectCategory::kNonObject)], 1u);
  ud::ClassDecision d;
  d.object_threshold = 0.35;
  d.class_thresholds = {0.1, 0.2, 0.3};
  d.uncertain_threshold = 0.25;
  EXPECT_EQ(ud::decisionText(d), "0.35/0.10/0.20/0.30/0.25");
  EXPECT_EQ(ud::decisionJson(d),
            "{\"object\": 0.35, \"vehicle\": 0.1, \"pedestrian\": 0.2, \"cyclist\": 0.3, "
            "\"uncertain\": 0.25}");
}
