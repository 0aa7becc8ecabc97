#include "urban_detection/core/evaluation/training.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <utility>

#include "urban_detection/core/evaluation/eval_datasets.h"
#include "urban_detection/core/evaluation/report.h"
#include "urban_detection/core/tracking/tracker.h"

namespace urban_detection {
namespace core {

ObjectCategory trainingLabel(const FrameMatch& m, std::size_t d, const EvalFrame& gt,
                             const std::string& content, FragmentRule fragments) {
  switch (m.verdict[d]) {
    case DetectionVerdict::kTrue:
      return categoryOfClassName(gt.objects[m.matched_gt[d]].label);
    case DetectionVerdict::kIgnored:
      return content == "other-object" ? ObjectCategory::kOtherObject : ObjectCategory::kUnknown;
    case DetectionVerdict::kFalse:
    default:
      if (content.compare(0, 8, "part_of_") == 0 && fragments == FragmentRule::kSkip) {
        return ObjectCategory::kUnknown;
      }
      return ObjectCategory::kNonObject;
  }
}

void trainingSet(const std::vector<TrainingFrame>& frames, const std::set<std::string>& groups,
                 std::vector<ObjectFeatureVector>* x, std::vector<ObjectCategory>* y) {
  x->clear();
  y->clear();
  for (const TrainingFrame& f : frames) {
    if (!f.always_train && !groups.count(f.group)) continue;
    const TrainingDetections& d = f.detectors[0];
    for (std::size_t i = 0; i < d.objects.size(); ++i) {
      if (d.labels[i] == ObjectCategory::kUnknown) continue;
      x->push_back(d.features[i]);
      y->push_back(d.labels[i]);
    }
  }
}

TrainingScore scoreFrames(const std::vector<TrainingFrame>& frames,
                          const std::set<std::string>& groups, std::size_t k,
                          const ClassDecision* decision, const ProbabilityFn& probs,
                          const EvaluationParams& ep,
                          std::map<std::string, TrainingScore>* by_group,
                          const ClassOverride* override_class) {
  DetectionEvaluator eval(ep);
  EvaluationParams ep_all = ep;
  ep_all.min_points = 1;
  DetectionEvaluator eval_all(ep_all);
  TrainingScore out;
  std::vector<DetectedObject> kept;
  FrameMatch m;
  for (std::size_t fi = 0; fi < frames.size(); ++fi) {
    const TrainingFrame& f = frames[fi];
    if (f.augmented || !groups.count(f.group)) continue;
    const TrainingDetections& d = f.detectors[k];
    kept.clear();
    for (std::size_t i = 0; i < d.objects.size(); ++i) {
      if (!decision) {
        kept.push_back(d.objects[i]);
        continue;
      }
      float confidence = 0.0f;
      ObjectCategory c = decideClass(probs(fi, i), *decision, true, &confidence);
      if (override_class) {
        const auto it = override_class->find(fi);
        if (it != override_class->end() && i < it->second.size() &&
            it->second[i] != ObjectCategory::kUnknown) {
          c = it->second[i];
        }
      }
      if (c == ObjectCategory::kNonObject) continue;
      kept.push_back(d.objects[i]);
      kept.back().category = c;
    }
    eval_all.evaluate(f.gt, kept, &m);
    const DetectionScore all = m.score;
    eval.evaluate(f.gt, kept, &m);
    RecallBreakdown b;
    b.addFrame(f.gt, m, kept, f.gt_range, ep.min_points);
    out.breakdown += b;
    if (by_group) {
      TrainingScore& g = (*by_group)[f.group];
      g.score += m.score;
      g.all += all;
      g.breakdown += b;
    }
  }
  out.score = eval.total();
  out.all = eval_all.total();
  return out;
}

double decisionObjective(const TrainingScore& s) {
  double sum = 0.0;
  int n = 0;
  for (int c = 0; c < 3; ++c) {
    if (s.breakdown.by_class[c].total == 0) continue;
    sum += s.breakdown.by_class[c].recall();
    ++n;
  }
  const double f = s.score.fRate();
  return n == 0 ? f : 0.5 * f + 0.5 * sum / n;
}

std::vector<double> thresholdGrid() {
  std::vector<double> t;
  for (int k = 5; k <= 95; k += 5) t.push_back(k / 100.0);
  return t;
}

ObjectClassifierModel trainOn(const std::vector<TrainingFrame>& frames,
                              const std::set<std::string>& groups,
                              const ClassifierTrainingParams& params,
                              const ObjectFeatureParams& fp) {
  std::vector<ObjectFeatureVector> x;
  std::vector<ObjectCategory> y;
  trainingSet(frames, groups, &x, &y);
  return ObjectClassifierModel::train(x, y, params, fp);
}

void temporalClasses(const std::vector<TrainingFrame>& frames, const std::string& group,
                     std::size_t k, const ClassDecision& decision, const ProbabilityFn& probs,
                     const std::vector<Eigen::Isometry3d>& poses,
                     const TrackerParams& tracker_params, ClassOverride* out,
                     TemporalStats* stats) {
  Tracker tracker(tracker_params);
  std::vector<DetectedObject> objects;
  for (std::size_t fi = 0; fi < frames.size(); ++fi) {
    const TrainingFrame& f = frames[fi];
    if (f.augmented || f.group != group) continue;
    const std::size_t slash = f.id.find('/');
    const std::size_t scan = std::strtoul(f.id.c_str() + (slash + 1), nullptr, 10);
    if (scan >= poses.size()) continue;
    objects = f.detectors[k].objects;
    std::vector<ObjectCategory> own(objects.size());
    for (std::size_t i = 0; i < objects.size(); ++i) {
      float confidence = 0.0f;
      own[i] = decideClass(probs(fi, i), decision, true, &confidence);
      objects[i].category = own[i];
      objects[i].class_confidence = confidence;
    }
    tracker.update(objects, poses[scan], 0.1 * static_cast<double>(scan));
    std::vector<ObjectCategory>& cls = (*out)[fi];
    cls.assign(objects.size(), ObjectCategory::kUnknown);
    for (const Track& t : tracker.tracks()) {
      if (t.detection < 0 || static_cast<std::size_t>(t.detection) >= objects.size() ||
          t.state == TrackState::kTentative || t.category == ObjectCategory::kNonObject ||
          t.category == ObjectCategory::kUnknown) {
        continue;
      }
      const std::size_t i = static_cast<std::size_t>(t.detection);
      cls[i] = t.category;
      ++(own[i] == ObjectCategory::kNonObject ? stats->kept : stats->reclassed);
    }
  }
}

ClassDecision bestDecision(const std::vector<TrainingFrame>& frames,
                           const std::set<std::string>& groups, const ProbabilityFn& probs,
                           const EvaluationParams& ep, DecisionRule rule, double uncertain_band) {
  ClassDecision best;
  double best_j = -1.0;
  auto consider = [&](const ClassDecision& d) {
    const double j = decisionObjective(scoreFrames(frames, groups, 0, &d, probs, ep, nullptr));
    if (j > best_j + 1e-12) {
      best_j = j;
      best = d;
    }
  };
  for (const double t : thresholdGrid()) {
    ClassDecision d;
    d.object_threshold = t;
    consider(d);
  }
  if (rule == DecisionRule::kObject) {
    best.uncertain_threshold = std::max(0.0, best.object_threshold - uncertain_band);
    return best;
  }
  for (int round = 0; round < 2; ++round) {
    for (std::size_t c = 0; c < 3; ++c) {
      const ClassDecision base = best;
      for (const double t : thresholdGrid()) {
        if (t >= base.object_threshold) break;
        ClassDecision d = base;
        d.class_thresholds[c] = t;
        consider(d);
      }
    }
    const ClassDecision base = best;
    for (const double t : thresholdGrid()) {
      if (t >= base.object_threshold) break;
      ClassDecision d = base;
      d.uncertain_threshold = t;
      consider(d);
    }
  }
  return best;
}

ClassDecision innerDecision(std::vector<TrainingFrame>* frames,
                            const std::vector<std::string>& groups,
                            const ClassifierTrainingParams& params, const ObjectFeatureParams& fp,
                            const EvaluationParams& ep, DecisionRule rule, double uncertain_band) {
  const int folds = std::min<int>(3, static_cast<int>(groups.size()));
  if (folds < 2) {
    ClassDecision d;
    d.object_threshold = params.object_threshold;
    return d;
  }
  std::map<std::pair<std::size_t, std::size_t>, ClassProbabilities> oof;
  for (const GroupFold& fold : crossValidationFolds(groups, folds)) {
    const std::set<std::string>& train = fold.train;
    const std::set<std::string>& test = fold.test;
    const ObjectClassifierModel m = trainOn(*frames, train, params, fp);
    for (std::size_t fi = 0; fi < frames->size(); ++fi) {
      const TrainingFrame& f = (*frames)[fi];
      if (f.augmented || !test.count(f.group)) continue;
      std::vector<ClassProbabilities> p;
      m.predict(f.detectors[0].features, &p);
      for (std::size_t i = 0; i < p.size(); ++i) oof[{fi, i}] = p[i];
    }
  }
  const std::set<std::string> all(groups.begin(), groups.end());
  return bestDecision(
      *frames, all,
      [&](std::size_t fi, std::size_t i) {
        return oof[{fi, i}];
      },
      ep, rule, uncertain_band);
}

std::vector<GroupFold> crossValidationFolds(const std::vector<std::string>& groups, int folds) {
  std::vector<GroupFold> out(static_cast<std::size_t>(std::max(folds, 0)));
  for (int k = 0; k < folds; ++k) {
    for (std::size_t g = 0; g < groups.size(); ++g) {
      (static_cast<int>(g) % folds == k ? out[k].test : out[k].train).insert(groups[g]);
    }
  }
  return out;
}

std::vector<std::string> leaveOneOut(const std::vector<std::string>& groups,
                                     const std::string& held_out) {
  std::vector<std::string> train;
  for (const std::string& g : groups) {
    if (g != held_out) train.push_back(g);
  }
  return train;
}

std::vector<std::string> scoredGroups(const std::vector<TrainingFrame>& frames) {
  std::vector<std::string> groups;
  for (const TrainingFrame& fd : frames) {
    if (!fd.augmented && (groups.empty() || groups.back() != fd.group)) groups.push_back(fd.group);
  }
  return groups;
}

std::map<std::string, ClassDecision> leaveOneSequenceOut(
    std::vector<TrainingFrame>* frames, const std::vector<std::string>& groups,
    const ClassifierTrainingParams& tp, const ObjectFeatureParams& fp, const EvaluationParams& ep,
    bool auto_threshold, DecisionRule rule, double uncertain_band) {
  std::map<std::string, ClassDecision> fold_decision;
  for (const std::string& held : groups) {
    const std::vector<std::string> train_groups = leaveOneOut(groups, held);
    ClassDecision d;
    d.object_threshold = tp.object_threshold;
    if (auto_threshold) d = innerDecision(frames, train_groups, tp, fp, ep, rule, uncertain_band);
    fold_decision[held] = d;
    const ObjectClassifierModel m =
        trainOn(*frames, std::set<std::string>(train_groups.begin(), train_groups.end()), tp, fp);
    for (TrainingFrame& fd : *frames) {
      if (fd.augmented || fd.group != held) continue;
      for (TrainingDetections& dk : fd.detectors) m.predict(dk.features, &dk.held_out);
    }
  }
  return fold_decision;
}

ProbabilityFn heldOutProbabilities(const std::vector<TrainingFrame>& frames, std::size_t k) {
  return
      [&frames, k](std::size_t fi, std::size_t i) { return frames[fi].detectors[k].held_out[i]; };
}

CategoryConfusion heldOutConfusion(const std::vector<TrainingFrame>& frames,
                                   const std::map<std::string, ClassDecision>& fold_decision) {
  CategoryConfusion confusion{};
  for (const TrainingFrame& fd : frames) {
    if (fd.augmented) continue;
    const auto decision = fold_decision.find(fd.group);
    if (decision == fold_decision.end()) continue;
    const TrainingDetections& d = fd.detectors[0];
    for (std::size_t i = 0; i < d.objects.size(); ++i) {
      if (d.labels[i] == ObjectCategory::kUnknown) continue;
      float confidence = 0.0f;
      const int pred =
          static_cast<int>(decideClass(d.held_out[i], decision->second, true, &confidence));
      ++confusion[static_cast<int>(d.labels[i])][pred];
    }
  }
  return confusion;
}

void TrainingScore::add(const TrainingScore& o) {
  score += o.score;
  all += o.all;
  breakdown += o.breakdown;
}

TrainingFrame labelledTrainingFrame(const Frame& f, const Dataset& ds, const std::string& group,
                                    const std::vector<std::unique_ptr<Pipeline>>& pipelines,
                                    std::size_t detectors, ObjectFeatureExtractor* extractor,
                                    FragmentRule fragments) {
  const LabeledCloud& foreground = pipelines[0]->process(f.cloud).foreground;
  DetectionEvaluator evaluator;
  TrainingFrame fd;
  fd.id = f.id;
  fd.group = group;
  fd.detectors.resize(pipelines.size());
  for (std::size_t k = 0; k < detectors && k < pipelines.size(); ++k) {
    TrainingDetections& d = fd.detectors[k];
    d.objects = (k == 0 ? pipelines[0]->result() : pipelines[k]->detect(foreground)).objects;
    FrameMatch m;
    evaluator.evaluate(f.gt, d.objects, &m);
    extractor->computeAll(foreground, d.objects, &d.features);
    d.verdicts = m.verdict;
    for (std::size_t i = 0; i < d.objects.size(); ++i) {
      d.contents.push_back(detectionContent(f, ds, d.objects[i]));
      d.labels.push_back(trainingLabel(m, i, f.gt, d.contents.back(), fragments));
    }
  }
  return fd;
}

TrainingFrame augmentedTrainingFrame(const std::string& id, const std::string& group,
                                     const CloudXYZIRT& cloud, const EvalFrame& gt,
                                     const std::vector<std::unique_ptr<Pipeline>>& pipelines,
                                     ObjectFeatureExtractor* extractor, std::size_t* pasted) {
  const PipelineResult& scan = pipelines[0]->process(cloud);
  TrainingFrame fd;
  fd.id = id;
  fd.group = group;
  fd.augmented = true;
  fd.detectors.resize(pipelines.size());
  TrainingDetections& d = fd.detectors[0];  // the forest learns from the first detector
  d.objects = scan.objects;
  DetectionEvaluator evaluator;
  FrameMatch m;
  evaluator.evaluate(gt, d.objects, &m);
  extractor->computeAll(scan.foreground, d.objects, &d.features);
  for (std::size_t i = 0; i < d.objects.size(); ++i) {
    const bool is_pasted = m.verdict[i] == DetectionVerdict::kTrue &&
                           gt.objects[m.matched_gt[i]].id >= kPastedInstanceBase;
    d.labels.push_back(is_pasted ? categoryOfClassName(gt.objects[m.matched_gt[i]].label)
                                 : ObjectCategory::kUnknown);
    *pasted += is_pasted;
  }
  return fd;
}

LabelledScan labelledScanOf(const Frame& f) {
  LabelledScan scan;
  scan.cloud = f.cloud;
  scan.labels.resize(f.cloud.size());
  for (std::size_t i = 0; i < scan.labels.size(); ++i) {
    const std::int32_t g = f.gt.object_of_point[i];
    scan.labels[i] = f.point_class[i] | (g >= 0 ? f.gt.objects[g].id << 16 : 0u);
  }
  return scan;
}

bool temporalEvidence(const std::vector<TrainingFrame>& frames,
                      const std::vector<std::string>& groups, const std::string& dir,
                      const std::map<std::string, ClassDecision>& fold_decision, ClassOverride* out,
                      TemporalStats* stats) {
  bool ok = true;
  for (const std::string& g : groups) {
    const std::string seq_dir =
        std::filesystem::is_directory(dir + "/velodyne") ? dir : dir + "/sequences/" + g;
    std::vector<Eigen::Isometry3d> poses;
    bool nominal = false;
    std::string error;
    if (!readSemanticKittiPoses(seq_dir, &poses, &nominal, &error)) {
      std::fprintf(stderr, "warning: no time evidence for %s: %s\n", g.c_str(), error.c_str());
      ok = false;
      continue;
    }
    temporalClasses(frames, g, 0, fold_decision.at(g), heldOutProbabilities(frames, 0), poses,
                    TrackerParams(), out, stats);
  }
  return ok;
}

std::string decisionText(const ClassDecision& d) {
  char b[64];
  std::snprintf(b, sizeof b, "%.2f/%.2f/%.2f/%.2f/%.2f", d.object_threshold, d.class_thresholds[0],
                d.class_thresholds[1], d.class_thresholds[2], d.uncertain_threshold);
  return b;
}

std::string decisionJson(const ClassDecision& d) {
  std::ostringstream o;
  o << "{\"object\": " << jsonNumber(d.object_threshold)
    << ", \"vehicle\": " << jsonNumber(d.class_thresholds[0])
    << ", \"pedestrian\": " << jsonNumber(d.class_thresholds[1])
    << ", \"cyclist\": " << jsonNumber(d.class_thresholds[2])
    << ", \"uncertain\": " << jsonNumber(d.uncertain_threshold) << "}";
  return o.str();
}

LabelCounts trainingLabelCounts(const std::vector<TrainingFrame>& frames,
                                std::size_t* not_trained_on) {
  LabelCounts counts{};
  *not_trained_on = 0;
  for (const TrainingFrame& fd : frames) {
    for (const ObjectCategory l : fd.detectors[0].labels) {
      if (l == ObjectCategory::kUnknown) {
        ++*not_trained_on;
      } else {
        ++counts[static_cast<int>(l)];
      }
    }
  }
  return counts;
}

std::string confusionTable(const CategoryConfusion& confusion) {
  std::string out;
  appendf(&out, "%14s", "");
  for (int c = 0; c < kNumObjectCategories; ++c)
    appendf(&out, " %12s", toString(static_cast<ObjectCategory>(c)));
  out += "\n";
  for (int r = 0; r < kNumObjectCategories; ++r) {
    appendf(&out, "%14s", toString(static_cast<ObjectCategory>(r)));
    for (int c = 0; c < kNumObjectCategories; ++c) appendf(&out, " %12zu", confusion[r][c]);
    out += "\n";
  }
  return out;
}

std::string confusionJson(const CategoryConfusion& confusion) {
  std::ostringstream json;
  json << "[";
  for (int r = 0; r < kNumObjectCategories; ++r) {
    json << (r ? ", " : "") << "[";
    for (int c = 0; c < kNumObjectCategories; ++c) json << (c ? ", " : "") << confusion[r][c];
    json << "]";
  }
  json << "]";
  return json.str();
}

std::string trainingScoreRow(const DetectionScore& s) {
  std::string out;
  appendf(&out, "%5zu %5zu %5zu %9.3f %7.3f %7.3f", s.no, s.mo, s.fo, s.precision(), s.recall(),
          s.fRate());
  return out;
}

std::string trainingScoreJson(const DetectionScore& s) {
  std::ostringstream o;
  o << "{\"no\": " << s.no << ", \"mo\": " << s.mo << ", \"fo\": " << s.fo
    << ", \"precision\": " << jsonNumber(s.precision())
    << ", \"recall\": " << jsonNumber(s.recall()) << ", \"f_rate\": " << jsonNumber(s.fRate())
    << "}";
  return o.str();
}

std::size_t addSimTrainingFrames(const std::string& gt, const std::string& pcap,
                                 std::size_t max_frames,
                                 const std::vector<std::unique_ptr<Pipeline>>& pipelines,
                                 ObjectFeatureExtractor* extractor, FragmentRule fragments,
                                 std::vector<TrainingFrame>* frames) {
  SimulatedGroundTruthParams sgp;
  sgp.min_points = 1;
  SimulatedDriveDataset sim(gt, pcap, loadCalibration(""), 0.0, sgp);
  Frame sf;
  std::size_t rows = 0;
  for (std::size_t n = 0; n < max_frames; ++n) {
    std::string err;
    const auto status = sim.next(&sf, &err);
    if (status == Dataset::Status::kEnd) break;
    if (status == Dataset::Status::kSkipped) continue;
    TrainingFrame fd = labelledTrainingFrame(sf, sim, "sim", pipelines, 1, extractor, fragments);
    fd.id = "sim/" + sf.id;
    fd.augmented = true;
    fd.always_train = true;
    for (const auto l : fd.detectors[0].labels) rows += l != ObjectCategory::kUnknown;
    frames->push_back(std::move(fd));
  }
  return rows;
}

}  // namespace core
}  // namespace urban_detection
