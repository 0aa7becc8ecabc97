#include "urban_detection/core/tracking/clear_mot.h"

#include "urban_detection/core/tracking/hungarian.h"

namespace urban_detection {
namespace core {

namespace {

constexpr double kForbidden = 1e9;

// Hungarian matching of the GT objects `rows` to the hypotheses `cols` on distance, pairs
// beyond `max_d` excluded; calls on_match(gt index, hyp index, distance) per pair.
template <class OnMatch>
void matchByDistance(const std::vector<MotGroundTruth>& gt, const std::vector<int>& rows,
                     const std::vector<MotHypothesis>& hyp, const std::vector<int>& cols,
                     double max_d, OnMatch on_match) {
  if (rows.empty() || cols.empty()) return;
  const int nr = static_cast<int>(rows.size()), nc = static_cast<int>(cols.size());
  std::vector<double> cost(static_cast<std::size_t>(nr) * nc, kForbidden);
  bool any = false;
  for (int r = 0; r < nr; ++r) {
    for (int c = 0; c < nc; ++c) {
      const double d = (gt[rows[r]].position - hyp[cols[c]].position).norm();
      if (d <= max_d) {
        cost[static_cast<std::size_t>(r) * nc + c] = d;
        any = true;
      }
    }
  }
  if (!any) return;
  std::vector<int> row_to_col;
  solveAssignment(cost, nr, nc, &row_to_col);
  for (int r = 0; r < nr; ++r) {
    const int c = row_to_col[r];
    if (c < 0) continue;
    const double d = cost[static_cast<std::size_t>(r) * nc + c];
    if (d < kForbidden) on_match(rows[r], cols[c], d);
  }
}

}  // namespace

double ClearMotResult::mota() const {
  if (gt == 0) return 1.0;
  return 1.0 - static_cast<double>(misses + false_positives + id_switches) / gt;
}
double ClearMotResult::motp_m() const {
  return matches ? distance_sum_m / matches : 0.0;
}
double ClearMotResult::recall() const {
  return gt ? static_cast<double>(matches) / gt : 1.0;
}
double ClearMotResult::precision() const {
  return matches + false_positives ? static_cast<double>(matches) / (matches + false_positives)
                                   : 1.0;
}
double ClearMotResult::idSwitchesPer100GtTracks() const {
  return gt_tracks ? 100.0 * static_cast<double>(id_switches) / gt_tracks : 0.0;
}

ClearMot::ClearMot(const ClearMotParams& params) : params_(params) {}

void ClearMot::addFrame(const std::vector<MotGroundTruth>& gt,
                        const std::vector<MotHypothesis>& hyp, std::vector<int>* matched_out) {
  const std::size_t frame = totals_.frames++;
  std::vector<int> gt_match(gt.size(), -1);
  std::vector<double> gt_dist(gt.size(), 0.0);
  std::vector<char> hyp_used(hyp.size(), 0);
  std::map<std::uint32_t, int> hyp_by_id;
  for (std::size_t h = 0; h < hyp.size(); ++h) hyp_by_id.emplace(hyp[h].id, static_cast<int>(h));

  // 1. Correspondences of the previous frame that still hold.
  for (std::size_t g = 0; g < gt.size(); ++g) {
    if (gt[g].ignored) continue;
    const auto it = trajectories_.find(gt[g].id);
    if (it == trajectories_.end()) continue;
    const Trajectory& tr = it->second;
    if (!tr.matched_in_previous || tr.last_frame + 1 != frame) continue;
    const auto h = hyp_by_id.find(tr.last_hyp);
    if (h == hyp_by_id.end() || hyp_used[h->second]) continue;
    const double d = (gt[g].position - hyp[h->second].position).norm();
    if (d > params_.max_distance_m) continue;
    gt_match[g] = h->second;
    gt_dist[g] = d;
    hyp_used[h->second] = 1;
  }
  // 2. The others, by minimum total distance.
  std::vector<int> rows, cols;
  for (std::size_t g = 0; g < gt.size(); ++g) {
    if (!gt[g].ignored && gt_match[g] < 0) rows.push_back(static_cast<int>(g));
  }
  for (std::size_t h = 0; h < hyp.size(); ++h) {
    if (!hyp_used[h]) cols.push_back(static_cast<int>(h));
  }
  matchByDistance(gt, rows, hyp, cols, params_.max_distance_m, [&](int g, int h, double d) {
    gt_match[g] = h;
    gt_dist[g] = d;
    hyp_used[h] = 1;
  });
  // 3. Hypotheses on ignored GT objects are dropped.
  rows.clear();
  cols.clear();
  for (std::size_t g = 0; g < gt.size(); ++g) {
    if (gt[g].ignored) rows.push_back(static_cast<int>(g));
  }
  for (std::size_t h = 0; h < hyp.size(); ++h) {
    if (!hyp_used[h]) cols.push_back(static_cast<int>(h));
  }
  matchByDistance(gt, rows, hyp, cols, params_.max_distance_m,
                  [&](int, int h, double) { hyp_used[h] = 2; });

  // 4. Counts.
  for (std::size_t g = 0; g < gt.size(); ++g) {
    if (gt[g].ignored) continue;
    ++totals_.gt;
    Trajectory& tr = trajectories_[gt[g].id];
    ++tr.present;
    const int h = gt_match[g];
    if (h < 0) {
      ++totals_.misses;
      tr.matched_in_previous = false;
    } else {
      ++totals_.matches;
      ++tr.tracked;
      totals_.distance_sum_m += gt_dist[g];
      if (tr.has_last && tr.last_hyp != hyp[h].id) ++totals_.id_switches;
      if (tr.has_last && !tr.matched_in_previous) ++totals_.fragmentations;
      tr.has_last = true;
      tr.last_hyp = hyp[h].id;
      tr.matched_in_previous = true;
    }
    tr.last_frame = frame;
  }
  for (std::size_t h = 0; h < hyp.size(); ++h) {
    if (!hyp_used[h] && !hyp[h].dont_care) ++totals_.false_positives;
  }
  if (matched_out) {
    matched_out->assign(gt.size(), -1);
    for (std::size_t g = 0; g < gt.size(); ++g) {
      if (!gt[g].ignored) (*matched_out)[g] = gt_match[g];
    }
  }
}

ClearMotResult ClearMot::result() const {
  ClearMotResult r = totals_;
  r.gt_tracks = r.mostly_tracked = r.partially_tracked = r.mostly_lost = 0;
  for (const auto& kv : trajectories_) {
    const Trajectory& tr = kv.second;
    if (tr.present == 0) continue;
    ++r.gt_tracks;
    const double f = static_cast<double>(tr.tracked) / tr.present;
    if (f >= params_.mostly_tracked) {
      ++r.mostly_tracked;
    } else if (f < params_.mostly_lost) {
      ++r.mostly_lost;
    } else {
      ++r.partially_tracked;
    }
  }
  return r;
}

}  // namespace core
}  // namespace urban_detection
