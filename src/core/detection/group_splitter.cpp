#include "urban_detection/core/detection/group_splitter.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "urban_detection/core/common/param_rules.h"

namespace urban_detection {
namespace core {

namespace {

// Position in `foreground` of the point with `index`, or -1. The detectors copy `index` from
// the foreground in its order and extractForeground() writes it in cloud order, so an object's
// points are found by a binary search, with the position after the previous point tried
// first; a foreground in another order (hand-made clouds) is searched linearly.
std::int32_t positionOf(const LabeledCloud& foreground, std::uint32_t index, std::size_t hint) {
  const auto& pts = foreground.points;
  if (hint < pts.size() && pts[hint].index == index && (hint == 0 || pts[hint - 1].index < index)) {
    return static_cast<std::int32_t>(hint);
  }
  auto it = std::lower_bound(pts.begin(), pts.end(), index,
                             [](const LabeledPoint& p, std::uint32_t i) { return p.index < i; });
  if (it != pts.end() && it->index == index) return static_cast<std::int32_t>(it - pts.begin());
  for (std::size_t k = 0; k < pts.size(); ++k) {
    if (pts[k].index == index) return static_cast<std::int32_t>(k);
  }
  return -1;
}

}  // namespace

std::string validate(const GroupSplitterParams& p) {
  const std::string error = checkFieldRanges(p);
  if (!error.empty() || p.min_length_m <= 0.0) return error;  // 0: no lower bound
  return orderMessage("min_length_m", p.min_length_m, "max_length_m", p.max_length_m, "m");
}

GroupSplitter::GroupSplitter(const GroupSplitterParams& params) : params_(params) {
  const std::string error = validate(params);
  if (!error.empty()) throw std::invalid_argument(error);
}

std::int32_t GroupSplitter::find(std::int32_t a) {
  while (parent_[a] != a) a = parent_[a] = parent_[parent_[a]];
  return a;
}

bool GroupSplitter::split(const LabeledCloud& foreground, const DetectedObject& object) {
  const GroupSplitterParams& p = params_;
  const float length = object.obb_size.x();
  const float height = object.max_pt.z() - object.min_pt.z();
  if (!(length >= p.min_length_m && length <= p.max_length_m && height <= p.max_height_m &&
        height >= p.min_person_height_m) ||
      object.indices.size() < 2 * static_cast<std::size_t>(p.min_piece_points)) {
    return false;
  }
  positions_.clear();
  std::size_t hint = 0;
  for (const std::uint32_t index : object.indices) {
    const std::int32_t pos = positionOf(foreground, index, hint);
    if (pos < 0) return false;  // not from this foreground: leave the object alone
    positions_.push_back(static_cast<std::uint32_t>(pos));
    hint = static_cast<std::size_t>(pos) + 1;
  }
  // The height map over the object's axis-aligned box.
  const float cell = static_cast<float>(p.cell_m), inv = 1.0f / cell;
  const float x0 = object.min_pt.x(), y0 = object.min_pt.y();
  const int nx = static_cast<int>((object.max_pt.x() - x0) * inv) + 1;
  const int ny = static_cast<int>((object.max_pt.y() - y0) * inv) + 1;
  const float empty = -std::numeric_limits<float>::infinity();
  zmax_.assign(static_cast<std::size_t>(nx) * ny, empty);
  auto cellOf = [&](float x, float y) {
    const int ix = std::min(nx - 1, std::max(0, static_cast<int>((x - x0) * inv)));
    const int iy = std::min(ny - 1, std::max(0, static_cast<int>((y - y0) * inv)));
    return iy * nx + ix;
  };
  for (const std::uint32_t pos : positions_) {
    const LabeledPoint& q = foreground.points[pos];
    float& z = zmax_[cellOf(q.x, q.y)];
    z = std::max(z, q.z);
  }
  // Heads: the highest cell within the spacing radius, high enough for a person.
  const float head_min_z = object.min_pt.z() + static_cast<float>(p.min_person_height_m);
  const int reach = static_cast<int>(std::floor(p.min_head_spacing_m * inv + 1e-6));
  const int reach2 = static_cast<int>(std::floor(
      p.min_head_spacing_m * p.min_head_spacing_m * static_cast<double>(inv) * inv + 1e-6));
  heads_.clear();
  for (int iy = 0; iy < ny; ++iy) {
    for (int ix = 0; ix < nx; ++ix) {
      const int c = iy * nx + ix;
      const float z = zmax_[c];
      if (!(z >= head_min_z)) continue;
      bool top = true;
      for (int dy = -reach; dy <= reach && top; ++dy) {
        for (int dx = -reach; dx <= reach && top; ++dx) {
          const int jx = ix + dx, jy = iy + dy;
          if ((dx == 0 && dy == 0) || dx * dx + dy * dy > reach2 || jx < 0 || jx >= nx || jy < 0 ||
              jy >= ny) {
            continue;
          }
          const int o = jy * nx + jx;
          top = zmax_[o] < z || (zmax_[o] == z && o > c);
        }
      }
      if (top) heads_.push_back(c);
    }
  }
  if (heads_.size() < 2) return false;
  // Heads of one person: no dip of min_saddle_drop_m between them.
  const float drop = static_cast<float>(p.min_saddle_drop_m);
  auto dips = [&](int a, int b) {
    const float ax = static_cast<float>(a % nx) + 0.5f, ay = static_cast<float>(a / nx) + 0.5f;
    const float bx = static_cast<float>(b % nx) + 0.5f, by = static_cast<float>(b / nx) + 0.5f;
    const float dist = std::hypot(bx - ax, by - ay);
    const float ux = -(by - ay) / dist, uy = (bx - ax) / dist;  // across the line
    const float floor_z = std::min(zmax_[a], zmax_[b]) - drop;
    const int steps = static_cast<int>(std::ceil(2.0f * dist));
    auto at = [&](float x, float y) {
      const int ix = static_cast<int>(std::floor(x)), iy = static_cast<int>(std::floor(y));
      return ix < 0 || ix >= nx || iy < 0 || iy >= ny ? empty : zmax_[iy * nx + ix];
    };
    // Empty samples are sampling holes (scan rings far apart on a roof), not dips; with no
    // sample at all between the heads they are apart.
    bool seen = false;
    for (int k = 1; k < steps; ++k) {
      const float t = static_cast<float>(k) / static_cast<float>(steps);
      const float x = ax + t * (bx - ax), y = ay + t * (by - ay);
      const float z = std::max({at(x, y), at(x + ux, y + uy), at(x - ux, y - uy)});
      if (z == empty) continue;
      seen = true;
      if (z < floor_z) return true;
    }
    return !seen;
  };
  const std::int32_t nh = static_cast<std::int32_t>(heads_.size());
  parent_.resize(nh);
  for (std::int32_t h = 0; h < nh; ++h) parent_[h] = h;
  for (std::int32_t i = 0; i < nh; ++i) {
    for (std::int32_t j = i + 1; j < nh; ++j) {
      const std::int32_t ri = find(i), rj = find(j);
      if (ri != rj && !dips(heads_[i], heads_[j])) parent_[std::max(ri, rj)] = std::min(ri, rj);
    }
  }
  // alive_[root] marks the people still kept; every point goes to the nearest head of a kept
  // person, then the smallest piece below min_piece_points is dropped and the points reassigned.
  person_.assign(nh, 0);
  std::int32_t alive = 0;
  for (std::int32_t h = 0; h < nh; ++h) {
    person_[h] = find(h) == h ? 1 : 0;
    alive += person_[h];
  }
  const std::size_t np = positions_.size();
  owner_.resize(np);
  counts_.resize(nh);
  while (alive >= 2) {
    std::fill(counts_.begin(), counts_.end(), 0u);
    for (std::size_t i = 0; i < np; ++i) {
      const LabeledPoint& q = foreground.points[positions_[i]];
      const float x = (q.x - x0) * inv, y = (q.y - y0) * inv;
      float best = std::numeric_limits<float>::max();
      std::int32_t best_root = -1;
      for (std::int32_t h = 0; h < nh; ++h) {
        const std::int32_t root = parent_[h];
        if (!person_[root]) continue;
        const float dx = x - (static_cast<float>(heads_[h] % nx) + 0.5f);
        const float dy = y - (static_cast<float>(heads_[h] / nx) + 0.5f);
        const float d2 = dx * dx + dy * dy;
        if (d2 < best) {
          best = d2;
          best_root = root;
        }
      }
      owner_[i] = best_root;
      ++counts_[best_root];
    }
    std::int32_t smallest = -1;
    for (std::int32_t h = 0; h < nh; ++h) {
      if (person_[h] && (smallest < 0 || counts_[h] < counts_[smallest])) smallest = h;
    }
    if (counts_[smallest] >= static_cast<std::uint32_t>(p.min_piece_points)) break;
    person_[smallest] = 0;
    --alive;
  }
  if (alive < 2) return false;
  // The pieces: one per person-sized person (at most max_piece_length_m long), the rest of the
  // object (the people that are not person-sized: a car's or a structure's tops) as one piece;
  // without a person-sized piece, or with a single piece, the object stays whole.
  std::vector<std::int32_t>& piece_of_root = heads_;  // heads are no longer needed
  piece_of_root.assign(nh, -1);
  std::int32_t npeople = 0;
  for (std::size_t i = 0; i < np; ++i) {
    std::int32_t& k = piece_of_root[owner_[i]];
    if (k < 0) k = npeople++;
  }
  piece_positions_.resize(npeople);
  for (auto& v : piece_positions_) v.clear();
  for (std::size_t i = 0; i < np; ++i) {
    piece_positions_[piece_of_root[owner_[i]]].push_back(positions_[i]);
  }
  pieces_.resize(npeople);
  person_sized_.assign(npeople, 0);
  std::int32_t sized = 0;
  for (std::int32_t k = 0; k < npeople; ++k) {
    geometry_.compute(foreground, piece_positions_[k], &pieces_[k]);
    // One person: short and narrow, standing from near the ground to a head.
    const DetectedObject& q = pieces_[k];
    person_sized_[k] = q.obb_size.x() <= p.max_piece_length_m &&
                       q.max_pt.z() - q.min_pt.z() >= p.min_person_height_m;
    sized += person_sized_[k];
  }
  if (sized == 0 || (sized == 1 && npeople == 1)) return false;
  // Piece per point: a person-sized person's own, or the rest (-1); pieces in the order of
  // their first point.
  std::vector<std::int32_t>& order = parent_;  // the union-find is no longer needed
  order.assign(npeople + 1, -1);
  std::int32_t nout = 0;
  for (std::size_t i = 0; i < np; ++i) {
    const std::int32_t k = piece_of_root[owner_[i]];
    std::int32_t& o = order[person_sized_[k] ? k : npeople];
    if (o < 0) o = nout++;
  }
  if (nout < 2) return false;
  out_positions_.resize(nout);
  for (auto& v : out_positions_) v.clear();
  for (std::size_t i = 0; i < np; ++i) {
    const std::int32_t k = piece_of_root[owner_[i]];
    out_positions_[order[person_sized_[k] ? k : npeople]].push_back(positions_[i]);
  }
  for (std::int32_t k = 0; k < nout; ++k) {
    DetectedObject piece;
    geometry_.compute(foreground, out_positions_[k], &piece);
    piece.indices.reserve(out_positions_[k].size());
    for (const std::uint32_t pos : out_positions_[k]) {
      piece.indices.push_back(foreground.points[pos].index);
    }
    out_.push_back(std::move(piece));
  }
  return true;
}

std::size_t GroupSplitter::apply(const LabeledCloud& foreground,
                                 std::vector<DetectedObject>* objects) {
  if (!(params_.min_length_m > 0.0) || objects->empty()) return 0;
  // Most objects are no candidates: only when one is split is the vector rebuilt.
  std::size_t added = 0, k = 0;
  out_.clear();
  for (; k < objects->size(); ++k) {
    const std::size_t before = out_.size();
    if (split(foreground, (*objects)[k])) {
      added += out_.size() - before - 1;
      break;
    }
  }
  if (k == objects->size()) return 0;
  // Objects before k are kept as they are; out_ holds k's pieces.
  first_pieces_.swap(out_);
  out_.clear();
  for (std::size_t j = 0; j < k; ++j) out_.push_back(std::move((*objects)[j]));
  for (auto& piece : first_pieces_) out_.push_back(std::move(piece));
  first_pieces_.clear();
  for (std::size_t j = k + 1; j < objects->size(); ++j) {
    const std::size_t before = out_.size();
    if (split(foreground, (*objects)[j])) {
      added += out_.size() - before - 1;
    } else {
      out_.push_back(std::move((*objects)[j]));
    }
  }
  objects->swap(out_);
  for (std::size_t j = 0; j < objects->size(); ++j) {
    (*objects)[j].id = static_cast<std::uint32_t>(j + 1);
  }
  return added;
}

}  // namespace core
}  // namespace urban_detection
