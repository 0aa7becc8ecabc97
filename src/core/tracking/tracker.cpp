#include "urban_detection/core/tracking/tracker.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "urban_detection/core/tracking/hungarian.h"

namespace urban_detection {
namespace core {

namespace {

constexpr double kPi = 3.14159265358979323846;
// Cost of a forbidden pair in an assignment group: larger than any admissible cost (gate +
// overlap weight, both bounded by validate()), so the solver uses as few as possible.
constexpr double kForbidden = 1e6;

// Angle wrapped to (-pi/2, pi/2]: the difference of two box yaws, which are defined modulo pi
// (a box looks the same turned half way round).
double wrapHalfPi(double a) {
  a = std::fmod(a, kPi);
  if (a > 0.5 * kPi) a -= kPi;
  if (a <= -0.5 * kPi) a += kPi;
  return a;
}

double wrapPi(double a) {
  a = std::fmod(a, 2.0 * kPi);
  if (a > kPi) a -= 2.0 * kPi;
  if (a <= -kPi) a += 2.0 * kPi;
  return a;
}

}  // namespace

std::string validate(const TrackerParams& p) {
  std::string error = checkFieldRanges(p);
  if (error.empty() && p.max_dt_s < p.default_dt_s) {
    std::ostringstream msg;
    msg << "parameter 'max_dt_s' = " << p.max_dt_s
        << " must not be below 'default_dt_s' = " << p.default_dt_s << " s";
    error = msg.str();
  }
  return error;
}

const char* toString(TrackState s) {
  switch (s) {
    case TrackState::kTentative:
      return "tentative";
    case TrackState::kConfirmed:
      return "confirmed";
    default:
      return "lost";
  }
}

Tracker::Tracker(const TrackerParams& params) {
  setParams(params);
}

void Tracker::setParams(const TrackerParams& params) {
  const std::string error = validate(params);
  if (!error.empty()) throw std::invalid_argument("TrackerParams: " + error);
  params_ = params;
}

void Tracker::reset() {
  for (const Track& t : tracks_) reset_died_.push_back(t.id);
  tracks_.clear();
  filters_.clear();
  have_stamp_ = false;
}

const TrackerStats& Tracker::update(const std::vector<DetectedObject>& objects,
                                    const Eigen::Isometry3d& odom_T_sensor, double stamp_s) {
  stats_ = TrackerStats();
  died_.clear();
  died_.swap(reset_died_);  // tracks dropped by reset() since the last update
  stats_.detections = objects.size();

  // Time step. A stamp going back or jumping far is a new stream: start over.
  double dt = 0.0;
  if (have_stamp_ && std::isfinite(stamp_s)) {
    dt = stamp_s - last_stamp_s_;
    if (dt < 0.0 || dt > params_.max_dt_s) {
      reset();
      died_.insert(died_.end(), reset_died_.begin(), reset_died_.end());
      reset_died_.clear();
      stats_.restarted = true;
      dt = 0.0;
    } else if (dt == 0.0) {
      dt = params_.default_dt_s;
    }
  } else if (have_stamp_) {
    dt = params_.default_dt_s;
  }
  if (std::isfinite(stamp_s)) {
    last_stamp_s_ = stamp_s;
    have_stamp_ = true;
  }

  // Detections into the fixed frame. A non-finite pose makes every detection unusable.
  const Eigen::Matrix3d R = odom_T_sensor.linear();
  const Eigen::Vector3d tr = odom_T_sensor.translation();
  const bool pose_ok = R.allFinite() && tr.allFinite();
  const double pose_yaw = pose_ok ? std::atan2(R(1, 0), R(0, 0)) : 0.0;
  measurements_.clear();
  for (std::size_t k = 0; k < objects.size(); ++k) {
    const DetectedObject& o = objects[k];
    if (!pose_ok || !o.obb_center.allFinite() || !o.obb_size.allFinite() ||
        !std::isfinite(o.obb_yaw_rad) || (o.obb_size.array() < 0.0f).any() ||
        o.obb_center.cwiseAbs().maxCoeff() > 1e6f) {
      ++stats_.invalid_detections;
      continue;
    }
    Measurement m;
    m.center = R * o.obb_center.cast<double>() + tr;
    m.size = o.obb_size.cast<double>();
    m.yaw_rad = wrapPi(o.obb_yaw_rad + pose_yaw);
    m.category = o.category;
    m.confidence = std::isfinite(o.class_confidence) ? o.class_confidence : 0.0f;
    m.index = static_cast<int>(k);
    measurements_.push_back(m);
  }

  predict(dt);
  associate();

  // Updates, misses and deaths.
  std::size_t keep = 0;
  for (std::size_t t = 0; t < tracks_.size(); ++t) {
    Track& track = tracks_[t];
    ++track.age;
    track.detection = -1;
    const int m = track_match_[t];
    if (m >= 0) {
      updateTrack(t, measurements_[m]);
      ++stats_.matched;
    } else {
      ++track.misses;
      bool dies = false;
      if (track.state == TrackState::kTentative) {
        dies = static_cast<int>(track.misses) >= params_.tentative_max_misses;
      } else {
        track.state = TrackState::kLost;
        dies = static_cast<int>(track.misses) >= params_.death_misses;
      }
      if (dies) {
        died_.push_back(track.id);
        continue;
      }
    }
    if (keep != t) {
      tracks_[keep] = tracks_[t];
      filters_[keep] = filters_[t];
    }
    ++keep;
  }
  tracks_.resize(keep);
  filters_.resize(keep);
  stats_.died = died_.size();

  for (std::size_t k = 0; k < measurements_.size(); ++k) {
    if (meas_match_[k] < 0) startTrack(measurements_[k]);
  }
  for (const Track& t : tracks_) {
    stats_.confirmed += t.state == TrackState::kConfirmed;
    stats_.tentative += t.state == TrackState::kTentative;
    stats_.lost += t.state == TrackState::kLost;
  }
  return stats_;
}

void Tracker::predict(double dt) {
  if (dt <= 0.0) return;
  Eigen::Matrix4d F = Eigen::Matrix4d::Identity();
  F(0, 2) = F(1, 3) = dt;
  // White-noise acceleration: the position and velocity of each axis share one random
  // acceleration over the step.
  const double q = params_.process_accel_std_mps2 * params_.process_accel_std_mps2;
  const double dt2 = dt * dt, dt3 = dt2 * dt, dt4 = dt3 * dt;
  Eigen::Matrix4d Q = Eigen::Matrix4d::Zero();
  Q(0, 0) = Q(1, 1) = 0.25 * dt4 * q;
  Q(0, 2) = Q(2, 0) = Q(1, 3) = Q(3, 1) = 0.5 * dt3 * q;
  Q(2, 2) = Q(3, 3) = dt2 * q;
  for (std::size_t t = 0; t < tracks_.size(); ++t) {
    Filter& f = filters_[t];
    f.x = F * f.x;
    f.P = F * f.P * F.transpose() + Q;
    Track& track = tracks_[t];
    track.center.x() = f.x(0);
    track.center.y() = f.x(1);
  }
}

void Tracker::associate() {
  const int nt = static_cast<int>(tracks_.size());
  const int nm = static_cast<int>(measurements_.size());
  track_match_.assign(nt, -1);
  meas_match_.assign(nm, -1);
  if (nt == 0 || nm == 0) return;
  // Established tracks (confirmed, lost) choose first; tentative tracks get what is left, so a
  // fresh duplicate never takes the detections of the object's older track.
  associateStage(false);
  associateStage(true);
}

void Tracker::associateStage(bool tentative) {
  const int nt = static_cast<int>(tracks_.size());
  const int nm = static_cast<int>(measurements_.size());
  // Gated pairs and their costs. The gate widens with the predicted centre's uncertainty (a
  // track coasting through missed revolutions, a new track whose velocity is unknown), up to
  // twice gate_distance_m.
  pairs_.clear();
  for (int t = 0; t < nt; ++t) {
    const Track& tr = tracks_[t];
    if ((tr.state == TrackState::kTentative) != tentative || track_match_[t] >= 0) continue;
    const Eigen::Vector2d tc = tr.center.head<2>();
    const Eigen::Matrix2d& P = filters_[t].P.topLeftCorner<2, 2>();
    // Largest eigenvalue of the 2x2 position covariance.
    const double half_trace = 0.5 * (P(0, 0) + P(1, 1));
    const double lambda_max =
        half_trace + std::sqrt(std::max(0.0, 0.25 * (P(0, 0) - P(1, 1)) * (P(0, 0) - P(1, 1)) +
                                                 P(0, 1) * P(1, 0)));
    const double gate = std::min(
        params_.gate_distance_m + params_.gate_sigmas * std::sqrt(std::max(0.0, lambda_max)),
        2.0 * params_.gate_distance_m);
    const double gate2 = gate * gate;
    for (int m = 0; m < nm; ++m) {
      if (meas_match_[m] >= 0) continue;
      const Measurement& me = measurements_[m];
      const double d2 = (me.center.head<2>() - tc).squaredNorm();
      if (d2 > gate2) continue;
      double cost = std::sqrt(d2);
      if (params_.overlap_weight_m > 0.0) {
        const double iou = bevIoU(tc, tr.size.x(), tr.size.y(), tr.yaw_rad, me.center.head<2>(),
                                  me.size.x(), me.size.y(), me.yaw_rad);
        cost += params_.overlap_weight_m * (1.0 - iou);
      }
      pairs_.push_back({t, m, cost});
    }
  }
  if (pairs_.empty()) return;

  // Independent groups: connected components of the gated pairs (tracks 0..nt-1, measurements
  // nt..nt+nm-1), by union-find.
  parent_.resize(nt + nm);
  for (int k = 0; k < nt + nm; ++k) parent_[k] = k;
  auto find = [this](int k) {
    while (parent_[k] != k) {
      parent_[k] = parent_[parent_[k]];
      k = parent_[k];
    }
    return k;
  };
  for (const Pair& p : pairs_) {
    const int a = find(p.track), b = find(nt + p.meas);
    if (a != b) parent_[a] = b;
  }
  // Single pairs (the usual case) are matched directly; larger groups are solved.
  std::vector<int>& group_of_root = assignment_;  // reused: root -> group index
  group_of_root.assign(nt + nm, -1);
  std::size_t groups = 0;
  for (const Pair& p : pairs_) {
    const int root = find(p.track);
    if (group_of_root[root] < 0) {
      group_of_root[root] = static_cast<int>(groups);
      if (group_rows_.size() <= groups) {
        group_rows_.emplace_back();
        group_cols_.emplace_back();
      }
      group_rows_[groups].clear();
      group_cols_[groups].clear();
      ++groups;
    }
  }
  for (int t = 0; t < nt; ++t) {
    const int g = group_of_root[find(t)];
    if (g >= 0) group_rows_[g].push_back(t);
  }
  for (int m = 0; m < nm; ++m) {
    const int g = group_of_root[find(nt + m)];
    if (g >= 0) group_cols_[g].push_back(m);
  }
  std::vector<int>& local_row = local_row_;  // index of a track / detection in its group
  std::vector<int>& local_col = local_col_;
  local_row.assign(nt, -1);
  local_col.assign(nm, -1);
  for (std::size_t g = 0; g < groups; ++g) {
    const std::vector<int>& rows = group_rows_[g];
    const std::vector<int>& cols = group_cols_[g];
    if (rows.size() == 1 && cols.size() == 1) {
      track_match_[rows[0]] = cols[0];
      meas_match_[cols[0]] = rows[0];
      continue;
    }
    for (std::size_t r = 0; r < rows.size(); ++r) local_row[rows[r]] = static_cast<int>(r);
    for (std::size_t c = 0; c < cols.size(); ++c) local_col[cols[c]] = static_cast<int>(c);
  }
  // Cost matrices of the larger groups, filled from the pair list.
  for (std::size_t g = 0; g < groups; ++g) {
    const std::vector<int>& rows = group_rows_[g];
    const std::vector<int>& cols = group_cols_[g];
    if (rows.size() == 1 && cols.size() == 1) continue;
    const int nr = static_cast<int>(rows.size()), nc = static_cast<int>(cols.size());
    cost_.assign(static_cast<std::size_t>(nr) * nc, kForbidden);
    for (const Pair& p : pairs_) {
      if (group_of_root[find(p.track)] != static_cast<int>(g)) continue;
      cost_[static_cast<std::size_t>(local_row[p.track]) * nc + local_col[p.meas]] = p.cost;
    }
    std::vector<int>& row_to_col = row_to_col_;
    solveAssignment(cost_, nr, nc, &row_to_col, &hungarian_scratch_);
    for (int r = 0; r < nr; ++r) {
      const int c = row_to_col[r];
      if (c < 0 || cost_[static_cast<std::size_t>(r) * nc + c] >= kForbidden) continue;
      track_match_[rows[r]] = cols[c];
      meas_match_[cols[c]] = rows[r];
    }
  }
}

void Tracker::updateTrack(std::size_t t, const Measurement& m) {
  Track& track = tracks_[t];
  Filter& f = filters_[t];
  // Kalman update of (x, y, vx, vy) with the measured centre (H = [I 0]).
  const double r = params_.measurement_std_m * params_.measurement_std_m;
  const Eigen::Matrix2d S = f.P.topLeftCorner<2, 2>() + r * Eigen::Matrix2d::Identity();
  const Eigen::Matrix<double, 4, 2> K = f.P.leftCols<2>() * S.inverse();
  const Eigen::Vector2d innovation = m.center.head<2>() - f.x.head<2>();
  f.x += K * innovation;
  Eigen::Matrix4d I_KH = Eigen::Matrix4d::Identity();
  I_KH.leftCols<2>() -= K;
  // Joseph form: stays symmetric and positive definite in floating point.
  f.P = I_KH * f.P * I_KH.transpose() + r * K * K.transpose();

  const double a = params_.smoothing;
  track.center =
      Eigen::Vector3d(f.x(0), f.x(1), track.center.z() + a * (m.center.z() - track.center.z()));
  track.size += a * (m.size - track.size);
  track.yaw_rad = wrapPi(track.yaw_rad + a * wrapHalfPi(m.yaw_rad - track.yaw_rad));
  track.velocity = f.x.tail<2>();
  track.velocity_covariance = f.P.bottomRightCorner<2, 2>();
  track.position_covariance = f.P.topLeftCorner<2, 2>();
  ++track.hits;
  track.misses = 0;
  track.detection = m.index;
  f.class_evidence.add(m.category, m.confidence);
  if (f.class_evidence.count() > 0) {
    track.category = f.class_evidence.category();
    track.class_confidence = f.class_evidence.probability();
  }
  if (track.state == TrackState::kLost ||
      (track.state == TrackState::kTentative &&
       (static_cast<int>(track.hits) >= params_.birth_hits || confidentBirth(track)))) {
    track.state = TrackState::kConfirmed;
  }
  // Heading: along the velocity when moving (the box yaw turned by pi if it points backwards).
  if (track.speed() > params_.moving_speed_mps) {
    const double heading = std::atan2(track.velocity.y(), track.velocity.x());
    if (std::fabs(wrapPi(track.yaw_rad - heading)) > 0.5 * kPi) {
      track.yaw_rad = wrapPi(track.yaw_rad + kPi);
    }
  }
}

bool Tracker::confidentBirth(const Track& t) const {
  return params_.confident_birth_probability > 0.0 &&
         (t.category == ObjectCategory::kVehicle || t.category == ObjectCategory::kPedestrian ||
          t.category == ObjectCategory::kCyclist) &&
         t.class_confidence >= params_.confident_birth_probability;
}

void Tracker::startTrack(const Measurement& m) {
  Track track;
  track.id = next_id_++;
  if (next_id_ == 0) next_id_ = 1;  // after 2^32 - 1 tracks
  track.age = 1;
  track.hits = 1;
  track.center = m.center;
  track.size = m.size;
  track.yaw_rad = m.yaw_rad;
  track.detection = m.index;
  track.state = params_.birth_hits <= 1 ? TrackState::kConfirmed : TrackState::kTentative;
  Filter f;
  f.x << m.center.x(), m.center.y(), 0.0, 0.0;
  const double r = params_.measurement_std_m * params_.measurement_std_m;
  const double v = params_.initial_velocity_std_mps * params_.initial_velocity_std_mps;
  f.P = Eigen::Vector4d(r, r, v, v).asDiagonal();
  f.class_evidence.add(m.category, m.confidence);
  if (f.class_evidence.count() > 0) {
    track.category = f.class_evidence.category();
    track.class_confidence = f.class_evidence.probability();
  }
  if (confidentBirth(track)) track.state = TrackState::kConfirmed;
  track.velocity_covariance = f.P.bottomRightCorner<2, 2>();
  track.position_covariance = f.P.topLeftCorner<2, 2>();
  tracks_.push_back(track);
  filters_.push_back(f);
  ++stats_.born;
}

}  // namespace core
}  // namespace urban_detection
